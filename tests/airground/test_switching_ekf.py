"""Switching EKF (seed 003 Eq. 4, Algorithm 1): mode rule, sw = 3 drift and recovery, gating."""

import math

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian
from relloc.errors import DataError
from relloc.estimators.switching_ekf import (
    PairSighting,
    SwitchingEkf,
    SwitchingEkfSettings,
    TickInputs,
    select_mode,
)
from relloc.models.airground import Mode
from relloc.models.unicycle import unicycle_step

SETTINGS = SwitchingEkfSettings(
    sigma_v=0.02, sigma_w=0.04, range_sigma=0.05, bearing_sigma=0.02, heading_sigma=0.02
)


def test_select_mode_follows_the_broadcast_set():
    assert select_mode(2, (1, 2)) is Mode.PAIR_SEEN
    assert select_mode(3, (1, 2)) is Mode.OTHER_PAIR_SEEN
    assert select_mode(3, ()) is Mode.NONE_SEEN


def _truth_x(leader, follower):
    return np.array([*(leader[:2] - follower[:2]), follower[2], leader[2]])


def _run_pair(detect, n_steps, seed, settings=SETTINGS, outlier_at=None, u=None):
    """One leader–follower pair; ``detect(k)`` says if the drone sees the pair."""
    rng = np.random.default_rng(seed)
    leader, follower = np.array([0.0, 0.0, 0.0]), np.array([-0.6, -0.6, 0.2])
    x0 = _truth_x(leader, follower)
    f = SwitchingEkf(
        1,
        Gaussian(x0 + np.array([0.1, -0.1, 0.05, -0.05]), np.diag([0.04, 0.04, 0.01, 0.01])),
        settings,
    )
    errors, modes, pos_var = [], [], []
    dt = 0.05
    u = np.array([0.12, -0.15, 0.1, 0.1]) if u is None else u
    for k in range(n_steps):
        act = u + rng.normal(0, [0.01, 0.02, 0.01, 0.02])
        follower = unicycle_step(follower, act[:2], dt)
        leader = unicycle_step(leader, act[2:], dt)
        x = _truth_x(leader, follower)
        rng_meas = float(np.hypot(*x[:2]) + rng.normal(0, 0.05))
        if outlier_at is not None and k == outlier_at:
            rng_meas += 3.0
        seen = detect(k)
        sightings = ()
        if seen:
            sightings = (
                PairSighting(
                    follower=1,
                    bearing=math.atan2(x[1], x[0]) + rng.normal(0, 0.02),
                    heading_follower=x[2] + rng.normal(0, 0.02),
                    heading_leader=x[3] + rng.normal(0, 0.02),
                ),
            )
        modes.append(
            f.tick(
                TickInputs(
                    u=u, detected=(1,) if seen else (), range_0i=rng_meas, sightings=sightings
                ),
                dt,
                (k + 1) * dt,
            )
        )
        errors.append(np.hypot(*(f.belief.mean[:2] - x[:2])))
        pos_var.append(np.trace(f.belief.cov[:2, :2]))
    f.pos_var = np.array(pos_var)
    return np.array(errors), modes, f


def test_modes_follow_detections():
    _, modes, f = _run_pair(lambda k: 100 <= k < 200, 300, 0)
    assert all(m is Mode.NONE_SEEN for m in modes[:100])
    assert all(m is Mode.PAIR_SEEN for m in modes[100:200])
    assert all(m is Mode.NONE_SEEN for m in modes[200:])
    assert f.counters.mode_ticks == {1: 100, 2: 0, 3: 200}
    assert f.counters.accepted["camera"] + f.counters.rejected["camera"] == 100


def test_range_only_error_grows_then_recovers_at_next_detection():
    # Parallel motion (r constant): range alone cannot fix the bearing. Detected for 4 s,
    # range-only (sw = 3) for 40 s, then detected again.
    detect = lambda k: k < 80 or k >= 880  # noqa: E731
    parallel = np.array([0.1, 0.0, 0.1, 0.0])
    before, late, after = [], [], []
    for seed in range(4):
        err, _, f = _run_pair(detect, 960, seed, u=parallel)
        before.append(err[60:80].mean())
        late.append(err[860:880].mean())
        after.append(err[940:960].mean())
        # the filter knows: its position variance grows without bearings, drops at detection
        assert f.pos_var[879] > 5 * f.pos_var[79]
        assert f.pos_var[959] < 0.2 * f.pos_var[879]
    assert np.mean(late) > 3 * np.mean(before)
    assert np.mean(after) < 0.3 * np.mean(late)
    assert max(after) < 0.05


def test_gross_range_outlier_is_gated_and_counted():
    err, _, f = _run_pair(lambda k: True, 200, 1, outlier_at=150)
    assert f.counters.rejected["range"] >= 1
    assert err[150:].max() < 0.1


def test_bad_input_is_a_clear_error():
    f = SwitchingEkf(1, Gaussian(np.array([1.0, 0, 0, 0]), np.eye(4)), SETTINGS)
    with pytest.raises(DataError, match="R_1"):
        f.tick(TickInputs(u=np.array([np.nan, 0, 0, 0])), 0.05, 0.05)
