r"""``relloc certs DIR --team NAME --robots a,b,c`` — the certificates of a secure team.

Writes a certificate authority, one EC key and certificate per robot (subject CN = the robot
id) and one for the launcher/clock (CN ``launcher``) into ``DIR`` (keys with permissions 0600;
see :mod:`relloc.runtime.certs`), and one Zenoh configuration per member into ``DIR/zenoh``
(mutual TLS only, listening on ``tls/127.0.0.1:0``; access control by certificate name; see
:mod:`relloc.runtime.access`). Use them with ``relloc team up ... --secure --certs DIR``, or
start the processes by hand (the built-in team; one ``relloc node`` per robot)::

    relloc certs DIR --team demo --robots observer,aerial1,aerial2,ground1,ground2
    relloc team clock --team demo --roster observer,aerial1,aerial2,ground1,ground2 \
        --duration 60 --zenoh-config DIR/zenoh/launcher.json5 --listen tls/127.0.0.1:7447
    relloc node --robot observer --team demo --zenoh-config DIR/zenoh/observer.json5 \
        --connect tls/127.0.0.1:7447

Across machines, name them with ``--host`` and listen there (``--listen tls/HOST:0``).
A folder that already holds a team's CA is refused unless ``--replace`` is given: the
certificates the old CA signed (copied to robots) stop working when it is replaced.
"""

from __future__ import annotations

import argparse

from relloc.cli.console import plain_text
from relloc.cli.flags import nonempty_path


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "certs",
        help="make a team CA, per-robot certificates and Zenoh TLS/ACL configurations",
        description=plain_text(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("folder", type=nonempty_path, help="output folder")
    p.add_argument("--team", required=True, help="team id (key-expression prefix)")
    p.add_argument("--robots", required=True, help="comma-separated robot ids")
    p.add_argument(
        "--host",
        action="append",
        default=[],
        metavar="NAME",
        help="extra DNS name or IP the certificates are valid for (besides loopback; repeatable)",
    )
    p.add_argument(
        "--replace",
        action="store_true",
        help="write over a folder that already holds a team's CA (its certificates stop working)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from relloc.errors import ConfigError
    from relloc.runtime.access import write_member_configs
    from relloc.runtime.certs import make_team_certs

    robots = tuple(r.strip() for r in args.robots.split(","))
    if not all(robots):
        raise ConfigError(f"--robots: an empty id in {args.robots!r}")
    held = [p for p in (args.folder / "ca.pem", args.folder / "ca.key") if p.exists()]
    if held and not args.replace:
        raise ConfigError(
            f"certs: {held[0]} exists: the folder holds a team's CA, and the certificates it "
            "signed stop working if it is replaced; pass --replace, or choose another folder"
        )
    certs = make_team_certs(args.folder, args.team, robots, args.host)
    configs = write_member_configs(certs, args.folder / "zenoh")
    print(
        f"CA {certs.ca}; {len(robots)} robot certificates + launcher; configs in "
        f"{next(iter(configs.values())).parent}"
    )
    return 0
