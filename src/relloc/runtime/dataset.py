"""A recorded team (any MRCLAM-layout folder) as a :class:`~relloc.core.recording.Recording`.

Seed 000 §6 replays real robot trajectories: the observed robot's plane is raised (2 m) so it
behaves like a drone, the *recorded* odometry drives the filter and range / azimuth / elevation
are synthesised from the ground truth. :func:`mrclam_team_recording` does the same for a whole
team, so that its robots can replay it:

- every robot of the folder (:func:`relloc.datasets.mrclam.load_mrclam`) becomes a robot of the
  recording — ``observer`` on the sensor plane (z = 0), every other robot on a plane ``height``
  above;
- the dataset is converted once (:func:`relloc.datasets.mrclam.to_recording`); the window
  starts ``start_after_odometry_s`` after the last robot's first odometry record (or at the
  last robot's first ground truth, if later) and lasts ``duration_s`` (shortened to what every
  robot recorded), re-timed to start at 0;
- truth is the Vicon pose on a ``rate_hz`` grid (yaw on the circle, gaps from
  :meth:`~relloc.core.recording.GroundTruth.valid_at`); odometry is each robot's recorded
  ``(v, ω)`` held on that grid, with the white-noise σ fitted from the recording itself
  (:func:`relloc.calibration.odometry.fit_odometry_noise` over everywhere the robot has both
  odometry and ground truth);
- the observer measures every other robot at the sensor's rate with the sensor's noise
  (:func:`relloc.sim.sensors.sense`); epochs where either robot's ground truth is in a gap are
  skipped and counted in :attr:`Recording.source`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from relloc.calibration.odometry import fit_odometry_noise
from relloc.calibration.window import odometry_and_truth
from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.datasets.mrclam import load_mrclam, to_recording
from relloc.errors import DataError
from relloc.sim.scenario import SensorSpec
from relloc.sim.sensors import measurement_times, sense


def mrclam_team_recording(
    folder: Path | str,
    rng: np.random.Generator,
    *,
    observer: int = 1,
    height: float = 2.0,
    start_after_odometry_s: float = 5.0,
    duration_s: float = 60.0,
    rate_hz: float = 100.0,
    sensor: SensorSpec | None = None,
) -> Recording:
    """The recorded team of ``folder`` (see module docstring); robots are ``robotN``."""
    sensor = sensor or SensorSpec()
    ds = load_mrclam(folder)
    ids = ds.robot_ids
    if len(ids) < 2:
        raise DataError(f"{folder}: a team log needs at least 2 robots, the folder has {ids}")
    if observer not in ids:
        raise DataError(f"{folder}: observer robot {observer} not in the dataset (robots {ids})")
    order = (observer, *(i for i in ids if i != observer))
    base = to_recording(ds)  # the one MRCLAM conversion: robots named by their subject ids
    which = [base.index(str(i)) for i in order]
    assert base.truth is not None
    start = max(
        max(float(base.odometry[k].t[0]) for k in which) + start_after_odometry_s,
        max(float(base.truth[k].t[0]) for k in which),
    )
    end = min(
        [start + duration_s]
        + [float(base.truth[k].t[-1]) for k in which]
        + [float(base.odometry[k].t[-1]) for k in which]
    )
    if end - start < 10.0:
        raise DataError(
            f"{folder}: the robots share only {max(end - start, 0.0):.1f} s of odometry and "
            "ground truth after the start; need 10 s"
        )
    n = int(np.floor((end - start) * rate_hz + 1e-9))
    t = np.arange(n + 1) / rate_hz
    truths, odometries, valid = [], [], []
    for rank, (rid, k) in enumerate(zip(order, which, strict=True)):
        pose = base.truth[k].at(start + t)
        pose[:, 2] = 0.0 if rank == 0 else height
        truths.append(GroundTruth(t=t, pose=pose, where=f"robot{rid}"))
        valid.append(base.truth[k].valid_at(start + t))
        robot = ds.robot(rid)
        fit = fit_odometry_noise(
            robot, odometry_and_truth(robot, f"{ds.path}: robot {rid}"), rate_hz=rate_hz
        )
        odometries.append(
            Odometry(
                t=t,
                velocity=base.odometry[k].held_at(start + t),
                sigma=np.array([fit.sigma_v, fit.sigma_lateral, 0.0, fit.sigma_w]),
            )
        )
    epochs = measurement_times(sensor.rate_hz, float(t[-1]))
    steps = np.clip(np.rint(epochs * rate_hz).astype(np.int64), 0, t.size - 1)
    rows_t, rows_j, rows_z, skipped = [], [], [], 0
    for j in range(1, len(order)):
        z, seen = sense(truths[0].pose[steps], truths[j].pose[steps], sensor, rng)
        ok = seen & valid[0][steps] & valid[j][steps]
        skipped += int(np.count_nonzero(seen & ~ok))
        rows_t.append(t[steps][ok])
        rows_j.append(np.full(int(ok.sum()), j, dtype=np.int64))
        rows_z.append(z[ok])
    m_t = np.concatenate(rows_t)
    m_j = np.concatenate(rows_j)
    idx = np.lexsort((m_j, m_t))
    measurements = measurement_rows(
        "range_bearing_elevation",
        t=m_t[idx],
        observer=0,
        target=m_j[idx],
        value=np.concatenate(rows_z)[idx],
        sigma=np.asarray(sensor.sigma),
    )
    return Recording(
        robots=tuple(f"robot{i}" for i in order),
        platforms=("ground",) * len(order),
        truth=tuple(truths),
        odometry=tuple(odometries),
        measurements=measurements,
        source=(
            f"{ds.path}: robots {order} from t={start:.2f} s for {t[-1]:.1f} s; observed planes "
            f"+{height:g} m; {skipped} measurement epochs in ground-truth gaps skipped"
        ),
    )
