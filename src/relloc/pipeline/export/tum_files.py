"""Estimates as TUM trajectory files, one estimate/truth pair per (owner, subject), for evo.

A TUM file is one pose per line, ``timestamp tx ty tz qx qy qz qw`` (seconds, metres, a unit
quaternion), ``#`` starting a comment. For every teammate trajectory of a
:class:`~relloc.pipeline.export.poses.PoseSet` this writes

- ``DIR/{owner}/{subject}[__{track}].tum`` — the estimate, every finite record;
- ``DIR/{owner}/{subject}[__{track}].truth.tum`` — the truth of the same quantity in the same
  frame at the same stamps (where known; not written when the recording has no truth),

so ``evo_ape tum TRUTH EST`` (no alignment) gives the RMSE of the position error over the
records with truth — relloc's position RMSE of that series over the same records — and
``-a``/``-as`` that after the best rigid (similarity) alignment. Axes the frame does not
estimate are 0 in both files (e.g. ``z`` of ``world_pose2``), so the error is the one relloc
scores. Pose-less parts (a seed-003 observer's own heading) are not trajectories of a
teammate and are left to the MCAP file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.pipeline.export.poses import (
    PoseSeries,
    PoseSet,
    check_unique,
    ros_token,
    yaw_quaternion,
)
from relloc.pipeline.output import prepare_out_dir, replace_file

Array = NDArray[np.float64]
HEADER = "# timestamp tx ty tz qx qy qz qw"


@dataclass(frozen=True)
class TumPair:
    """The files of one series: ``estimate`` and (if truth is known) ``truth``."""

    label: str
    estimate: Path
    truth: Path | None
    poses: int

    def to_dict(self) -> dict[str, Any]:
        return {
            "estimate": str(self.estimate),
            "truth": None if self.truth is None else str(self.truth),
            "poses": self.poses,
        }


def tum_lines(t: Array, position: Array, yaw: Array) -> str:
    """TUM text of poses: stamps to the nanosecond, values with every digit of a float64."""
    q = yaw_quaternion(yaw)
    rows = np.column_stack([position, q])
    body = "".join(
        f"{tk:.9f} " + " ".join(f"{v:.17g}" for v in row) + "\n"
        for tk, row in zip(t, rows, strict=True)
    )
    return HEADER + "\n" + body


def _stem(p: PoseSeries) -> str:
    stem = ros_token(p.subject)
    if p.track:
        stem += "__" + "_".join(ros_token(part) for part in p.track.split("/") if part)
    return stem


def tum_paths(directory: Path, poses: PoseSet) -> dict[str, Path]:
    """The estimate file of every teammate trajectory in ``poses`` by series label (module
    docstring; the truth file is its ``.truth.tum`` sibling). ConfigError if two series would
    share a file — names that differ only in what :func:`ros_token` replaces, e.g. the tracks
    ``a/b`` and ``a_b`` — so that one never silently overwrites the other. Every name is made
    of ROS tokens, so every path lies inside ``directory`` (``..`` becomes ``__``)."""
    out = {
        p.label: Path(directory) / poses.names[p.owner] / f"{_stem(p)}.tum"
        for p in poses.poses
        if p.trajectory
    }
    check_unique([(path, label) for label, path in out.items()], "TUM file")
    return out


def write_tum(directory: Path, poses: PoseSet) -> tuple[TumPair, ...]:
    """Write the TUM files of every teammate trajectory in ``poses`` (module docstring); the
    paths are checked (:func:`tum_paths`) before any file is written. ``directory`` is made
    even when there is no trajectory, so the folder the summary names exists."""
    directory = Path(directory)
    paths = tum_paths(directory, poses)
    prepare_out_dir(directory, "--tum")
    out = []
    for p in poses.poses:
        if not p.trajectory:
            continue
        path = paths[p.label]
        estimate = _write(path, tum_lines(p.t, p.position, p.yaw))
        truth = None
        known = p.has_truth
        if known.any():
            truth = _write(
                path.with_name(f"{_stem(p)}.truth.tum"),
                tum_lines(p.t[known], p.truth_position[known], p.truth_yaw[known]),
            )
        out.append(TumPair(label=p.label, estimate=estimate, truth=truth, poses=int(p.t.size)))
    return tuple(out)


def _write(path: Path, text: str) -> Path:
    """One TUM file, its folder created (:func:`~relloc.pipeline.output.replace_file`)."""
    return replace_file(path, "--tum", lambda tmp: tmp.write_text(text))
