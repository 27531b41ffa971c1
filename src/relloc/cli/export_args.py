"""``--mcap FILE`` and ``--tum DIR``: the options every estimating command shares to write its
estimates for ROS tools (Foxglove, ``ros2 bag play``) and evo (:mod:`relloc.pipeline.export`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from relloc.cli.flags import nonempty_path

if TYPE_CHECKING:
    from relloc.pipeline.export import ExportRequest


def add_export_arguments(p: argparse.ArgumentParser, which: str = "the estimates") -> None:
    """Add ``--mcap`` and ``--tum`` to ``p``; ``which`` says what is written (help text)."""
    g = p.add_argument_group("ROS / evo output (extra 'ros')")
    g.add_argument(
        "--mcap",
        type=nonempty_path,
        default=None,
        metavar="FILE",
        help=f"write {which} as a ROS 2 MCAP file (Foxglove, ros2 bag play)",
    )
    g.add_argument(
        "--tum",
        type=nonempty_path,
        default=None,
        metavar="DIR",
        help=f"write {which} as TUM trajectory files per robot pair (evo_ape tum TRUTH EST)",
    )


def export_request(args: argparse.Namespace) -> ExportRequest | None:
    """What ``--mcap``/``--tum`` ask for, or ``None`` when neither was given."""
    from relloc.pipeline.export import ExportRequest

    request = ExportRequest(mcap=args.mcap, tum=args.tum)
    return request if request.wanted else None


def print_export(section: dict[str, Any] | None) -> None:
    """One line per file written (for commands that print)."""
    if not section:
        return
    if "mcap" in section:
        m = section["mcap"]
        print(
            f"wrote {m['path']} ({m['messages']} messages on {len(m['topics'])} topics, "
            f"{m['bytes'] / 1024:.0f} KiB, {m['seconds']:.2f} s; {section['run']})"
        )
    if "tum" in section:
        print(f"wrote {len(section['tum']['pairs'])} TUM pairs under {section['tum']['dir']}")
    for reason, n in section.get("skipped", {}).items():
        print(f"not exported: {n} records ({reason})")
