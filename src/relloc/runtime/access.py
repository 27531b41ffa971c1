"""Zenoh mutual TLS and access control for a team (the ``--secure`` configuration).

:func:`member_config` is the Zenoh configuration of one team member (a robot id or the
launcher, see :mod:`relloc.runtime.certs`):

- **transport**: TLS only — ``listen`` on ``tls/127.0.0.1:0`` (no TCP listener), the team CA
  as the only root (``root_ca_certificate``), the member's own key and certificate for both
  roles, ``enable_mtls`` (a peer without a certificate of this CA cannot open a link) and
  ``verify_name_on_connect`` (the listener's certificate must name ``127.0.0.1``);
- **access control** (Zenoh 1.x ``access_control``, enforced by every member on what it receives
  — ``ingress`` — from each authenticated peer, matched by its certificate's common name;
  default ``deny``):

  - every roster robot and the launcher may subscribe, declare liveliness subscribers and query
    liveliness under ``relloc/<team>/**``, and reply to those queries;
  - robot ``r`` may publish (``put``) only under ``relloc/<team>/robot/<r>/**`` and hold only the
    liveliness tokens ``relloc/<team>/alive/<r>`` and ``relloc/<team>/ready/<r>``;
  - only the launcher identity may publish under ``relloc/<team>/clock/**`` (``tick``, ``ctl``)
    and hold ``relloc/<team>/alive/clock``;
  - outgoing messages (``egress``) may go to any team member.

A certificate of the team CA whose name is not on the roster gets nothing. Zenoh peers link
directly (gossip through the launcher's endpoint), so every message a member receives comes
over the sender's own authenticated link: the common name is the sender.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from relloc.errors import ConfigError
from relloc.runtime import keys
from relloc.runtime.certs import LAUNCHER_ID, TeamCerts, load_team_certs, make_team_certs

SECURE_LISTEN = "tls/127.0.0.1:0"
SUBSCRIBE_MESSAGES = [
    "declare_subscriber",
    "declare_liveliness_subscriber",
    "liveliness_query",
    "query",
    "reply",
]
ALL_MESSAGES = [*SUBSCRIBE_MESSAGES, "put", "liveliness_token"]


def _publish_rule(rule_id: str, key_exprs: list[str], tokens: list[str]) -> list[dict[str, Any]]:
    return [
        {
            "id": f"{rule_id}-put",
            "permission": "allow",
            "flows": ["ingress"],
            "messages": ["put"],
            "key_exprs": key_exprs,
        },
        {
            "id": f"{rule_id}-token",
            "permission": "allow",
            "flows": ["ingress"],
            "messages": ["liveliness_token"],
            "key_exprs": tokens,
        },
    ]


def access_control(certs: TeamCerts) -> dict[str, Any]:
    """The ``access_control`` section shared by every member of the team."""
    team = certs.team
    everything = [f"relloc/{team}/**"]
    rules: list[dict[str, Any]] = [
        {
            "id": "egress",
            "permission": "allow",
            "flows": ["egress"],
            "messages": ALL_MESSAGES,
            "key_exprs": everything,
        },
        {
            "id": "subscribe",
            "permission": "allow",
            "flows": ["ingress"],
            "messages": SUBSCRIBE_MESSAGES,
            "key_exprs": everything,
        },
    ]
    subjects: list[dict[str, Any]] = [
        {"id": "members", "cert_common_names": [*certs.robots, LAUNCHER_ID]}
    ]
    policies: list[dict[str, Any]] = [{"rules": ["egress", "subscribe"], "subjects": ["members"]}]
    publishers = {r: r for r in certs.robots} | {LAUNCHER_ID: keys.CLOCK_ID}
    for member, token_owner in publishers.items():
        if member == LAUNCHER_ID:
            prefix = [f"relloc/{team}/clock/**"]
            tokens = [keys.alive_key(team, token_owner)]
        else:
            prefix = [f"relloc/{team}/robot/{member}/**"]
            tokens = [keys.alive_key(team, member), keys.ready_key(team, member)]
        member_rules = _publish_rule(f"publish-{member}", prefix, tokens)
        rules += member_rules
        subjects.append({"id": f"cn-{member}", "cert_common_names": [member]})
        policies.append({"rules": [r["id"] for r in member_rules], "subjects": [f"cn-{member}"]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def member_config(certs: TeamCerts, member: str) -> dict[str, Any]:
    """The Zenoh configuration (as a JSON-able dict) of ``member`` (see module docstring)."""
    key, cert = str(certs.private_key(member).resolve()), str(certs.certificate(member).resolve())
    return {
        "listen": {"endpoints": [SECURE_LISTEN]},
        "transport": {
            "link": {
                "protocols": ["tls"],
                "tls": {
                    "root_ca_certificate": str(certs.ca.resolve()),
                    "listen_private_key": key,
                    "listen_certificate": cert,
                    "enable_mtls": True,
                    "connect_private_key": key,
                    "connect_certificate": cert,
                    "verify_name_on_connect": True,
                },
            }
        },
        "access_control": access_control(certs),
    }


def write_member_configs(certs: TeamCerts, folder: Path) -> dict[str, Path]:
    """Write ``<folder>/<member>.json5`` for every robot and the launcher; returns the paths."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for member in (*certs.robots, LAUNCHER_ID):
        path = folder / f"{member}.json5"
        path.write_text(json.dumps(member_config(certs, member), indent=2) + "\n")
        paths[member] = path
    return paths


@dataclass(frozen=True)
class SecureTeam:
    """A team's certificates and the Zenoh configuration file of each member."""

    certs: TeamCerts
    configs: dict[str, Path]

    def config(self, member: str) -> Path:
        return self.configs[member]

    def arguments(self, member: str) -> list[str]:
        """``relloc node``/``relloc team clock`` options of ``member``: TLS-only loopback
        listener and its configuration file."""
        return ["--listen", SECURE_LISTEN, "--zenoh-config", str(self.configs[member])]


def secure_team(
    out_dir: Path, team: str, roster: Sequence[str], certs_dir: Path | None
) -> SecureTeam:
    """The secure setup of ``relloc team up --secure``: the certificates of ``certs_dir``
    (checked to be of this team and to cover the roster) or new ones in ``<out>/certs``; member
    configurations written to ``<out>/zenoh``."""
    if certs_dir is None:
        certs = make_team_certs(out_dir / "certs", team, roster)
    else:
        certs = load_team_certs(certs_dir)
        if certs.team != team:
            raise ConfigError(f"--certs: {certs_dir} is for team {certs.team!r}, not {team!r}")
        missing = sorted(set(roster) - set(certs.robots))
        if missing:
            raise ConfigError(f"--certs: {certs_dir} has no certificate for robots {missing}")
        certs = TeamCerts(certs.folder, team, tuple(roster))
    return SecureTeam(certs, write_member_configs(certs, out_dir / "zenoh"))
