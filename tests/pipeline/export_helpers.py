"""A hand-made recording and estimates in every frame, and readers of the written files."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements

T = np.round(np.arange(1.0, 6.0, 0.25), 6)  # record times (s)


def recording() -> Recording:
    """Three robots (the third named ``3`` to exercise ROS name tokens) with curved paths."""
    tt = np.linspace(0.0, 10.0, 101)
    truth = tuple(
        GroundTruth(
            t=tt,
            pose=np.column_stack(
                [
                    1.0 + k + np.cos(0.3 * tt + k),
                    2.0 - k + np.sin(0.2 * tt),
                    0.5 * k + 0.05 * tt,
                    np.mod(0.4 * tt + k + math.pi, 2 * math.pi) - math.pi,
                ]
            ),
        )
        for k in range(3)
    )
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    return Recording(
        robots=("leader", "follower", "3"),
        platforms=("ground", "ground", "aerial"),
        odometry=(still, still, still),
        measurements=empty_measurements(),
        truth=truth,
        source="hand-made",
        meta={"common_frame_yaw": 0.3},
    )


def standing_pair(
    truth_t: tuple[float, float] | None, a_pose: list[float], b_pose: list[float]
) -> Recording:
    """Robots ``a`` and ``b`` standing at ``a_pose`` and ``b_pose`` (x, y, z, yaw), with truth
    from ``truth_t[0]`` to ``truth_t[1]`` only (none when ``truth_t`` is None) and no
    odometry."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    truth = None
    if truth_t is not None:
        tt = np.array(truth_t)
        truth = tuple(GroundTruth(t=tt, pose=np.array([pose] * 2)) for pose in (a_pose, b_pose))
    return Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        odometry=(still, still),
        measurements=empty_measurements(),
        truth=truth,
        source="hand-made",
        meta={},
    )


def _spd(rng: np.random.Generator, k: int, d: int) -> np.ndarray:
    a = rng.normal(size=(k, d, d))
    return a @ np.swapaxes(a, 1, 2) * 0.01 + 1e-3 * np.eye(d)


def _series(
    rec: Recording, rng: np.random.Generator, owner: str, subject: str, frame: str, track: str = ""
) -> BeliefSeries:
    from relloc.pipeline.frames import frame as frame_of

    f = frame_of(frame)
    truth = f.truth(rec, owner, subject, T)
    return BeliefSeries(
        owner=owner,
        subject=subject,
        track=track,
        frame=frame,
        t=T,
        mean=truth + rng.normal(scale=0.1, size=truth.shape),
        cov=_spd(rng, T.size, f.dim),
        age=T - T[0],
    )


def estimates(rng: np.random.Generator) -> Estimates:
    """A belief in every frame, one with a track name, one in a frame with no pose map."""
    rec = recording()
    rel = _series(rec, rng, "leader", "3", "relative_pose4")
    odd = BeliefSeries(
        owner="leader",
        subject="follower",
        track="",
        frame="range_bias",
        t=T,
        mean=np.zeros((T.size, 1)),
        cov=np.ones((T.size, 1, 1)),
        age=T,
    )
    beliefs = [
        rel,
        odd,
        _series(rec, rng, "3", "leader", "relative_pose4", track="bank/k2"),
        _series(rec, rng, "team", "follower", "world_pose2"),
        _series(rec, rng, "follower", "leader", "airground_follower"),
    ]
    return Estimates(estimator="hand", beliefs=tuple(sorted(beliefs, key=lambda s: s.key)))


def yaw_of(q) -> float:  # type: ignore[no-untyped-def]
    """Yaw of a ROS quaternion message (roll and pitch must be 0)."""
    assert abs(q.x) < 1e-15 and abs(q.y) < 1e-15
    return 2.0 * math.atan2(q.z, q.w)


def evo_ape(truth: Path, estimate: Path, home: Path, *args: str) -> dict[str, float]:
    """Run the real ``evo_ape tum TRUTH EST`` (the one next to this Python); its statistics."""
    exe = Path(sys.executable).with_name("evo_ape")
    results = home / f"{estimate.stem}_ape.zip"
    env = {**os.environ, "HOME": str(home), "MPLBACKEND": "Agg"}
    subprocess.run(
        [str(exe), "tum", str(truth), str(estimate), *args, "--save_results", str(results)],
        check=True,
        capture_output=True,
        env=env,
        timeout=120,
    )
    import json

    with zipfile.ZipFile(results) as z:
        return json.loads(z.read("stats.json"))


def have_evo() -> bool:
    return Path(sys.executable).with_name("evo_ape").exists()
