"""Runtime branches that a hostile peer, a bad file or a bad argument reaches and no longer
run otherwise: a full inbox, a certificate out of date, an encrypted or oversized world file,
a robot's rejected, duplicate and late deliveries, its input timeouts and the world leaving."""

from __future__ import annotations

import datetime
import time
import zipfile

import numpy as np
import pytest
from test_airground_protocol import ROSTER, SC, TEAM

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.errors import ConfigError, DataError
from relloc.runtime import keys
from relloc.runtime.admission import admit
from relloc.runtime.airground import (
    MEASUREMENT_FIELDS,
    DroneRole,
    RobotProcess,
    RobotSettings,
    load_world,
    save_world,
    sense_body,
)
from relloc.runtime.messages import encode
from relloc.runtime.transport import Inbox, Incoming, TransportSettings, declare_publisher
from relloc.sim.airground import AirGroundWorld


# ------------------------------------------------------------------ inbox, certificates, faults
def test_an_inbox_full_by_record_count_drops_and_counts_the_next_message():
    inbox = Inbox(2)  # room for 2 records, and plenty of bytes
    for i in range(3):
        inbox._push(Incoming(f"k/{i}", b"x"))
    assert inbox.overflow == 1
    assert [item.key for item in inbox.drain()] == ["k/0", "k/1"]


def test_a_certificate_out_of_date_is_refused_naming_its_file(tmp_path):
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization

    from relloc.runtime.certs import load_team_certs, make_team_certs

    certs = make_team_certs(tmp_path / "certs", "t", ["a"])
    with pytest.raises(ConfigError, match=r"'stranger'.*certs"):
        certs.certificate("stranger")
    ca_key = serialization.load_pem_private_key((certs.folder / "ca.key").read_bytes(), None)
    path = certs.certificate("a")
    cert = x509.load_pem_x509_certificate(path.read_bytes())
    now = datetime.datetime.now(datetime.UTC)
    expired = (
        x509.CertificateBuilder(extensions=list(cert.extensions))
        .subject_name(cert.subject)
        .issuer_name(cert.issuer)
        .public_key(cert.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(days=30))
        .not_valid_after(now - datetime.timedelta(days=1))
        .sign(ca_key, hashes.SHA256())  # type: ignore[arg-type]
    )
    path.write_bytes(expired.public_bytes(serialization.Encoding.PEM))
    with pytest.raises(DataError, match=rf"{path.name}: valid only from .* UTC"):
        load_team_certs(certs.folder)


def test_a_partition_of_nobody_is_refused():
    from relloc.runtime.faults import Partition

    with pytest.raises(ConfigError, match=r"partition\.side: list at least one robot"):
        Partition(side=(), start_s=0.0, end_s=1.0)


def test_a_held_message_whose_sender_says_nothing_more_is_released_at_its_deadline():
    from relloc.runtime.faults import FaultSettings, LinkEmulator

    link = LinkEmulator(
        "me", FaultSettings(reorder=0.999, reorder_hold_s=0.5), np.random.default_rng(0)
    )
    link.admit("only", "mate", 1.0)
    assert link.counters.reordered == 1 and link.release(1.4) == []
    assert link.release(1.5) == ["only"]
    assert link.release(10.0) == []


# ------------------------------------------------------------------ team sources
def test_a_team_source_that_is_nothing_and_a_negative_seed_are_refused(tmp_path):
    from relloc.runtime.scenario import check_source, run_seeds

    with pytest.raises(ConfigError, match=r"team source: '.*nowhere' is neither"):
        check_source(str(tmp_path / "nowhere"))
    # a mistyped reproduction is told the ones there are
    with pytest.raises(
        ConfigError,
        match=r"'desilva2016' is neither 'default', a reproduction \(desilva2015, "
        r"desilva2015-kidnapped, sharma2013\), a scenario file nor a dataset folder",
    ):
        check_source("desilva2016")
    with pytest.raises(ConfigError, match=r"--seed: -1 must be ≥ 0"):
        run_seeds(-1)


def test_readings_of_a_robot_off_the_roster_and_a_bad_live_source_are_refused():
    from relloc.runtime.sources import LiveSource, MeasurementBatch, batch_rows

    batch = MeasurementBatch(
        t=np.array([0.1]), targets=("ghost",), z=np.ones((1, 3)), sigma=np.ones((1, 3))
    )
    with pytest.raises(DataError, match=r"a: readings of \['ghost'\], who are not on the roster"):
        batch_rows(batch, ("a", "b"), "a")
    with pytest.raises(DataError, match="LiveSource a: odometry_sigma must be 4 finite"):
        LiveSource("a", odometry_sigma=[0.1, 0.1, np.nan, 0.1])
    live = LiveSource("a", odometry_sigma=[0.1] * 4)
    stamps, u = live.odometry(0.0, 1.0)  # nothing pushed: empty, of the usual shapes
    assert stamps.shape == (0,) and u.shape == (0, 4)


def test_a_series_the_distributed_run_never_recorded_counts_as_in_process_only():
    from relloc.runtime.summary import agreement

    t = np.array([0.0, 0.5, 1.0])
    ref = BeliefSeries(
        owner="a", subject="b", frame="a", t=t, mean=np.zeros((3, 4)),
        cov=np.tile(np.eye(4), (3, 1, 1)), age=t,
    )  # fmt: skip
    agree = agreement(Estimates(estimator="plkf"), Estimates(estimator="plkf", beliefs=(ref,)))
    assert agree["pairs"] == {ref.label: {"common": 0, "only_in_process": 3}}


# ------------------------------------------------------------------ world files
@pytest.fixture(scope="module")
def world_arrays(tmp_path_factory) -> dict[str, np.ndarray]:
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    for _ in range(3):
        world.step(np.tile([0.1, 0.0], (3, 1)), np.zeros((1, 2)))
    path = tmp_path_factory.mktemp("world") / "world.npz"
    save_world(world, path)
    with np.load(path) as f:
        return {k: f[k] for k in f.files}


def test_a_world_file_with_an_encrypted_member_is_refused_naming_it(tmp_path, world_arrays):
    path = tmp_path / "locked.npz"
    np.savez(path, **world_arrays)
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        start = z.start_dir  # type: ignore[attr-defined]
    assert data[start : start + 4] == b"PK\x01\x02"
    data[start + 8] |= 0x01  # the first member's "encrypted" flag, in the central directory
    path.write_bytes(bytes(data))
    with pytest.raises(
        DataError, match=r"locked\.npz: not a world file \(unsupported zip: .*encrypted"
    ):
        load_world(path, SC)


def test_a_world_file_longer_than_the_run_or_with_a_nan_formation_error_is_refused(
    tmp_path, world_arrays
):
    assert set(world_arrays) == {"truth", "commands", "formation_error"} | {
        f"m_{n}" for n in MEASUREMENT_FIELDS
    }
    long = dict(world_arrays, commands=np.zeros((SC.n_steps + 1, len(ROSTER), 4)))
    np.savez(tmp_path / "long.npz", **long)
    with pytest.raises(DataError, match=rf"long\.npz: commands: {SC.n_steps + 1} ticks, more"):
        load_world(tmp_path / "long.npz", SC)
    error = world_arrays["formation_error"].copy()
    error[0, 0, 0] = np.nan
    np.savez(tmp_path / "nan.npz", **dict(world_arrays, formation_error=error))
    with pytest.raises(DataError, match=r"nan\.npz: formation_error: holds NaN or inf"):
        load_world(tmp_path / "nan.npz", SC)


# ------------------------------------------------------------------ a robot's inputs
def _drone(session: object, **settings: object) -> RobotProcess:
    """Drone ``D_1``'s process, every teammate present, its publishers on a real Zenoh session."""
    s = RobotSettings(team=TEAM, robot="D_1", transport=TransportSettings(), **settings)  # type: ignore[arg-type]
    proc = RobotProcess(s, SC, DroneRole(SC, 0))
    for kind in ("rows", "odom", "cmd", "est", "stats"):
        proc._pubs[kind] = declare_publisher(session, keys.robot_key(TEAM, "xD_1", kind))
    for member in (keys.CLOCK_ID, *ROSTER):
        if member != "D_1":
            proc._handle(Incoming(keys.alive_key(TEAM, member), b"", "joined"))  # type: ignore[arg-type]
    return proc


def _sense_tick0(proc: RobotProcess) -> None:
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    body = sense_body(world, 3, 0, drone=0)
    key = keys.clock_key(TEAM, "sense")
    proc._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, 0.0, body)))
    assert proc._tick is not None and proc._tick.k == 0


def test_a_robot_waits_for_the_leaders_command_then_counts_an_input_timeout(session):
    proc = _drone(session, input_timeout_s=0.05)
    _sense_tick0(proc)
    proc._progress()
    assert proc._tick is not None and proc.counters["input_timeouts"] == 0  # still waiting
    time.sleep(0.06)
    proc._progress()
    assert proc._tick is None and proc.counters["input_timeouts"] == 1
    assert proc.counters["sent.cmd"] == 1


def test_a_robot_acts_at_once_once_the_world_has_left(session):
    proc = _drone(session)  # a 10 s input timeout: only the world's leaving ends the wait
    _sense_tick0(proc)
    proc._progress()
    assert proc._tick is not None
    proc._handle(Incoming(keys.alive_key(TEAM, keys.CLOCK_ID), b"", "left"))  # type: ignore[arg-type]
    proc._progress()
    assert proc._tick is None and proc.counters["inputs_missing_at_end"] == 1
    assert proc.counters["input_timeouts"] == 0


def test_rejected_duplicate_and_late_deliveries_are_counted_and_do_not_hold_back_the_rest(
    session,
):
    proc = _drone(session)
    _sense_tick0(proc)

    def rows(sender: str, seq: int, stamp: float, kind: str = "range") -> object:
        body = {"stamps": [stamp], "kinds": [kind], "subjects": ["D_1"], "landmarks": [-1.0]}
        body |= {"sensors": [0.0], "values": [1.0], "sigmas": [0.1]}
        key = keys.robot_key(TEAM, sender, "rows")
        return admit(key, encode("rows", sender, seq, 0.1, body), roster=ROSTER)

    good, late = rows("R_1", 0, 0.1), rows("R_2", 0, 0.0)
    bad = rows("R_1", 1, 0.1, kind="bogus")  # decodes, and is refused when filed
    proc._deliver([bad, good, good, late], 0.1)  # type: ignore[list-item]
    assert proc.counters["rejected"] == 1 and proc.counters["rejected.malformed"] == 1
    assert proc.counters["duplicates"] == 1 and proc.counters["late_rows"] == 1
    assert proc.counters["delivered.rows"] == 3  # the refused one is counted as it is filed
    assert [r.t.tolist() for r in proc.heard.rows["R_1"]] == [[0.1]]
    assert [r.t.tolist() for r in proc.heard.rows["R_2"]] == [[]]


def test_a_robot_off_the_team_and_a_sense_before_the_last_tick_is_done_are_refused(session):
    with pytest.raises(ConfigError, match=r"--robot: 'R_9' is not in the team"):
        RobotProcess(
            RobotSettings(team=TEAM, robot="R_9", transport=TransportSettings()),
            SC,
            DroneRole(SC, 0),
        )
    proc = _drone(session)
    _sense_tick0(proc)  # waits for the leader's command
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    world.step(np.tile([0.1, 0.0], (3, 1)), np.zeros((1, 2)))
    body = sense_body(world, 3, 1, drone=0)
    t = float(world.times[1])
    proc._handle(
        Incoming(keys.clock_key(TEAM, "sense"), encode("sense", keys.CLOCK_ID, 1, t, body))
    )
    assert proc.counters["rejected.bad_tick"] == 1 and proc._tick.k == 0  # type: ignore[union-attr]


# ------------------------------------------------------------------ the team's report
def _summary_with_a_fault() -> dict:
    outcome = {"fault": "kill flyer@1", "window_s": [1.0, 3.0], "position_rmse_before_m": 0.1}
    outcome |= {"tracks_kept": 1, "note": "the track was re-found"}
    return {
        "scenario": "s", "seed": 1,
        "messages": {"per_robot": {}, "team": {"transport_loss_rate": None}},
        "processes": {"robots": 0, "kills": 1, "restarts": 0}, "simulated_s": 1.0, "wall_s": 2.0,
        "secure": False, "rejected_by_reason": {}, "team": {}, "in_process": {"team": {}},
        "agreement": {"max_abs_mean_diff": 0.0, "max_abs_cov_diff": 0.0, "tolerance": 1e-9,
                      "within_tolerance": True},
        "fault_outcomes": [outcome],
    }  # fmt: skip


def test_the_team_report_and_terminal_summary_show_each_fault(capsys):
    from relloc.runtime.team import print_summary, runtime_markdown

    text = runtime_markdown(_summary_with_a_fault())
    assert "### Faults" in text and "- kill flyer@1: the track was re-found" in text
    row = next(line for line in text.splitlines() if line.startswith("| kill flyer@1"))
    assert "0.1" in row
    print_summary(_summary_with_a_fault())
    out = " ".join(capsys.readouterr().out.split())  # the console wraps at its width
    assert "fault kill flyer@1 (1–3 s): position RMSE 0.1 → — → — m" in out
    assert "tracks kept 1; the track was re-found" in out
    assert "largest |Δ| of a belief mean entry 0 (tolerance 1e-09; within tolerance)" in out
