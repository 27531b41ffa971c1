"""Seed 001's agents as processes under faults (``relloc team up sharma2013``): a restarted agent
rejoins the team's estimate through ``sync``, and late odometry is re-filtered from the
checkpoints like late readings. Real robot processes over loopback Zenoh, a few simulated
seconds each; the fault seeds are the command's default (0)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from relloc.cli import main
from relloc.core.gaussian import Gaussian
from relloc.experiments.sharma2013_team import AGREEMENT_TOLERANCE
from relloc.experiments.team_sources import sharma_estimator, sharma_sim
from relloc.runtime.messages import SCHEMA_VERSION, MessageRejected, decode, encode

REJOIN_TOLERANCE = 1e-6
"""Largest |difference| of a restarted agent's belief entry from an agent that stayed up: after
the handoff both filter the same events; what differs is the round-off of converting the handed
covariance to information form once (about 1e-12 relative) as it carries through the EIF."""


def _summary(out):
    return json.loads((out / "summary.json").read_text())


@pytest.mark.slow
def test_a_restarted_agent_rejoins_the_team_estimate(tmp_path):
    out = tmp_path / "out"
    argv = ["team", "up", "sharma2013", "--out", str(out), "--duration", "6", "--quiet"]
    assert main([*argv, "--kill", "3@2", "--restart", "3@3"]) == 0
    run = _summary(out)["per_run"][0]
    (rejoin,) = run["rejoined"]
    assert rejoin["sync"]["resumed"] == 1 and rejoin["sync"].get("timeout", 0) == 0, rejoin
    assert rejoin["first_record_s"] is not None and rejoin["first_record_s"] < 2.0
    diffs = rejoin["max_abs_diff_from_agents"]
    assert set(diffs) == {"1", "2", "4", "5"}
    assert max(diffs.values()) <= REJOIN_TOLERANCE, diffs
    # it has records after the restart (the rejoined life), like everyone else
    agent3 = run["agents"]["3"]
    assert agent3["records"] > 0.5 * run["agents"]["1"]["records"]
    (phases,) = run["fault_phases"]
    assert set(phases["agents"]) == {"1", "2", "3", "4", "5"}
    assert phases["agents"]["3"]["pos_rmse_after_m"] is not None


@pytest.mark.slow
def test_late_odometry_is_refiltered_to_the_in_process_estimate(tmp_path):
    """Delay and jitter, nothing lost: every message arrives within the checkpoint span, so
    every late reading and every late odometry sample is fused at its own time stamp."""
    out = tmp_path / "out"
    argv = ["team", "up", "sharma2013", "--out", str(out), "--duration", "5", "--quiet"]
    assert main([*argv, "--delay", "30", "--jitter", "150"]) == 0
    summary = _summary(out)
    agents = summary["per_run"][0]["agents"]
    assert sum(a["odometry_late"] for a in agents.values()) > 0  # the case is exercised
    for robot, a in agents.items():
        assert a["odometry_refiltered"] == a["odometry_late"], robot
        assert a["odometry_late_lost"] == 0 and a["readings_late_lost"] == 0, robot
        assert max(a["max_abs_mean_diff"], a["max_abs_cov_diff"]) <= AGREEMENT_TOLERANCE, robot
        assert a["records_missing"] == 0, robot


def test_the_team_filter_hands_off_its_belief_and_resumes_from_it():
    """``team_belief`` leaves the filter untouched; a filter resumed from it continues as the
    original does (same events, same readings)."""
    scenario, sim = sharma_sim(3, 0, 2.0)
    rec = sim.recording
    from relloc.pipeline.replay import replay

    times = np.round(np.arange(0, 21) * 0.1, 12)
    a = sharma_estimator(sim, scenario, "two_landmarks")
    replay(rec, [a], record_times=times[:11], start=0.0, end=1.0)
    t, belief = a.team_belief()
    again_t, again = a.team_belief()
    assert t == again_t and np.array_equal(belief.cov, again.cov)  # nothing moved
    assert belief.dim == 3 * rec.n_robots and t <= 1.0
    b = a.resumed(t, belief)
    assert b.team_belief()[0] == t
    np.testing.assert_allclose(b.team_belief()[1].cov, belief.cov, rtol=0, atol=1e-12)


def test_sync_messages_are_shape_checked():
    roster = ("1", "2")
    ok = {"target": "2", "stamp": 1.0, "mean": np.zeros(6), "cov": np.eye(6)}
    assert decode(encode("sync", "1", 0, 1.0, ok), roster=roster).body["target"] == "2"
    request = {"target": "2", "stamp": 1.0, "mean": np.zeros(0), "cov": np.zeros((0, 0))}
    assert decode(encode("sync", "1", 0, 1.0, request), roster=roster).body["mean"].size == 0
    bad = [
        ({**ok, "cov": np.eye(5)}, "shape"),
        ({**ok, "target": "nobody"}, "unknown_target"),
        ({**ok, "cov": np.eye(6) + np.triu(np.ones((6, 6)), 1)}, "bad_covariance"),
    ]
    import msgpack

    for body, reason in bad:
        payload = {
            "v": SCHEMA_VERSION,
            "type": "sync",
            "sender": "1",
            "seq": 0,
            "t": 1.0,
            "wall_ns": 0,
        }
        payload |= {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in body.items()}
        with pytest.raises(MessageRejected) as exc:
            decode(msgpack.packb(payload), roster=roster)
        assert exc.value.reason == reason
    assert Gaussian(ok["mean"], ok["cov"]).dim == 6


def test_a_reply_is_taken_only_from_the_teammate_asked_with_the_team_dimensions():
    from collections import Counter

    from relloc.runtime.handoff import RETRY_TICKS, WAIT_TICKS, Handoff

    counters: Counter[str] = Counter()
    h = Handoff("3", ("1", "2", "3"), counters)
    assert h.request(["1", "2"]) is None  # not waiting: nothing to ask
    h.begin(after=5.0)
    first = h.request(["1", "2"])
    assert first is not None and first["target"] == "1" and first["stamp"] == 5.0
    for _ in range(RETRY_TICKS - 1):
        assert h.request(["1", "2"]) is None
    second = h.request(["1", "2"])
    assert second is not None and second["target"] == "2"  # the next teammate
    good = {"target": "3", "stamp": 5.2, "mean": np.zeros(9), "cov": np.eye(9)}
    assert h.accept("1", good, 5.2, 0.1) is None  # not the one asked now
    assert h.accept("2", {**good, "mean": np.zeros(6), "cov": np.eye(6)}, 5.2, 0.1) is None
    assert h.accept("2", {**good, "stamp": 4.0}, 5.2, 0.1) is None  # before the time asked
    assert h.accept("2", {**good, "stamp": 9.0}, 5.2, 0.1) is None  # ahead of the clock
    singular = np.diag([1.0] * 8 + [0.0])
    assert h.accept("2", {**good, "cov": singular}, 5.2, 0.1) is None
    # finite but absurd: a team belief of 1e300 m, or of a variance whose inverse is 0
    assert h.accept("2", {**good, "mean": np.full(9, 1e300)}, 5.2, 0.1) is None
    assert h.accept("2", {**good, "cov": 1e300 * np.eye(9)}, 5.2, 0.1) is None
    assert counters["rejected.sync_unasked"] == 1 and counters["rejected.shape"] == 1
    assert counters["rejected.sync_stamp"] == 2 and counters["rejected.bad_covariance"] == 2
    assert counters["rejected.out_of_range"] == 1
    stamp, belief = h.accept("2", good, 5.2, 0.1)
    assert stamp == 5.2 and belief.dim == 9
    h.resumed()
    assert not h.waiting and counters["sync.resumed"] == 1
    # a node that never hears back gives up and filters from its prior
    late = Handoff("3", ("1", "2", "3"), counters)
    late.begin(after=1.0)
    for _ in range(WAIT_TICKS + 1):
        late.request(["1"])
    assert not late.waiting and counters["sync.timeout"] == 1


def test_a_lost_robot_gets_the_variance_of_a_robot_driving_at_the_platform_speed():
    """Two unicycles; robot B's odometry stops at 1 s. With ``lost_speed`` V its position
    variance, ``a`` seconds after its command expired, exceeds the still model's by ``(V a)²``
    per axis and its heading's by ``min((Ω a)², π²/3)``; robot A is untouched; with V = 0
    nothing changes at all."""
    from dataclasses import replace

    from relloc.core.contract import HeldOdometry
    from relloc.estimators.cooperative import (
        CooperativeEstimator,
        CooperativeSettings,
        OdometryModel,
        SensorModel,
    )

    still_model = OdometryModel(q_v0=1e-3, q_w0=1e-3, max_hold_s=0.5)
    prior = Gaussian(np.array([0.0, 0, 0, 5, 0, 0]), np.eye(6) * 0.01)

    def run(model: OdometryModel) -> list:
        settings = CooperativeSettings(odometry=model, sensor=SensorModel(sigma_bearing=0.01))
        est = CooperativeEstimator(("A", "B"), prior, settings)
        velocity = np.array([[1.0, 0, 0, 0.1], [1.0, 0, 0, 0.1]])
        for k in range(41):  # events every 0.1 s to 4 s; B's last command at 1 s
            t = round(0.1 * k, 10)
            held_since = max(round(t - 0.1, 10), 0.0)  # held over the step ending at t
            stamp = np.array([held_since, min(held_since, 1.0)])
            est.advance(t, HeldOdometry(velocity=velocity, stamp=stamp))
        return est.beliefs()

    speed, turn = 2.0, 0.5
    still = run(still_model)
    lost = run(replace(still_model, lost_speed=speed, lost_turn_rate=turn))
    age = 4.0 - (1.0 + 0.5)
    np.testing.assert_allclose(lost[0].cov, still[0].cov, rtol=0, atol=0)
    np.testing.assert_allclose(lost[0].mean, still[0].mean, rtol=0, atol=0)
    extra = lost[1].cov - still[1].cov
    np.testing.assert_allclose(np.diag(extra), [(speed * age) ** 2] * 2 + [(turn * age) ** 2])
    np.testing.assert_allclose(lost[1].mean, still[1].mean, rtol=0, atol=0)  # still: mean zero
    off = run(replace(still_model, lost_speed=0.0, lost_turn_rate=turn))
    assert all(np.array_equal(o.cov, s.cov) for o, s in zip(off, still, strict=True))


def test_a_reply_the_wire_check_lets_through_but_the_filter_cannot_take_is_counted():
    """The wire check allows an asymmetry of 1e-9 of the covariance's scale (at least 1); a
    team belief of small variances with such an asymmetry decodes, and then the Gaussian it
    would become refuses it (asymmetry beyond 1e-6 of its largest variance): counted
    ``rejected.bad_covariance``, not a crash."""
    from collections import Counter

    import msgpack

    from relloc.runtime.handoff import Handoff

    roster = ("1", "2", "3")
    cov = 1e-6 * np.eye(9)
    cov[0, 1] = 5e-10  # the lower triangle, which the eigenvalue check reads, is diagonal
    payload = {"v": SCHEMA_VERSION, "type": "sync", "sender": "1", "seq": 0, "t": 5.2}
    payload |= {"wall_ns": 0, "target": "3", "stamp": 5.2}
    payload |= {"mean": np.zeros(9).tolist(), "cov": cov.tolist()}
    body = decode(msgpack.packb(payload), roster=roster, key_sender="1").body
    counters: Counter[str] = Counter()
    h = Handoff("3", roster, counters)
    h.begin(after=5.0)
    assert h.request(["1", "2"])["target"] == "1"
    assert h.accept("1", body, 5.2, 0.1) is None
    assert counters["rejected.bad_covariance"] == 1 and h.waiting
