"""``relloc mrclam cut SRC DST [--start S] [--end E] [--robots 1,3,5]``: a part of an MRCLAM
folder as a run of its own (:mod:`relloc.datasets.mrclam_cut`), to run any MRCLAM experiment
(``relloc reproduce ... --dataset DST``) on other calibration and scoring windows, or with
fewer robots. Prints what became of every robot file's rows.

``relloc mrclam move SRC DST [--rotate RAD] [--shift=X,Y] [--clock-shift S] [--barcodes
OLD:NEW,...]``: the same run as if recorded in another world frame, at another time and with
other barcodes (:mod:`relloc.datasets.mrclam_move`), to check that an experiment depends on none
of them. Prints what became of every file's rows. A bad value exits 2 naming its flag, and
nothing is written."""

from __future__ import annotations

import argparse
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from relloc.cli.flags import barcode_map, flag_errors, integer_list, number_pair

#: :func:`relloc.datasets.mrclam_move.move_mrclam`'s parameters → the flags of ``mrclam move``.
MOVE_FLAGS = {
    "rotation_rad": "--rotate",
    "shift_m": "--shift",
    "clock_s": "--clock-shift",
    "barcodes": "--barcodes",
}


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "mrclam",
        help="write a part of an MRCLAM run, or the run in another frame, clock and barcodes",
        description="Tools for folders in MRCLAM layout.",
    )
    sub = p.add_subparsers(dest="mrclam_command", metavar="ACTION", required=True)
    q = sub.add_parser(
        "cut",
        help="copy the rows of a time span and of some robots into a new folder",
        description="Times are seconds since the run's earliest robot time stamp.",
    )
    q.add_argument("source", type=Path, help="a folder in MRCLAM layout")
    q.add_argument("destination", type=Path, help="the new folder (must not exist)")
    q.add_argument("--start", type=float, default=0.0, help="first second kept (default 0)")
    q.add_argument("--end", type=float, default=math.inf, help="end of the span (default: all)")
    q.add_argument("--robots", default=None, help="robots kept, e.g. 1,3,5 (default: all)")
    q.set_defaults(func=run)
    m = sub.add_parser(
        "move",
        help="write a run as if recorded in another world frame, at another time, with other "
        "barcodes",
        description="Every ground-truth position p becomes R(RAD) p + (X, Y), every heading "
        "θ + RAD (wrapped), every time stamp t + S and every barcode OLD its NEW, in "
        "Barcodes.dat and in the measurements; ranges, bearings and odometry are body-frame "
        "readings and stay as they are. Give a negative value with '=': --shift=-1.5,2, "
        "--rotate=-1e-3.",
    )
    m.add_argument("source", type=Path, help="a folder in MRCLAM layout")
    m.add_argument("destination", type=Path, help="the new folder (must not exist)")
    m.add_argument(
        "--rotate", type=float, default=0.0, metavar="RAD", help="turn of the frame (default 0)"
    )
    m.add_argument("--shift", default=None, metavar="X,Y", help="shift in m (default 0,0)")
    m.add_argument(
        "--clock-shift", type=float, default=0.0, metavar="S", help="s added to every time stamp"
    )
    m.add_argument(
        "--barcodes", default=None, metavar="OLD:NEW,...", help="new barcodes, e.g. 5:11,14:12"
    )
    m.set_defaults(func=run_move)


def run(args: argparse.Namespace) -> int:
    from relloc.datasets.mrclam_cut import cut_mrclam

    report = cut_mrclam(
        args.source,
        args.destination,
        start_s=args.start,
        end_s=args.end,
        robots=integer_list(args.robots, "--robots"),
    )
    print(
        f"wrote {report.destination}: [{report.start_s:g}, {report.end_s:g}) s of "
        f"{report.source} (t0 {report.t0_unix:.3f} Unix s), robots {list(report.robots)}"
    )
    _print_files(report.files, ("kept", "outside", "unreadable"))
    return 0


def run_move(args: argparse.Namespace) -> int:
    from relloc.datasets.mrclam_move import move_mrclam

    shift = number_pair(args.shift, "--shift") or (0.0, 0.0)
    barcodes = barcode_map(args.barcodes, "--barcodes")
    with flag_errors(MOVE_FLAGS):
        report = move_mrclam(
            args.source,
            args.destination,
            rotation_rad=args.rotate,
            shift_m=shift,
            clock_s=args.clock_shift,
            barcodes=barcodes,
        )
    codes = ", ".join(f"{old}→{new}" for old, new in sorted(report.barcodes.items())) or "kept"
    print(
        f"wrote {report.destination}: {report.source} turned by {report.rotation_rad} rad, "
        f"shifted by ({report.shift_m[0]}, {report.shift_m[1]}) m, clock "
        f"{report.clock_s:+} s (t0 {report.t0_unix:.3f} → {report.t0_unix + report.clock_s:.3f}"
        f" Unix s), barcodes {codes}"
    )
    _print_files(report.files, ("moved", "unreadable"))
    return 0


def _print_files(files: Mapping[str, Any], counts: tuple[str, ...]) -> None:
    """One line per file written, with its row ``counts`` (attributes of its record)."""
    width = max(len(name) for name in files)
    widths = [max(7, len(c)) for c in counts]
    print(
        f"{'file':<{width}}" + "".join(f"  {c:>{w}}" for c, w in zip(counts, widths, strict=True))
    )
    for name, f in files.items():
        cells = "".join(f"  {getattr(f, c):>{w}}" for c, w in zip(counts, widths, strict=True))
        print(f"{name:<{width}}{cells}")
