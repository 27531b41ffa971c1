"""What ``--secure`` and the default transport set up, checked without starting a team:
certificates (CN, chain, names, 0600 keys), the access-control rules each member enforces, the
loopback-only / TLS-only listeners of every child's command line."""

from __future__ import annotations

import ipaddress
import json
import stat

import pytest
from cryptography import x509
from cryptography.x509.oid import NameOID

from relloc.errors import ConfigError, DataError
from relloc.runtime.access import member_config, secure_team
from relloc.runtime.certs import LAUNCHER_ID, load_team_certs, make_team_certs
from relloc.runtime.launcher import TeamSettings, clock_command, node_command
from relloc.runtime.transport import TransportSettings

ROBOTS = ("observer", "flyer", "rover")


def _cert(path):
    return x509.load_pem_x509_certificate(path.read_bytes())


def test_one_certificate_per_robot_and_the_launcher_signed_by_the_team_ca(tmp_path):
    certs = make_team_certs(tmp_path, "demo", ROBOTS, hosts=("robot7.local", "10.0.0.7"))
    ca = _cert(certs.ca)
    for member in (*ROBOTS, LAUNCHER_ID):
        cert = _cert(certs.certificate(member))
        assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == member
        cert.verify_directly_issued_by(ca)
        names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
        assert names.get_values_for_type(x509.DNSName) == ["localhost", "robot7.local"]
        assert names.get_values_for_type(x509.IPAddress) == [
            ipaddress.ip_address("127.0.0.1"),
            ipaddress.ip_address("10.0.0.7"),
        ]
        assert stat.S_IMODE(certs.private_key(member).stat().st_mode) == 0o600
    assert stat.S_IMODE((tmp_path / "ca.key").stat().st_mode) == 0o600
    assert load_team_certs(tmp_path).robots == ROBOTS
    with pytest.raises(ConfigError, match="reserved"):
        make_team_certs(tmp_path / "x", "demo", ("a", LAUNCHER_ID))
    with pytest.raises(ConfigError, match="--host"):
        make_team_certs(tmp_path / "y", "demo", ("a",), hosts=("bad host",))
    (tmp_path / "flyer.key").unlink()
    with pytest.raises(DataError, match="missing"):
        load_team_certs(tmp_path)


def _copy(src, dst):  # type: ignore[no-untyped-def]
    import shutil

    shutil.copytree(src, dst)
    return dst


def test_certificates_that_do_not_belong_together_are_refused_naming_the_file(tmp_path):
    """Each of these once started every process and left them waiting, with empty logs, for
    TLS links that never came up, until the wall timeout."""
    good = make_team_certs(tmp_path / "good", "demo", ROBOTS).folder
    other = make_team_certs(tmp_path / "other", "demo", ROBOTS).folder
    assert load_team_certs(good).robots == ROBOTS
    cases = {
        "another team's CA": ({"ca.pem": other / "ca.pem"}, r"observer\.pem: not signed by"),
        "another CA's pair": (
            {"observer.pem": other / "observer.pem", "observer.key": other / "observer.key"},
            r"observer\.pem: not signed by",
        ),
        "a teammate's pair": (
            {"observer.pem": good / "flyer.pem", "observer.key": good / "flyer.key"},
            r"observer\.pem: its common name is \['flyer'\], not \['observer'\]",
        ),
        "a teammate's key": ({"observer.key": good / "flyer.key"}, "not the private key of"),
        "not PEM": ({"observer.pem": good / "team.json"}, r"observer\.pem: not a PEM certificate"),
        "a key not PEM": ({"observer.key": good / "team.json"}, "not an unencrypted PEM"),
    }
    for name, (replaced, message) in cases.items():
        folder = _copy(good, tmp_path / name.replace(" ", "_").replace("'", ""))
        for file, source in replaced.items():
            (folder / file).write_bytes(source.read_bytes())
        with pytest.raises(DataError, match=message):
            load_team_certs(folder)
    folder = _copy(good, tmp_path / "split")
    manifest = json.loads((folder / "team.json").read_text())
    (folder / "team.json").write_text(json.dumps({**manifest, "robots": "observer"}))
    with pytest.raises(DataError, match="robots must be a list of ids"):  # was split in letters
        load_team_certs(folder)


def test_access_control_lets_each_robot_publish_only_under_its_own_prefix(tmp_path):
    certs = make_team_certs(tmp_path, "demo", ROBOTS)
    config = member_config(certs, "observer")
    assert config["listen"]["endpoints"] == ["tls/127.0.0.1:0"]
    assert config["transport"]["link"]["protocols"] == ["tls"]
    tls = config["transport"]["link"]["tls"]
    assert tls["enable_mtls"] and tls["verify_name_on_connect"]
    acl = config["access_control"]
    assert acl["enabled"] and acl["default_permission"] == "deny"
    rules = {r["id"]: r for r in acl["rules"]}
    subjects = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}
    publishers: dict[str, set[str]] = {}
    for policy in acl["policies"]:
        for rule_id in policy["rules"]:
            rule = rules[rule_id]
            if rule["flows"] == ["ingress"] and set(rule["messages"]) & {"put", "liveliness_token"}:
                for subject in policy["subjects"]:
                    for cn in subjects[subject]:
                        publishers.setdefault(cn, set()).update(rule["key_exprs"])
    assert publishers == {
        **{
            r: {f"relloc/demo/robot/{r}/**", f"relloc/demo/alive/{r}", f"relloc/demo/ready/{r}"}
            for r in ROBOTS
        },
        LAUNCHER_ID: {"relloc/demo/clock/**", "relloc/demo/alive/clock"},
    }


def test_secure_team_checks_a_given_certificate_folder(tmp_path):
    make_team_certs(tmp_path / "certs", "demo", ROBOTS[:2])
    with pytest.raises(ConfigError, match="rover"):
        secure_team(tmp_path / "out", "demo", ROBOTS, tmp_path / "certs")
    with pytest.raises(ConfigError, match="team"):
        secure_team(tmp_path / "out", "other", ROBOTS[:2], tmp_path / "certs")
    team = secure_team(tmp_path / "out", "demo", ROBOTS[:2], tmp_path / "certs")
    assert sorted(team.configs) == sorted([*ROBOTS[:2], LAUNCHER_ID])
    with pytest.raises(ConfigError, match="--secure"):
        TeamSettings(scenario="default", out_dir=tmp_path, certs_dir=tmp_path / "certs")


def test_children_listen_on_loopback_only_and_tls_only_when_secure(tmp_path):
    settings = TeamSettings(scenario="default", out_dir=tmp_path)
    plain = node_command(settings, "observer", "tcp/127.0.0.1:7447")
    assert plain[plain.index("--listen") + 1] == "tcp/127.0.0.1:0"
    team = secure_team(tmp_path, "team", ROBOTS, None)
    secure = node_command(settings, "observer", "tls/127.0.0.1:7447", team)
    assert secure[secure.index("--listen") + 1] == "tls/127.0.0.1:0"
    assert secure[secure.index("--zenoh-config") + 1] == str(team.config("observer"))
    clock = clock_command(settings, ROBOTS, 4.0, "tls/127.0.0.1:7447", tmp_path / "c.json", team)
    assert clock[clock.index("--zenoh-config") + 1] == str(team.config(LAUNCHER_ID))
    conf = TransportSettings().zenoh_config()
    assert conf.get_json("listen/endpoints") in (
        '["tcp/127.0.0.1:0"]',
        '{"peer":["tcp/127.0.0.1:0"]}',
    )


def test_a_zenoh_config_naming_a_bad_tls_file_is_refused_naming_key_and_file(tmp_path):
    # Zenoh's own message for a certificate of garbage was "peer sent no certificates"
    from relloc.runtime.access import write_member_configs

    certs = make_team_certs(tmp_path / "certs", "demo", ROBOTS[:1])
    config = write_member_configs(certs, tmp_path / "zenoh")[ROBOTS[0]]
    TransportSettings(config_file=config).zenoh_config()  # as written: accepted
    cert, key = certs.certificate(ROBOTS[0]), certs.private_key(ROBOTS[0])
    key.write_bytes(cert.read_bytes())  # a certificate where the key should be
    with pytest.raises(ConfigError, match=r"tls/listen_private_key: .* not an unencrypted PEM"):
        TransportSettings(config_file=config).zenoh_config()
    cert.write_text("garbage\n")
    with pytest.raises(ConfigError, match=rf"{config}: transport/link/tls/listen_certificate: "):
        TransportSettings(config_file=config).zenoh_config()
    certs.ca.unlink()
    with pytest.raises(ConfigError, match=r"tls/root_ca_certificate: .*No such file"):
        TransportSettings(config_file=config).zenoh_config()
