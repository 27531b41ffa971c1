"""What the launcher makes of the collected ``est``/``evt``/``stats`` streams
(``relloc.runtime.summary``), with hand-made inputs and hand-counted totals."""

from __future__ import annotations

import numpy as np
import pytest
from test_est_message_bodies import _series

from relloc.core.estimates import Estimates
from relloc.runtime.launcher import Collected
from relloc.runtime.messages import decode, encode
from relloc.runtime.summary import (
    agreement,
    assemble_estimates,
    clock_report,
    robot_messages,
    team_message_totals,
)

ROSTER = ("zeta", "alpha", "mid")  # roster order is not alphabetical


def _est(stamps: list[float], xs: list[float], ages: list[float], w: list[float]) -> dict:
    n = len(stamps)
    means = np.zeros((n, 4))
    means[:, 0] = xs
    body = {
        "target": "alpha",
        "track": "",
        "frame": "relative_pose4",
        "stamps": stamps,
        "means": means,
        "covs": np.stack([np.eye(4)] * n),
        "ages": ages,
        "update_stamps": [],
        "update_ages": [],
        "nis": [],
        "update_dofs": [],
        "cond_r": [],
        "cond_s": [],
        "info_names": ["w"],
        "info": w,
    }
    return decode(encode("est", "zeta", 0, 1.0, body), roster=ROSTER).body


def test_a_refiltered_record_replaces_the_one_first_shipped_for_its_time():
    collected = Collected(
        estimates=[
            ("zeta", _est([0.1, 0.2], [1.0, 2.0], [0.0, 0.1], [0.5, 0.6])),
            ("zeta", _est([0.2, 0.3], [20.0, 3.0], [0.7, 0.2], [0.9, 0.8])),  # 0.2 again
        ]
    )
    (s,) = assemble_estimates(collected, ROSTER, "ekf").beliefs
    assert s.t.tolist() == [0.1, 0.2, 0.3]
    assert s.mean[:, 0].tolist() == [1.0, 20.0, 3.0]
    assert s.age.tolist() == [0.0, 0.7, 0.2]
    assert s.info["w"].tolist() == [0.5, 0.9, 0.8]
    assert s.cov.shape == (3, 4, 4)


def test_events_are_sorted_by_time_then_roster_order_of_owner_and_subject():
    collected = Collected(
        events=[
            (2.0, "zeta", "alpha", "created"),
            (1.0, "mid", "zeta", "created"),
            (1.0, "alpha", "zeta", "deleted"),
            (1.0, "zeta", "mid", "created"),
            (1.0, "zeta", "alpha", "recreated"),
        ]
    )
    events = assemble_estimates(collected, ROSTER, "ekf").events
    assert [(e.t, e.owner, e.subject, e.kind) for e in events] == [
        (1.0, "zeta", "alpha", "recreated"),
        (1.0, "zeta", "mid", "created"),
        (1.0, "alpha", "zeta", "deleted"),
        (1.0, "mid", "zeta", "created"),
        (2.0, "zeta", "alpha", "created"),
    ]


def _stats() -> Collected:
    first = {
        "sent.odom": 3,
        "sent.stats": 1,
        "sent.ack": 5,
        "wire.odom": 7,
        "delivered.odom": 6,
        "rejected": 1,
        "rejected.malformed": 1,
        "duplicates": 5,
        "duplicate_samples": 2,
        "from_absent.alpha": 1,
        "cpu_ms": 1000,
        "latency_ms.p50": 7,
        "final": 0,
    }
    second = {
        "sent.odom": 4,
        "rejected": 2,
        "rejected.spoofed": 2,
        "from_absent.mid": 2,
        "cpu_ms": 500,
        "latency_ms.p50": 9,
        "latency_ms.samples": 40,
        "final": 1,
    }
    return Collected(stats={"zeta": [first, second], "alpha": [{"final": 0, "listens": 0}]})


def test_a_robots_counters_are_summed_over_its_processes_latency_taken_from_the_last():
    z = robot_messages(_stats(), ROSTER)["zeta"]
    assert z["processes"] == 2 and z["final_report"] is True
    assert z["sent"]["odom"] == 7 and z["sent"]["stats"] == 1 and z["sent"]["ack"] == 5
    assert z["received_wire"]["odom"] == 7 and z["received_delivered"]["odom"] == 6
    assert z["rejected"] == 3
    assert z["rejected_by_reason"] == {"malformed": 1, "spoofed": 2}
    assert z["duplicates_dropped"] == 5 and z["duplicate_odometry_samples"] == 2
    assert z["from_absent_teammate"] == 3
    assert z["cpu_s"] == pytest.approx(1.5)
    assert z["estimate_latency_ms"] == {"p50": 9, "p99": None, "samples": 40}
    assert z["listens"] is True


def test_a_robot_without_a_final_report_or_not_listening_says_so():
    out = robot_messages(_stats(), ROSTER)
    assert out["alpha"]["final_report"] is False and out["alpha"]["listens"] is False
    assert out["alpha"]["processes"] == 1
    assert out["mid"]["processes"] == 0 and out["mid"]["final_report"] is False


def _robot(sent: int, wire: int, delivered: int, listens: bool) -> dict:
    return {
        "sent": {"odom": sent, "meas": 0, "rows": 0, "eqm": 0, "mail": 0},
        "received_wire": {"odom": wire},
        "received_delivered": {"odom": delivered},
        "rejected": 1,
        "estimates": 2,
        "listens": listens,
    }


def test_each_data_message_is_expected_once_at_every_other_listening_robot():
    per_robot = {
        "a": _robot(10, 40, 35, True),
        "b": _robot(20, 40, 35, True),
        "c": _robot(30, 0, 0, False),  # hears nothing, expects nothing
    }
    totals = team_message_totals(per_robot)
    # a: 10 × {b}, b: 20 × {a}, c: 30 × {a, b}
    assert totals["data_messages_expected"] == 90
    assert totals["data_messages_sent"] == 60
    assert totals["data_messages_received_wire"] == 80
    assert totals["data_messages_delivered"] == 70
    assert totals["transport_loss_rate"] == pytest.approx(1.0 / 9.0)
    assert totals["rejected"] == 3 and totals["estimates"] == 6
    assert team_message_totals(per_robot, killed=True)["transport_loss_rate"] is None


def test_a_run_without_a_clock_report_reads_as_empty(tmp_path):
    assert clock_report(tmp_path) == {}


def test_agreement_matches_times_to_a_microsecond_and_keeps_the_worst_pair():
    ref = Estimates(
        estimator="ekf",
        beliefs=(
            _series([0.1, 0.2], [0.0, 0.0], owner="mid", subject="alpha"),
            _series([0.1], [0.0], owner="zeta", subject="alpha"),
        ),
    )
    got = Estimates(
        estimator="ekf",
        beliefs=(
            _series([0.1 + 1e-9, 0.2, 0.3], [0.5, 0.0, 7.0], owner="mid", subject="alpha"),
            _series([0.1], [0.25], owner="zeta", subject="alpha"),
        ),
    )
    out = agreement(got, ref)
    mid = out["pairs"]["mid->alpha"]
    assert (mid["common"], mid["only_in_process"], mid["only_distributed"]) == (2, 0, 1)
    assert mid["max_abs_mean_diff"] == 0.5
    assert out["pairs"]["zeta->alpha"]["max_abs_mean_diff"] == 0.25
    assert out["max_abs_mean_diff"] == 0.5


def test_a_long_refiltered_stretch_keeps_the_latest_record_of_every_time():
    stamps = [round(0.1 * k, 10) for k in range(20)]
    first = _est(stamps, [1.0] * 20, [0.0] * 20, [0.0] * 20)
    second = _est(stamps, [2.0] * 20, [0.5] * 20, [1.0] * 20)
    collected = Collected(estimates=[("zeta", first), ("zeta", second)])
    (s,) = assemble_estimates(collected, ROSTER, "ekf").beliefs
    assert s.t.tolist() == stamps
    assert s.mean[:, 0].tolist() == [2.0] * 20
    assert s.info["w"].tolist() == [1.0] * 20
