"""A team's public-key infrastructure: one CA, one key and certificate per robot and one for the
launcher (which also drives the clock), made with the ``cryptography`` package.

Layout of a certificate folder (``relloc certs DIR --team NAME --robots a,b,c``)::

    DIR/ca.pem  DIR/ca.key                  the team's certificate authority (keep ca.key offline)
    DIR/<id>.pem  DIR/<id>.key              one per robot id and one for ``launcher``
    DIR/team.json                           {"team": NAME, "robots": [...], "launcher": "launcher"}

Every certificate's subject common name (CN) is its holder's id: Zenoh's access control matches
mutual-TLS peers by that name (``cert_common_names``), so a robot can be allowed to publish only
under its own key prefix. Leaf certificates are valid for both TLS roles (a Zenoh peer listens
and connects) and name ``localhost``, ``127.0.0.1`` and any extra ``hosts`` (DNS names or IP
addresses of the robots' machines) as subject alternative names, so a connecting peer can verify
the listener's name. Private keys (EC P-256) are written
with permissions 0600.
"""

from __future__ import annotations

import datetime
import ipaddress
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from relloc.errors import ConfigError, DataError, require
from relloc.pipeline.output import prepare_out_dir
from relloc.runtime import keys

LAUNCHER_ID = "launcher"
"""Common name of the launcher's certificate: the only identity allowed to send ``tick``/``ctl``
(the launcher and the clock process it starts both hold it)."""
VALID_DAYS = 365
SUBJECT_ALT_NAMES = ("localhost", "127.0.0.1")
"""Names every leaf certificate is valid for (``hosts`` add to them)."""


@dataclass(frozen=True)
class TeamCerts:
    """Paths of a certificate folder (see module docstring)."""

    folder: Path
    team: str
    robots: tuple[str, ...]

    @property
    def ca(self) -> Path:
        return self.folder / "ca.pem"

    def certificate(self, member: str) -> Path:
        return self.folder / f"{self._member(member)}.pem"

    def private_key(self, member: str) -> Path:
        return self.folder / f"{self._member(member)}.key"

    def _member(self, member: str) -> str:
        if member != LAUNCHER_ID and member not in self.robots:
            raise ConfigError(f"certs: no certificate for {member!r} in {self.folder}")
        return member


def check_roster(team: str, robots: Sequence[str], flag: str = "") -> tuple[str, ...]:
    """``robots`` as a tuple, after checking the team's and every robot's id
    (:func:`relloc.runtime.keys.check_id`, so that every file named after one lies in the
    folder; a robot's through :func:`~relloc.runtime.keys.check_robot_id`, so none is the
    clock's): at least one robot, none twice, none the launcher's id. A ConfigError names
    ``{flag}team`` or ``{flag}robots``."""
    keys.check_id(team, f"{flag}team")
    robots = tuple(robots)
    if not robots:
        raise ConfigError(f"{flag}robots: no robot ids")
    for r in robots:
        keys.check_robot_id(r, f"{flag}robots")
    if LAUNCHER_ID in robots or len(set(robots)) != len(robots):
        raise ConfigError(
            f"{flag}robots: duplicate ids or the reserved id {LAUNCHER_ID!r}: {robots!r:.60}"
        )
    return robots


def make_team_certs(
    folder: Path, team: str, robots: Sequence[str], hosts: Sequence[str] = ()
) -> TeamCerts:
    """Write a CA and one key/certificate per robot plus the launcher's into ``folder``."""
    robots = check_roster(team, robots, "--")
    for name in hosts:  # a bad --host is refused before the CA is written
        _alt_name(name)
    folder = prepare_out_dir(folder, "certs")
    ca_key, ca_cert = _certificate_authority(team)
    _write_key(folder / "ca.key", ca_key)
    _write_pem(folder / "ca.pem", ca_cert)
    for member in (*robots, LAUNCHER_ID):
        key, cert = _leaf(member, ca_key, ca_cert, (*SUBJECT_ALT_NAMES, *hosts))
        _write_key(folder / f"{member}.key", key)
        _write_pem(folder / f"{member}.pem", cert)
    manifest = {"team": team, "robots": list(robots), "launcher": LAUNCHER_ID}
    (folder / "team.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return TeamCerts(folder, team, robots)


def load_team_certs(folder: Path) -> TeamCerts:
    """The certificate folder written by :func:`make_team_certs`, checked to be complete and
    to belong together (:func:`check_member`): a mismatch found only by the TLS handshake
    left every process waiting for links that never came up. The manifest's team and robots
    must pass :func:`check_roster`, as :func:`make_team_certs`'s do."""
    folder = Path(folder)
    manifest_path = folder / "team.json"
    try:
        manifest = json.loads(manifest_path.read_text())
        robots = manifest["robots"]
        if not isinstance(robots, list) or not all(isinstance(r, str) for r in robots):
            raise TypeError(f"robots must be a list of ids, got {robots!r:.60}")
        team = manifest["team"]
        certs = TeamCerts(folder, team, check_roster(team, robots))
    except (OSError, ValueError, KeyError, TypeError, RecursionError, ConfigError) as exc:
        raise DataError(f"{manifest_path}: not a relloc certificate folder ({exc})") from None
    missing = [
        str(p)
        for p in (
            certs.ca,
            *(certs.certificate(m) for m in (*certs.robots, LAUNCHER_ID)),
            *(certs.private_key(m) for m in (*certs.robots, LAUNCHER_ID)),
        )
        if not p.is_file()
    ]
    if missing:
        raise DataError(f"{folder}: missing certificate files {missing}")
    ca = read_certificate(certs.ca)
    for member in (*certs.robots, LAUNCHER_ID):
        check_member(certs, member, ca)
    return certs


def check_member(certs: TeamCerts, member: str, ca: Any) -> None:
    """DataError naming the file unless ``member``'s certificate is signed by the team's CA
    (``ca``), names ``member`` (its CN), is valid now and holds the public key of ``member``'s
    private key."""
    from cryptography.exceptions import InvalidSignature
    from cryptography.hazmat.primitives import serialization
    from cryptography.x509.oid import NameOID

    path = certs.certificate(member)
    cert = read_certificate(path)
    try:
        cert.verify_directly_issued_by(ca)
    except (ValueError, TypeError, InvalidSignature) as exc:  # another issuer, key or signer
        raise DataError(f"{path}: not signed by {certs.ca} ({type(exc).__name__})") from None
    names = [a.value for a in cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)]
    if names != [member]:
        raise DataError(f"{path}: its common name is {names}, not [{member!r}]")
    now = datetime.datetime.now(datetime.UTC)
    if not cert.not_valid_before_utc <= now <= cert.not_valid_after_utc:
        raise DataError(
            f"{path}: valid only from {cert.not_valid_before_utc:%Y-%m-%d %H:%M} to "
            f"{cert.not_valid_after_utc:%Y-%m-%d %H:%M} UTC"
        )
    key_path = certs.private_key(member)
    key = read_private_key(key_path)
    public = serialization.PublicFormat.SubjectPublicKeyInfo
    pem = serialization.Encoding.PEM
    if key.public_key().public_bytes(pem, public) != cert.public_key().public_bytes(pem, public):
        raise DataError(f"{key_path}: not the private key of {path}")


def read_certificate(path: Path) -> Any:
    """The X.509 certificate in the PEM file ``path`` (DataError naming it otherwise)."""
    x509 = require("cryptography.x509", "runtime")
    try:
        return x509.load_pem_x509_certificate(path.read_bytes())
    except (OSError, ValueError) as exc:
        raise DataError(f"{path}: not a PEM certificate ({exc})") from None


def read_private_key(path: Path) -> Any:
    """The unencrypted private key in the PEM file ``path`` (DataError naming it otherwise)."""
    serialization = require("cryptography.hazmat.primitives.serialization", "runtime")
    try:
        return serialization.load_pem_private_key(path.read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise DataError(f"{path}: not an unencrypted PEM private key ({exc})") from None


#: The TLS files a Zenoh configuration names (keys under ``transport/link/tls``).
TLS_FILES = (
    "root_ca_certificate",
    "listen_certificate",
    "listen_private_key",
    "connect_certificate",
    "connect_private_key",
)


def check_tls_files(conf: Any, where: str) -> None:
    """ConfigError naming ``where``, the key and the file unless every TLS file the Zenoh
    configuration ``conf`` names (:data:`TLS_FILES`) is a readable PEM certificate or private
    key. Zenoh would otherwise fail inside its TLS layer (a file of garbage read as "peer sent
    no certificates"), or, for a connecting peer, only when a link is tried."""
    zenoh = require("zenoh", "runtime")
    for name in TLS_FILES:
        key = f"transport/link/tls/{name}"
        try:
            value = json.loads(conf.get_json(key))
        except zenoh.ZError:  # a Zenoh without this key: nothing to check
            continue
        if value is None:
            continue
        read = read_private_key if name.endswith("private_key") else read_certificate
        try:
            read(Path(str(value)))
        except DataError as exc:
            raise ConfigError(f"{where}: {key}: {exc}") from None


def _name(common_name: str, team: str | None = None) -> Any:
    x509 = require("cryptography.x509", "runtime")
    from cryptography.x509.oid import NameOID

    attrs = [x509.NameAttribute(NameOID.COMMON_NAME, common_name)]
    if team is not None:
        attrs.append(x509.NameAttribute(NameOID.ORGANIZATION_NAME, f"relloc team {team}"))
    return x509.Name(attrs)


def _new_key() -> Any:
    ec = require("cryptography.hazmat.primitives.asymmetric.ec", "runtime")
    return ec.generate_private_key(ec.SECP256R1())


def _validity(builder: Any) -> Any:
    now = datetime.datetime.now(datetime.UTC)
    return builder.not_valid_before(now - datetime.timedelta(minutes=5)).not_valid_after(
        now + datetime.timedelta(days=VALID_DAYS)
    )


def _certificate_authority(team: str) -> tuple[Any, Any]:
    x509 = require("cryptography.x509", "runtime")
    from cryptography.hazmat.primitives import hashes

    key = _new_key()
    name = _name(f"relloc {team} CA", team)
    builder = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                key_cert_sign=True,
                crl_sign=True,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
    )
    return key, _validity(builder).sign(key, hashes.SHA256())


def _alt_name(name: str) -> Any:
    x509 = require("cryptography.x509", "runtime")
    try:
        return x509.IPAddress(ipaddress.ip_address(name))
    except ValueError:
        if not name or any(c.isspace() or c in "/:@" for c in name):
            raise ConfigError(f"--host: {name!r} is neither an IP address nor a DNS name") from None
        return x509.DNSName(name)


def _leaf(member: str, ca_key: Any, ca_cert: Any, hosts: Sequence[str]) -> tuple[Any, Any]:
    x509 = require("cryptography.x509", "runtime")
    from cryptography.hazmat.primitives import hashes
    from cryptography.x509.oid import ExtendedKeyUsageOID

    key = _new_key()
    alt_names = [_alt_name(h) for h in dict.fromkeys(hosts)]
    builder = (
        x509.CertificateBuilder()
        .subject_name(_name(member))
        .issuer_name(ca_cert.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.SubjectAlternativeName(alt_names), critical=False)
        .add_extension(
            x509.ExtendedKeyUsage(
                [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
            ),
            critical=False,
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()),
            critical=False,
        )
    )
    return key, _validity(builder).sign(ca_key, hashes.SHA256())


def _write_key(path: Path, key: Any) -> None:
    from cryptography.hazmat.primitives import serialization

    data = key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    if path.exists():
        path.unlink()
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.chmod(path, 0o600)


def _write_pem(path: Path, cert: Any) -> None:
    from cryptography.hazmat.primitives import serialization

    path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
