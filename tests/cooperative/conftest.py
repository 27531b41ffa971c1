"""Shared fixtures: the team filter run through the replay loop, and a small synthetic dataset
written in the MRCLAM folder layout."""

from pathlib import Path

import numpy as np
import pytest

from relloc.core.estimates import Estimates
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Recording
from relloc.estimators.cooperative import CooperativeEstimator, CooperativeSettings
from relloc.pipeline.replay import replay
from relloc.sim.cooperative import CooperativeScenario, simulate


class FilterRun:
    """The team filter over a recording: ``mean (T, n, 3)``, ``cov (T, n, 3, 3)`` at the record
    times, the estimator (its counts) and the estimates record."""

    def __init__(
        self,
        recording: Recording,
        prior: Gaussian,
        settings: CooperativeSettings,
        record_times: np.ndarray,
        start: float = 0.0,
    ) -> None:
        self.estimator = CooperativeEstimator(
            recording.robots, prior, settings, recording.landmarks
        )
        self.estimates: Estimates = replay(
            recording,
            [self.estimator],
            record_times=record_times,
            start=start,
            end=float(record_times[-1]),
        )
        self.t, self.mean, self.cov = self.estimates.stacked("team", recording.robots)

    @property
    def counts(self):
        return self.estimator.counts


@pytest.fixture(scope="session")
def team_run():
    """``team_run(recording, prior, settings, record_times, start=0.0) -> FilterRun``."""
    return FilterRun


HEADER = "# synthetic MRCLAM-layout data written by relloc's tests\n#\n# {}\n#\n"
T0_UNIX = 1248444189.0
ROBOT_BARCODES = (5, 14, 41, 32, 23)
LANDMARK_BARCODES = (63, 81, 7, 70, 45, 27)


def write_mrclam_folder(folder: Path, duration: float = 30.0, seed: int = 0) -> Path:
    """Simulate five robots among six landmarks and write the 17 MRCLAM files.

    Includes one detection with a barcode that is in no table (the loader must count it).
    """
    rng = np.random.default_rng(seed)
    centres = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0], [3.0, 3.0], [1.5, -1.0]])
    square = np.array([[0.6, 0.0], [0.6, 0.6], [0.0, 0.6], [0.0, 0.0]])
    landmarks = np.array(
        [[-1.5, -1.5], [4.5, -1.5], [-1.5, 4.5], [4.5, 4.5], [1.5, 5.0], [1.5, -3.0]]
    )
    scenario = CooperativeScenario(
        start_poses=np.column_stack([centres, np.zeros(5)]),
        waypoints=tuple(square + c for c in centres),
        landmarks_xy=landmarks,
        speed=0.15,
        dt=0.1,
        duration=duration,
        sensing_range=6.0,
        fov=1.2,
        sigma_v=0.02,
        sigma_w=0.05,
        sigma_bearing=0.01,
        sigma_range=0.05,
        max_turn_rate=0.5,
        capture_radius=0.15,
    )
    rec = simulate(scenario, rng).recording
    assert rec.truth is not None and rec.measurements.landmark is not None
    folder.mkdir(parents=True, exist_ok=True)
    subjects = [(i + 1, b) for i, b in enumerate(ROBOT_BARCODES)]
    subjects += [(6 + k, b) for k, b in enumerate(LANDMARK_BARCODES)]
    (folder / "Barcodes.dat").write_text(
        HEADER.format("Subject #    Barcode #") + "".join(f"{s}\t{b}\n" for s, b in subjects)
    )
    (folder / "Landmark_Groundtruth.dat").write_text(
        HEADER.format("Subject #    x [m]    y [m]    x std-dev [m]    y std-dev [m]")
        + "".join(
            f"{6 + k}\t{x:.6f}\t{y:.6f}\t0.0001\t0.0001\n" for k, (x, y) in enumerate(landmarks)
        )
    )
    det = rec.measurements.of_kind("range_bearing")
    for i in range(5):
        gt = "".join(
            f"{T0_UNIX + t:.3f}\t{p[0]:.5f}\t{p[1]:.5f}\t{p[3]:.5f}\n"
            for t, p in zip(rec.truth[i].t, rec.truth[i].pose, strict=True)
        )
        (folder / f"Robot{i + 1}_Groundtruth.dat").write_text(HEADER.format("Time x y theta") + gt)
        o = rec.odometry[i]
        odo = "".join(
            f"{T0_UNIX + t:.3f}\t{u[0]:.4f}\t{u[3]:.4f}\n"
            for t, u in zip(o.t, o.velocity, strict=True)
        )
        (folder / f"Robot{i + 1}_Odometry.dat").write_text(HEADER.format("Time v w") + odo)
        sel = det.observer == i
        lines = []
        for t, tr, lm, (r, b, _) in zip(
            det.t[sel], det.target[sel], det.landmark[sel], det.value[sel], strict=True
        ):
            code = ROBOT_BARCODES[tr] if tr >= 0 else LANDMARK_BARCODES[lm]
            lines.append(f"{T0_UNIX + t:.3f}\t{code}\t{r:.3f}\t{b:.4f}\n")
        if i == 0:
            lines.insert(
                len(lines) // 2, lines[len(lines) // 2].split("\t")[0] + "\t99\t1.0\t0.1\n"
            )
        (folder / f"Robot{i + 1}_Measurement.dat").write_text(
            HEADER.format("Time Subject range bearing") + "".join(lines)
        )
    return folder


@pytest.fixture(scope="session")
def synthetic_mrclam(tmp_path_factory) -> Path:
    return write_mrclam_folder(tmp_path_factory.mktemp("mrclam") / "Synthetic", duration=12.0)
