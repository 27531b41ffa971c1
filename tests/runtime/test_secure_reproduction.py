"""A reproduction's team on the closed network: ``relloc team up sharma2013 --secure`` (mutual
TLS only, one certificate per robot from ``relloc certs``, Zenoh access control) gives every
agent exactly the estimates of the plain run — the security layer changes the transport, never
what a filter receives."""

from __future__ import annotations

import json

import pytest

from relloc.cli import main
from relloc.runtime.summary import DATA_KINDS

pytestmark = pytest.mark.slow

ROBOTS = "1,2,3,4,5"


def _agents(summary: dict) -> dict:
    run = summary["per_run"][0]
    return {
        robot: (a["pos_rmse_m"], a["heading_rmse_rad"], a["max_abs_mean_diff"], a["records"])
        for robot, a in run["agents"].items()
    }


def test_sharma_team_on_the_secure_network_equals_the_plain_run(tmp_path):
    certs = tmp_path / "certs"
    assert main(["certs", str(certs), "--team", "team", "--robots", ROBOTS]) == 0
    base = ["team", "up", "sharma2013", "--duration", "2", "--quiet"]
    assert main([*base, "--out", str(tmp_path / "plain")]) == 0
    secure_out = tmp_path / "secure"
    assert main([*base, "--out", str(secure_out), "--secure", "--certs", str(certs)]) == 0
    plain = json.loads((tmp_path / "plain" / "summary.json").read_text())
    secure = json.loads((secure_out / "summary.json").read_text())
    assert (plain["secure"], secure["secure"]) == (False, True)
    # the launcher wrote each member's TLS + access-control configuration from those certificates
    config = json.loads((secure_out / "run0" / "zenoh" / "1.json5").read_text())
    assert config["transport"]["link"]["protocols"] == ["tls"]
    assert config["transport"]["link"]["tls"]["root_ca_certificate"] == str(
        (certs / "ca.pem").resolve()
    )
    assert _agents(secure) == _agents(plain)
    assert secure["agreement"]["within_tolerance"], secure["agreement"]
    assert secure["per_run"][0]["collector_rejected_by_reason"] == {}
    # what a filter receives is the same message for message; the collector's ``est``/``evt``/
    # ``stats`` count follows how far each node had filtered at each report tick (scheduling,
    # not security), so their content is compared above through every agent's records
    for robot, m in secure["per_run"][0]["messages"].items():
        assert m["rejected"] == 0, robot
        plain_sent = plain["per_run"][0]["messages"][robot]["sent"]
        for kind in (*DATA_KINDS, "ack"):
            assert m["sent"][kind] == plain_sent[kind], (robot, kind)


def test_certs_without_secure_is_a_config_error(tmp_path):
    argv = ["team", "up", "sharma2013", "--out", str(tmp_path / "o"), "--certs", str(tmp_path)]
    assert main([*argv, "--quiet"]) == 2
