"""Writing estimates for the ROS ecosystem: an MCAP file (Foxglove, ``ros2 bag play``) and TUM
trajectory files (evo), from one :class:`~relloc.core.estimates.Estimates` and its
:class:`~relloc.core.recording.Recording` (extra ``ros``).

- :mod:`relloc.pipeline.export.poses` — every frame's beliefs as ROS poses with 6×6
  covariances, and the ROS names of robots, topics and frames;
- :mod:`relloc.pipeline.export.mcap_file` — the MCAP file;
- :mod:`relloc.pipeline.export.tum_files` — the TUM files.

:class:`ExportRequest` is what ``--mcap FILE`` / ``--tum DIR`` ask for; :func:`export_estimates`
writes it and returns the ``export`` section of a ``summary.json``: the files, the messages per
topic, what was skipped and why, and per teammate trajectory relloc's own position RMSE over
the written records (no alignment: what ``evo_ape tum TRUTH EST`` reports) and over the
steady-state records (track age ≥ ``settle_s``: the records the team report pools).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.pipeline.evaluation import at_times, position_rmse, series_errors
from relloc.pipeline.export.mcap_file import check_mcap_path, write_mcap
from relloc.pipeline.export.poses import UNKNOWN_VARIANCE, PoseSeries, PoseSet, pose_set
from relloc.pipeline.export.tum_files import tum_paths, write_tum


@dataclass(frozen=True)
class ExportRequest:
    """Where to write: ``mcap`` a file, ``tum`` a folder (either may be ``None``)."""

    mcap: Path | None = None
    tum: Path | None = None

    def __post_init__(self) -> None:
        """Fail before any work on paths that cannot be written (ConfigError naming the flag)."""
        if self.mcap is not None:
            check_mcap_path(Path(self.mcap))
        if self.tum is not None and Path(self.tum).exists() and not Path(self.tum).is_dir():
            raise ConfigError(f"--tum: {self.tum} exists and is not a folder")

    @property
    def wanted(self) -> bool:
        return self.mcap is not None or self.tum is not None


def export_estimates(
    request: ExportRequest,
    estimates: Estimates,
    recording: Recording,
    *,
    run: str,
    settle_s: float = 0.0,
) -> dict[str, Any]:
    """Write what ``request`` asks for; returns the ``export`` summary section (module
    docstring). ``run`` says which run the estimates are (e.g. ``"run 0 of 10, seed 2026"``)."""
    poses = pose_set(estimates, recording)
    out: dict[str, Any] = {
        "run": run,
        "unknown_variance": UNKNOWN_VARIANCE,
        "series": {
            p.label: _figures(p, estimates, recording, settle_s)
            for p in poses.poses
            if p.trajectory
        },
    }
    if poses.skipped:
        out["skipped"] = dict(poses.skipped)
    if request.tum is not None:
        tum_paths(request.tum, poses)  # a clash of file names fails before any file is written
    if request.mcap is not None:
        written = write_mcap(request.mcap, poses, recording, estimator=estimates.estimator)
        out["mcap"] = written.to_dict()
    if request.tum is not None:
        pairs = write_tum(request.tum, poses)
        out["tum"] = {"dir": str(request.tum), "pairs": {p.label: p.to_dict() for p in pairs}}
    return out


def _figures(
    p: PoseSeries, estimates: Estimates, recording: Recording, settle_s: float
) -> dict[str, Any]:
    """relloc's own scores of the records of ``p`` that have truth (module docstring).

    Only the position error enters (:func:`~relloc.pipeline.evaluation.series_errors` and
    :func:`~relloc.pipeline.evaluation.position_rmse`, as every relloc summary scores it), never
    the covariance: a
    belief whose covariance is singular (zero, rank-deficient) or not invertible in floating
    point is still exported and scored rather than failing the export on a NEES it does not
    report. ``steady_position_rmse_m`` is NaN when no record has reached ``settle_s``.
    """
    known = p.has_truth
    out: dict[str, Any] = {
        "topic": p.topic,
        "frame_id": p.frame_id,
        "records": int(p.t.size),
        "records_with_truth": int(known.sum()),
    }
    if not known.any():
        return out
    series = at_times(estimates.series(p.owner, p.subject, p.track), p.t[known])
    error = series_errors(series, recording)
    out["position_rmse_m"] = position_rmse(error, series.frame)
    out["settle_s"] = settle_s
    out["steady_position_rmse_m"] = position_rmse(error[series.age >= settle_s], series.frame)
    return out


__all__ = ["ExportRequest", "PoseSet", "export_estimates", "pose_set"]
