"""Parts of the seed-000 MRCLAM replay (:mod:`relloc.experiments.wanasinghe2014_mrclam`) checked
by hand: the measurement epochs of each Table-2 rate, the filters' common prior, the noise
inflation applied to the odometry σ and its summary record, which filters run where, and the
steady-state updates the inflation fit counts and the stretches it is fitted on (on the first
45 s of MRCLAM run 6)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from relloc.calibration.window import CalibrationWindow
from relloc.core.recording import GroundTruth, Odometry
from relloc.datasets.mrclam import load_mrclam, to_recording
from relloc.experiments.wanasinghe2014_mrclam import (
    InflationFit,
    ReplayData,
    ReplaySettings,
    _epochs,
    _inflated,
    _inflated_by,
    calibration_stretches,
    inflation_task,
    prepare_replay,
    replay_filters,
    replay_pcrlb,
    replay_prior,
    replay_task,
)


def test_epochs_start_one_period_after_the_window_start() -> None:
    """A 1 s grid at 100 Hz (101 times): 10 Hz readings at steps 10, 20, …, 100 and one 1 Hz
    reading at step 100 — none at the window start."""
    t = np.linspace(0.0, 1.0, 101)
    np.testing.assert_array_equal(_epochs(t, 10.0), np.arange(10, 101, 10))
    np.testing.assert_array_equal(_epochs(t, 1.0), [100])


def test_the_replay_prior_is_a_uniform_range_and_an_unknown_yaw() -> None:
    """Position σ = init_range max / √3 (6 m → variance 12 m²), yaw σ = π/√3 (variance π²/3)."""
    settings = ReplaySettings(dataset=Path("unused"), init_range=(0.3, 6.0))
    prior = replay_prior(settings, np.array([1.0, 2.0, 0.5, -0.3]))
    np.testing.assert_allclose(prior.mean, [1.0, 2.0, 0.5, -0.3])
    np.testing.assert_allclose(np.diag(prior.cov), [12.0, 12.0, 12.0, math.pi**2 / 3.0])


def _replay_data() -> ReplayData:
    t = np.arange(5) * 0.01
    od = Odometry(t=t[:-1], velocity=np.zeros((4, 4)), sigma=np.array([0.02, 0.01, 0.0, 0.03]))
    truth = GroundTruth(t=t, pose=np.zeros((5, 4)))
    return ReplayData(
        source="hand",
        robots=("1", "3"),
        t=t,
        odometry=(od, od),
        truth=(truth, truth),
        valid=np.ones(5, dtype=bool),
        fits={},
        skipped_epochs={},
        load_report={},
    )


def _fit(k: float) -> InflationFit:
    window = CalibrationWindow(200.0, 360.0, "hand")
    return InflationFit(
        k=k,
        met=True,
        target_percent=5.0,
        grid=(1.0, 1.5, 2.0, 3.0),
        yaw_percent_beyond=(20.0, 9.0, 4.0),
        samples=1234,
        stretches=(window,),
        stretches_in_window=3,
        draws=2,
        seed=99,
    )


def test_the_inflation_multiplies_every_odometry_sigma_by_k() -> None:
    data = _replay_data()
    for od in _inflated_by(data, 2.5).odometry:
        np.testing.assert_allclose(od.sigma, [0.05, 0.025, 0.0, 0.075])
    inflated = _inflated(data, _fit(2.0))
    assert inflated.inflation == _fit(2.0)
    np.testing.assert_allclose(inflated.odometry[1].sigma, [0.04, 0.02, 0.0, 0.06])
    np.testing.assert_allclose(data.odometry[0].sigma, [0.02, 0.01, 0.0, 0.03])  # untouched


def test_the_inflation_record_lists_each_factor_tried_up_to_the_one_kept() -> None:
    assert _fit(2.0).to_dict() == {
        "k": 2.0,
        "met": True,
        "target_percent": 5.0,
        "tried": [
            {"k": 1.0, "yaw_percent_beyond": 20.0},
            {"k": 1.5, "yaw_percent_beyond": 9.0},
            {"k": 2.0, "yaw_percent_beyond": 4.0},
        ],
        "samples_per_factor": 1234,
        "stretches": [{"start_s": 200.0, "end_s": 360.0, "source": "hand"}],
        "stretches_in_window": 3,
        "draws_per_stretch": 2,
        "seed": 99,
    }


def test_the_bias_compensated_plkf_runs_on_the_noisy_calibrated_cases_only() -> None:
    assert replay_filters("case1") == ("PLKF", "TEKF", "yaw bank")
    assert replay_filters("case3") == ("PLKF", "TEKF", "yaw bank")
    assert replay_filters("case2") == ("PLKF", "BC-PLKF", "TEKF", "yaw bank")
    assert replay_filters("case4", "calibrated") == ("PLKF", "BC-PLKF", "TEKF", "yaw bank")
    for kind in ("raw", "truth_velocity"):
        assert replay_filters("case2", kind) == ("PLKF", "yaw bank")


@pytest.fixture(scope="module")
def short_replay(tmp_path_factory: pytest.TempPathFactory, mrclam_run6_cut):
    dataset = mrclam_run6_cut(tmp_path_factory.mktemp("mrclam") / "MRCLAM_short")
    settings = ReplaySettings(
        dataset=dataset, duration_s=10.0, min_duration_s=8.0, start_after_odometry_s=1.0
    )
    return settings, prepare_replay(settings)


def test_the_inflation_fit_counts_the_plkf_updates_of_the_steady_state(short_replay) -> None:
    """A 10 s window: the 10 Hz cases update at ages 0.1 … 10 s, the 1 Hz cases at 1 … 10 s.
    From age 2.95 s: 71 + 71 + 8 + 8 = 158 updates (skipped epochs in truth gaps aside), not
    all 100 + 100 + 10 + 10 = 220. Seed root 46023 is used nowhere else in the tests; the
    count does not depend on it."""
    settings, data = short_replay
    skipped = sum(data.skipped_epochs.values())
    seed = np.random.SeedSequence(46023)
    beyond, total = inflation_task(seed, 0, [data], settings, 2.95)
    assert total == 158 - skipped
    # beyond: the yaw NEES (e_φ/σ_φ)² above χ²(1, 0.95) = 3.841 (tables), same draw
    tracks = replay_task(seed, 0, data, settings, ("PLKF",))
    z = [
        (ev.error[ev.age >= 2.95, 3] / ev.sigma[ev.age >= 2.95, 3]) ** 2
        for ev in (tracks[c]["PLKF"].evaluation for c in tracks)
    ]
    assert beyond == int(np.count_nonzero(np.concatenate(z) > 3.8415)) > 0


def test_the_replay_bound_has_no_epoch_past_a_steady_state_longer_than_the_window(
    short_replay,
) -> None:
    """The steady state is counted from the window's start (not from the recording's clock):
    past 10.5 s of a 10 s window there is no epoch, so every bound is NaN."""
    settings, data = short_replay
    assert data.t[0] > 1.0  # the window starts well after the recording's t = 0
    bound = replay_pcrlb(data, settings, steady_state_s=10.5)
    assert set(bound) == {"case1", "case2", "case3", "case4"}
    assert all(math.isnan(v) for case in bound.values() for v in case.values())


def test_calibration_stretches_start_where_the_pair_has_data_and_keep_a_minimal_last_one(
    short_replay,
) -> None:
    """Stretches of 10 s (the last kept when ≥ 8 s) of the part of the window where both robots
    have odometry: a window from t = 0 starts at the later first odometry record (12.x s) and
    holds two 10 s stretches and the 8.x s left; a window of exactly 8 s is one stretch."""
    settings, _ = short_replay
    ds = load_mrclam(settings.dataset)
    recording = to_recording(ds)
    first = max(ds.robot(r).odometry.t[0] for r in (1, 3))
    assert 12.0 < first < 13.0  # run 6's robots stand still for their first 12.x s
    stretches = calibration_stretches(settings, recording, CalibrationWindow(0.0, 41.0, "w"))
    assert len(stretches) == 3 and stretches[0].start_s == pytest.approx(first)
    assert all(w.duration_s == pytest.approx(10.0) for w in stretches[:2])
    assert stretches[2].end_s == 41.0 and 8.0 <= stretches[2].duration_s < 10.0
    (exact,) = calibration_stretches(settings, recording, CalibrationWindow(30.0, 38.0, "w"))
    assert (exact.start_s, exact.end_s) == (30.0, 38.0)


def test_the_replay_bound_is_the_rms_over_the_steady_state_epochs(short_replay) -> None:
    """1 Hz case 3 of a 10 s window: past 9.5 s only the epoch at 10 s (bound b₁₀); the same
    window cut after 9 s, past 8.5 s, only the epoch at 9 s (b₉: the bound at an epoch does
    not depend on later data); past 8.5 s in the whole window the root of the mean square,
    √((b₉² + b₁₀²)/2), not the mean of b₉ and b₁₀."""
    settings, data = short_replay
    b10 = replay_pcrlb(data, settings, 9.5)["case3"]
    cut = dataclasses.replace(data, t=data.t[:901], valid=data.valid[:901])
    b9 = replay_pcrlb(cut, settings, 8.5)["case3"]
    both = replay_pcrlb(data, settings, 8.5)["case3"]
    for state in ("x", "y", "z", "phi"):
        assert b9[state] != pytest.approx(b10[state], rel=1e-3), state
        rms = math.sqrt((b9[state] ** 2 + b10[state] ** 2) / 2.0)
        assert both[state] == pytest.approx(rms, rel=1e-9), state
