"""``relloc mrclam cut SRC DST [--start S] [--end E] [--robots 1,3,5]``: a part of an MRCLAM
folder as a run of its own (:mod:`relloc.datasets.mrclam_cut`), to run any MRCLAM experiment
(``relloc reproduce ... --dataset DST``) on other calibration and scoring windows, or with
fewer robots. Prints what became of every robot file's rows."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from relloc.cli.flags import integer_list


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "mrclam",
        help="write a part of an MRCLAM run (a time span, some robots) as a run of its own",
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
    width = max(len(name) for name in report.files)
    print(f"{'file':<{width}}  {'kept':>7}  {'outside':>7}  {'unreadable':>10}")
    for name, f in report.files.items():
        print(f"{name:<{width}}  {f.kept:>7}  {f.outside:>7}  {f.unreadable:>10}")
    return 0
