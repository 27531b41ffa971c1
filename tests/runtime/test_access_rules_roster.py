"""The ``--secure`` access control of a team: who may subscribe, and a certificate folder
covering more robots than the team that runs."""

from __future__ import annotations

import json

from relloc.runtime.access import secure_team
from relloc.runtime.certs import LAUNCHER_ID, make_team_certs


def _allowed(acl: dict, message: str) -> dict[str, set[str]]:
    """Per certificate common name, the key expressions it may send ``message`` on."""
    rules = {r["id"]: r for r in acl["rules"]}
    subjects = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}
    out: dict[str, set[str]] = {}
    for policy in acl["policies"]:
        for rule_id in policy["rules"]:
            rule = rules[rule_id]
            if "ingress" in rule["flows"] and message in rule["messages"]:
                for subject in policy["subjects"]:
                    for cn in subjects[subject]:
                        out.setdefault(cn, set()).update(rule["key_exprs"])
    return out


def test_a_team_of_a_larger_certificate_folder_admits_only_its_own_robots(tmp_path):
    make_team_certs(tmp_path / "certs", "demo", ("observer", "flyer", "rover"))
    team = secure_team(tmp_path / "out", "demo", ("observer", "flyer"), tmp_path / "certs")
    assert team.certs.robots == ("observer", "flyer")
    assert sorted(team.configs) == sorted(["observer", "flyer", LAUNCHER_ID])
    acl = json.loads(team.config("observer").read_text())["access_control"]
    subscribers = _allowed(acl, "declare_subscriber")
    assert set(subscribers) == {"observer", "flyer", LAUNCHER_ID}
    assert all(keys == {"relloc/demo/**"} for keys in subscribers.values())
    assert set(_allowed(acl, "put")) == {"observer", "flyer", LAUNCHER_ID}
