"""The air-ground team's protocol (``sense`` from the world, ``cmd`` to it): admission by role,
validation of every field, the world's and a robot's handling of bad messages, the truth file."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.core.recording import measurement_rows
from relloc.errors import DataError
from relloc.runtime import keys
from relloc.runtime.admission import admit
from relloc.runtime.airground import (
    LeaderRole,
    Received,
    RobotProcess,
    RobotSettings,
    WorldProcess,
    WorldSettings,
    load_world,
    save_world,
    sense_body,
)
from relloc.runtime.messages import SCHEMA_VERSION, MessageRejected, encode
from relloc.runtime.transport import Incoming, TransportSettings
from relloc.sim.airground import AirGroundScenario, AirGroundWorld, robot_names

TEAM = "t"
SC = AirGroundScenario(offsets=((0.5, 0.5), (-0.5, 0.5)), offset_frame="global", duration=0.5)
ROSTER = robot_names(SC)  # R_0, R_1, R_2, D_1
TRANSPORT = TransportSettings()


def _world() -> AirGroundWorld:
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    for _ in range(3):  # a camera frame and UWB ranges at t = 0.05 and 0.15
        world.step(np.tile([0.1, 0.0], (3, 1)), np.zeros((1, 2)))
    return world


def _sense(world: AirGroundWorld, robot: int, **changes: object) -> dict:
    drone = robot - 3 if robot >= 3 else None
    return sense_body(world, robot, world.k, drone=drone) | changes


def _admit(kind: str, sender: str, body: dict, key: str, t: float = 0.15):
    return admit(key, encode(kind, sender, 0, t, body), roster=ROSTER)


def test_sense_and_cmd_round_trip_on_their_own_keys_only():
    world = _world()
    body = _sense(world, 3)
    msg = _admit("sense", keys.CLOCK_ID, body, keys.clock_key(TEAM, "sense"))
    assert msg.body["target"] == "D_1" and msg.body["position"].shape == (3,)
    np.testing.assert_array_equal(msg.body["position"], world.drone_position(0))
    cmd = {"k": 3, "u": np.array([0.1, 0.0, 0.0, 0.02])}
    assert _admit("cmd", "R_1", cmd, keys.robot_key(TEAM, "R_1", "cmd")).body["k"] == 3
    cases = [
        # a robot claiming the world's readings, on the world's key
        ("sense", "R_1", body, keys.clock_key(TEAM, "sense"), "spoofed"),
        # a command from the infrastructure sender, or under another robot's key
        ("cmd", keys.CLOCK_ID, cmd, keys.clock_key(TEAM, "ctl"), "wrong_kind"),
        ("cmd", "R_2", cmd, keys.robot_key(TEAM, "R_1", "cmd"), "spoofed"),
        (
            "sense",
            keys.CLOCK_ID,
            body | {"target": "nobody"},
            keys.clock_key(TEAM, "sense"),
            "unknown_target",
        ),
        (
            "sense",
            keys.CLOCK_ID,
            body | {"fix_subject": "nobody", "fix": np.zeros(2)},
            keys.clock_key(TEAM, "sense"),
            "unknown_target",
        ),
        (
            "sense",
            keys.CLOCK_ID,
            body | {"fix_subject": "R_0", "fix": np.zeros(1)},
            keys.clock_key(TEAM, "sense"),
            "shape",
        ),
        ("sense", keys.CLOCK_ID, body | {"k": 99}, keys.clock_key(TEAM, "sense"), "malformed"),
        (
            "sense",
            keys.CLOCK_ID,
            body | {"position": np.zeros(2)},
            keys.clock_key(TEAM, "sense"),
            "shape",
        ),
    ]
    for kind, sender, b, key, reason in cases:
        with pytest.raises(MessageRejected) as exc:
            admit(key, encode(kind, sender, 0, 0.1, b, max_bytes=10**6), roster=ROSTER)
        assert exc.value.reason == reason, (kind, sender, key)
    with pytest.raises(MessageRejected) as exc:  # no such robot stream
        admit(f"relloc/{TEAM}/robot/R_1/sense", encode("sense", "R_1", 0, 0.1, body), roster=ROSTER)
    assert exc.value.reason == "unknown_key"


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    k=st.integers(min_value=0, max_value=2**40),
    dt=st.floats(allow_nan=True, allow_infinity=True),
    fix=st.lists(st.floats(allow_nan=True), max_size=5),
    subject=st.sampled_from(["", "R_0", "R_2", "D_1", "zz"]),
    position=st.lists(st.floats(), max_size=4),
)
def test_any_sense_body_is_accepted_or_rejected_with_a_reason(k, dt, fix, subject, position):
    body = _sense(_world(), 1) | {"k": k, "dt": dt, "fix_subject": subject}
    body |= {"fix": fix, "position": position}
    raw = {
        "v": SCHEMA_VERSION,
        "type": "sense",
        "sender": keys.CLOCK_ID,
        "seq": 0,
        "t": 0.1,
        "wall_ns": 1,
    }
    raw |= {n: (v.tolist() if isinstance(v, np.ndarray) else v) for n, v in body.items()}
    payload = msgpack.packb(raw, use_bin_type=True)
    try:
        msg = admit(keys.clock_key(TEAM, "sense"), payload, roster=ROSTER)
    except MessageRejected as exc:
        assert exc.reason
        return
    assert msg.body["k"] <= msg.body["n"] and msg.body["fix"].size in (0, 2, 3)


def test_the_world_counts_stale_spoofed_and_foreign_commands_and_keeps_the_good_one():
    world = _world()
    proc = WorldProcess(WorldSettings(team=TEAM, transport=TRANSPORT), world)
    proc._k = 3
    good = {"k": 3, "u": np.array([0.1, 0.0, 0.0, 0.02])}
    items = [
        (keys.robot_key(TEAM, "R_1", "cmd"), encode("cmd", "R_1", 0, 0.15, good)),
        (keys.robot_key(TEAM, "R_2", "cmd"), encode("cmd", "R_2", 0, 0.1, good | {"k": 2})),
        (keys.robot_key(TEAM, "R_0", "cmd"), encode("cmd", "R_1", 1, 0.15, good)),
        (keys.robot_key(TEAM, "X", "cmd"), encode("cmd", "X", 0, 0.15, good)),
        (
            keys.robot_key(TEAM, "R_0", "odom"),
            encode("odom", "R_0", 0, 0.15, {"stamps": [0.15], "u": [[0.1, 0, 0, 0]]}),
        ),
        (keys.robot_key(TEAM, "R_0", "cmd"), b"\x93garbage"),
    ]
    for key, payload in items:
        proc._handle(Incoming(key, payload))
    assert set(proc._cmds) == {"R_1"}
    np.testing.assert_array_equal(proc._cmds["R_1"], good["u"])
    assert proc.report.rejected_by_reason == {
        "stale": 1,
        "spoofed": 1,
        "unknown_sender": 1,
        "wrong_kind": 1,
        "malformed": 1,
    }


def test_a_robot_the_world_counts_ready_is_present_whichever_token_arrives_first():
    """``ready`` and ``alive`` come through two liveliness subscribers in no set order: a
    restarted robot whose ``ready`` is seen first is already among the robots whose command the
    world waits for (its first tick is not stepped over with a zero command counted nowhere),
    and a robot whose ``alive`` token left is not ready even if its ``ready`` token's departure
    comes later (a restart is not taken as done on a dead process' token)."""
    proc = WorldProcess(WorldSettings(team=TEAM, transport=TRANSPORT), _world())

    def token(kind: str, robot: str, presence: str) -> None:
        key = f"relloc/{TEAM}/{kind}/{robot}"
        proc._handle(Incoming(key, b"", presence))  # type: ignore[arg-type]

    token("ready", "R_2", "joined")
    assert proc.roll.ready == proc.roll.present == {"R_2"}
    token("alive", "R_2", "joined")
    token("alive", "R_2", "left")  # killed
    assert not proc.roll.ready and not proc.roll.present
    token("ready", "R_2", "left")  # its ready token's departure, late
    token("ready", "R_2", "joined")  # restarted
    assert proc.roll.ready == proc.roll.present == {"R_2"}
    token("ready", "R_2", "left")
    assert proc.roll.present == {"R_2"} and not proc.roll.ready
    token("alive", "intruder", "joined")
    assert proc.roll.present == {"R_2"}


def test_the_world_resumes_after_a_restart_once_every_present_robot_is_ready_anew(session):
    """A teammate that has not yet seen a restarted robot's ``alive`` token may not know its
    subscriptions: what it publishes for the next tick would not reach the robot, which would
    wait ``input_timeout_s`` for it while the world waits ``cmd_timeout_s`` for its command
    (once counted 29 commands of 30). So the world waits, beyond the restarted robot's
    ``ready``, for every present robot's ``ready`` token declared since the announcement (each
    renews its own on seeing the restarted one), and not for the tokens they held before."""
    from relloc.runtime.faults import RobotEvent
    from relloc.runtime.transport import Inbox, declare_publisher

    proc = WorldProcess(WorldSettings(team=TEAM, transport=TRANSPORT), _world())
    proc._pubs["ctl"] = declare_publisher(session, keys.clock_key("unheard", "ctl"))
    others = set(ROSTER) - {"R_2"}
    proc.roll.present, proc.roll.ready = set(others), set(others)  # R_2 was killed
    inbox = Inbox()

    def token(kind: str, robot: str, presence: str) -> None:
        inbox._push(Incoming(f"relloc/{TEAM}/{kind}/{robot}", b"", presence))  # type: ignore[arg-type]

    token("alive", "R_2", "joined")
    token("ready", "R_2", "joined")  # the restarted robot has seen its teammates
    for robot in sorted(others):  # each teammate has seen the restarted robot
        token("ready", robot, "left")
        token("ready", robot, "joined")
    proc._robot_event(inbox, "restart", RobotEvent(robot="R_2", at_s=1.0))
    assert proc.report.events[-1]["completed"]
    assert not inbox.drain()  # every renewed token was waited for
    assert proc.roll.present == proc.roll.ready == set(ROSTER)


def test_a_robot_renews_its_ready_token_when_a_teammate_appears_after_it_was_ready(session):
    """A robot declares ``ready`` once it has seen the world's and its teammates' ``alive``
    tokens, and declares it again when a teammate's token appears later (a restart): by then
    its session knows the newcomer's subscriptions. A repeated appearance changes nothing."""
    from relloc.runtime.transport import Inbox

    proc = _process("R_0", session)
    proc._session = session
    watch = Inbox()
    watch.watch_presence(session, keys.ready_wildcard(TEAM))

    def presence(robot: str, change: str) -> None:
        proc._handle(Incoming(keys.alive_key(TEAM, robot), b"", change))  # type: ignore[arg-type]
        proc._declare_ready()

    def heard() -> list[str]:
        changes = []
        while (item := watch.get(timeout=0.5)) is not None:
            assert keys.parse_presence_key(item.key) == ("ready", "R_0")
            changes.append(item.presence)
        return changes

    try:
        for member in (keys.CLOCK_ID, "R_1", "R_2"):
            presence(member, "joined")
        assert proc._ready_token is None and heard() == []
        presence("D_1", "joined")
        assert heard() == ["joined"]
        presence("R_2", "left")  # killed
        assert heard() == []
        presence("R_2", "joined")  # restarted
        assert heard() == ["left", "joined"]
        presence("R_2", "joined")
        assert heard() == []
    finally:
        if proc._ready_token is not None:
            proc._ready_token.undeclare()
        watch.close()


def test_a_follower_builds_its_filter_before_it_joins_and_a_restarted_one_starts_broad():
    """:meth:`FollowerRole.prepare` (called before the robot declares ready) builds the filter
    of a start at tick 0 with its gate quantiles; the first tick keeps it, and a follower whose
    first tick is a later one (restarted) replaces it with the broad-prior filter."""
    from relloc.core.kalman import chi2_threshold
    from relloc.core.recording import empty_measurements
    from relloc.experiments.guler2023_team import role_of, run_seed, team_case
    from relloc.runtime.airground import RESTART_SIGMAS, FollowerRole, Sensed

    case = team_case("two_drones", 0.5)
    seed = run_seed(0, "two_drones", 0)
    chi2_threshold.cache_clear()
    start = role_of(case, "R_1", seed)
    assert isinstance(start, FollowerRole)
    start.prepare()
    assert start.agent is not None and chi2_threshold.cache_info().currsize == 3
    prepared = start.agent
    sensed = Sensed(0, 0.0, empty_measurements(), np.zeros(0), None)
    start.act(sensed, Received())
    assert start.agent is prepared and start.first_k == 0
    np.testing.assert_array_equal(prepared.estimator.belief.cov, start.prior.cov)

    restarted = role_of(case, "R_1", seed)
    assert isinstance(restarted, FollowerRole)
    restarted.prepare()
    t = float(restarted.times[5])
    restarted.act(Sensed(5, t, empty_measurements(), np.zeros(0), None), Received())
    assert restarted.agent is not None and restarted.first_k == 5
    belief = restarted.agent.estimator.belief
    assert np.all(np.diag(belief.cov) > np.square(RESTART_SIGMAS) - 1e-9)


def test_a_robot_rejects_a_sense_out_of_step_and_ignores_another_robots():
    world = _world()
    proc = RobotProcess(
        RobotSettings(team=TEAM, robot="R_0", transport=TRANSPORT), SC, LeaderRole(SC)
    )
    key = keys.clock_key(TEAM, "sense")
    t = float(world.times[world.k])
    for robot, changes in ((1, {}), (0, {"n": 99}), (0, {"dt": 0.1})):
        body = _sense(world, robot, **changes)
        proc._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, t, body)))
    assert proc.counters["rejected.bad_tick"] == 2 and proc._tick is None
    # an end that overtakes the last readings is noted, not obeyed before the last tick
    end = encode("ctl", keys.CLOCK_ID, 0, t, {"action": "end", "robot": ""})
    proc._handle(Incoming(keys.clock_key(TEAM, "ctl"), end))
    assert proc._ending and not proc._done


def test_received_readings_of_a_later_tick_are_kept_for_it():
    heard = Received()
    rows = measurement_rows(
        "range",
        t=np.array([0.1, 0.2]),
        observer=np.array([0, 0]),
        target=np.array([1, 1]),
        value=np.array([1.0, 1.1]),
    )
    heard.rows["R_0"] = [rows]
    now = heard.rows_at("R_0", 0.1)
    assert [p.t.tolist() for p in now] == [[0.1]]
    assert [p.t.tolist() for p in heard.rows_at("R_0", 0.2)] == [[0.2]]
    assert heard.rows_at("R_0", 0.3) == []
    heard.leader_u = [(0.0, (0.1, 0.0)), (0.1, (0.2, 0.01))]
    assert heard.leader_command(0.05) == (0.1, 0.0)
    assert heard.leader_command(0.1) == (0.2, 0.01)
    assert Received().leader_command(1.0) is None


def test_world_file_round_trip_and_bad_file(tmp_path):
    world = _world()
    path = tmp_path / "world.npz"
    save_world(world, path)
    recording, formation_error = load_world(path, SC)
    expected = world.recording()
    np.testing.assert_array_equal(formation_error, world.formation_error)
    for a, b in zip(recording.truth, expected.truth, strict=True):
        np.testing.assert_array_equal(a.pose, b.pose)
    np.testing.assert_array_equal(recording.measurements.value, expected.measurements.value)
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(DataError, match=r"bad\.npz"):
        load_world(tmp_path / "bad.npz", SC)
    np.savez(tmp_path / "part.npz", truth=np.zeros(3))
    with pytest.raises(DataError, match="missing"):
        load_world(tmp_path / "part.npz", SC)


def _process(robot: str, session: object) -> RobotProcess:
    """Robot ``robot``'s process with publishers on a real, unconnected Zenoh session."""
    from relloc.runtime.airground import DroneRole
    from relloc.runtime.transport import declare_publisher

    role = DroneRole(SC, 0) if robot == "D_1" else LeaderRole(SC)
    proc = RobotProcess(RobotSettings(team=TEAM, robot=robot, transport=TRANSPORT), SC, role)
    for kind in ("rows", "odom", "cmd", "est", "stats"):
        proc._pubs[kind] = declare_publisher(session, keys.robot_key(TEAM, f"x{robot}", kind))
    return proc


def test_a_sense_that_does_not_fit_the_robot_is_refused_and_does_not_use_up_its_tick(session):
    """A decodable ``sense`` whose position or marker fix does not fit the team once crashed
    a drone's guidance (an empty position, a leader fix without heading, a fix of a drone),
    and one with readings that fail to decode used up the tick before it was refused, so the
    world's genuine ``sense`` of that tick was then refused. Both are refused first now."""
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    key = keys.clock_key(TEAM, "sense")
    drone = _process("D_1", session)
    genuine = sense_body(world, 3, 0, drone=0)
    hostile = [
        {"position": np.zeros(0)},
        {"fix_subject": "R_0", "fix": np.array([1.0, 2.0])},  # the leader's needs a heading
        {"fix_subject": "D_1", "fix": np.array([1.0, 2.0])},  # only UGVs carry markers
        {"fix_subject": "R_1", "fix": np.array([1.0, 2.0, 0.3])},  # a follower's has none
    ]
    for changes in hostile:
        drone._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, 0.0, genuine | changes)))
    assert drone.counters["rejected.shape"] == len(hostile) and drone._last_k is None
    follower_fix = {"fix_subject": "R_1", "fix": np.array([1.0, 2.0])}
    drone._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, 0.0, genuine | follower_fix)))
    drone._progress()
    assert drone.counters["ticks"] == 1 and drone._tick is None  # acted on tick 0

    leader = _process("R_0", session)
    good = sense_body(world, 0, 0, drone=None)
    bad_rows = {"stamps": [0.0], "kinds": ["bogus"], "subjects": [""], "landmarks": [-1.0]}
    bad_rows |= {"sensors": [0.0], "values": [1.0], "sigmas": [0.1]}
    for changes in (bad_rows, {"position": np.zeros(3)}):  # a UGV has no position sent
        leader._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, 0.0, good | changes)))
    assert leader.counters["rejected"] == 2 and leader._last_k is None
    leader._handle(Incoming(key, encode("sense", keys.CLOCK_ID, 0, 0.0, good)))
    assert leader.counters["ticks"] == 1 and leader.counters["sent.cmd"] == 1
