"""The ROS writers: the MCAP file read back with two readers (``mcap_ros2`` and ``rosbags``) and
the TUM files scored by the real ``evo_ape``, every value checked against the estimates."""

from __future__ import annotations

import math
import re
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from export_helpers import T, estimates, evo_ape, have_evo, recording, yaw_of
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from relloc.core.angles import wrap_angle
from relloc.errors import ConfigError, DataError
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.export.mcap_file import stamp_ns
from relloc.pipeline.export.poses import (
    POSE_MAPS,
    UNKNOWN,
    UNKNOWN_VARIANCE,
    pose_set,
    ros_names,
    ros_token,
    select_covariance,
)
from relloc.pipeline.frames import frame

pytest.importorskip("mcap_ros2", reason="extra 'ros' (mcap-ros2-support) is not installed")
pytest.importorskip("rosbags", reason="extra 'ros' (rosbags) is not installed")

U = UNKNOWN_VARIANCE


def expected_poses(est, rec):  # type: ignore[no-untyped-def]
    """What each topic must hold, written out by hand per frame (not through POSE_MAPS):
    ``topic -> (frame_id, t, position (K,3), yaw (K,), cov (K,6,6), truth position, truth yaw)``."""
    out = {}
    for s in est.beliefs:
        if s.frame == "range_bias":
            continue
        k = s.t.size
        truth = frame(s.frame).truth(rec, s.owner, s.subject, s.t)
        cov = np.zeros((k, 6, 6))
        P = s.cov
        owner = {"3": "r3"}.get(s.owner, s.owner)
        subject = {"3": "r3"}.get(s.subject, s.subject)
        topic = f"/{owner}/estimates/{subject}" + (f"/{s.track}" if s.track else "")
        if s.frame == "relative_pose4":
            cov[:, :3, :3] = P[:, :3, :3]
            cov[:, :3, 5] = P[:, :3, 3]
            cov[:, 5, :3] = P[:, 3, :3]
            cov[:, 5, 5] = P[:, 3, 3]
            cov[:, 3, 3] = cov[:, 4, 4] = U
            out[topic] = (
                f"{owner}/base_link",
                s.t,
                s.mean[:, :3],
                s.mean[:, 3],
                cov,
                truth[:, :3],
                truth[:, 3],
            )
        elif s.frame == "world_pose2":
            cov[:, :2, :2] = P[:, :2, :2]
            cov[:, :2, 5] = P[:, :2, 2]
            cov[:, 5, :2] = P[:, 2, :2]
            cov[:, 5, 5] = P[:, 2, 2]
            cov[:, 2, 2] = cov[:, 3, 3] = cov[:, 4, 4] = U
            pos = np.column_stack([s.mean[:, :2], np.zeros(k)])
            tpos = np.column_stack([truth[:, :2], np.zeros(k)])
            out[topic] = ("map", s.t, pos, s.mean[:, 2], cov, tpos, truth[:, 2])
        else:  # airground_follower: (r_x, r_y, θ_i, θ_0)
            cov[:, :2, :2] = P[:, :2, :2]
            cov[:, :2, 5] = P[:, :2, 3]
            cov[:, 5, :2] = P[:, 3, :2]
            cov[:, 5, 5] = P[:, 3, 3]
            cov[:, 2, 2] = cov[:, 3, 3] = cov[:, 4, 4] = U
            pos = np.column_stack([s.mean[:, :2], np.zeros(k)])
            tpos = np.column_stack([truth[:, :2], np.zeros(k)])
            fid = f"{owner}/common"
            out[topic] = (fid, s.t, pos, s.mean[:, 3], cov, tpos, truth[:, 3])
            heading = np.zeros((k, 6, 6))
            heading[:, 5, 5] = P[:, 2, 2]
            heading[:, 3, 3] = heading[:, 4, 4] = U
            zero = np.zeros((k, 3))
            out[topic + "/observer_heading"] = (
                fid,
                s.t,
                zero,
                s.mean[:, 2],
                heading,
                zero,
                truth[:, 2],
            )
    return out


@pytest.fixture(scope="module")
def written(tmp_path_factory):  # type: ignore[no-untyped-def]
    d = tmp_path_factory.mktemp("export")
    rec = recording()
    est = estimates(np.random.default_rng(20261201))
    section = export_estimates(
        ExportRequest(mcap=d / "out.mcap", tum=d / "tum"), est, rec, run="hand", settle_s=1.0
    )
    return d, rec, est, section


def by_topic_mcap_ros2(path: Path):  # type: ignore[no-untyped-def]
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    topics = defaultdict(list)
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages(log_time_order=False):
            topics[channel.topic].append((message.log_time, msg, schema.name))
    return topics


def by_topic_rosbags(path: Path):  # type: ignore[no-untyped-def]
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    reader = McapReader(path)
    reader.open()
    try:
        for c in reader.connections:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        topics = defaultdict(list)
        for c, ns, raw in reader.messages(reader.connections):
            topics[c.topic].append((ns, store.deserialize_cdr(raw, c.msgtype), c.msgtype))
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    finally:
        reader.close()
    return topics, qos


def check_topics(topics, est, rec):  # type: ignore[no-untyped-def]
    """Every estimate, truth and tf message against the values they were made from."""
    for topic, (fid, t, pos, yaw, cov, tpos, tyaw) in expected_poses(est, rec).items():
        msgs = topics[topic]
        assert [m[2] for m in msgs] == ["geometry_msgs/msg/PoseWithCovarianceStamped"] * t.size
        assert [m[0] for m in msgs] == [round(x * 1e9) for x in t]
        for k, (ns, msg, _) in enumerate(msgs):
            st = msg.header.stamp
            assert st.sec * 1_000_000_000 + st.nanosec == ns
            assert msg.header.frame_id == fid
            p = msg.pose.pose.position
            np.testing.assert_array_equal([p.x, p.y, p.z], pos[k])
            assert yaw_of(msg.pose.pose.orientation) == pytest.approx(wrap_angle(yaw[k]), abs=1e-12)
            np.testing.assert_array_equal(np.asarray(msg.pose.covariance).reshape(6, 6), cov[k])
        truth_msgs = topics[topic.replace("/estimates/", "/ground_truth/", 1)]
        assert [m[0] for m in truth_msgs] == [round(x * 1e9) for x in t]
        for k, (_, msg, typ) in enumerate(truth_msgs):
            assert typ == "geometry_msgs/msg/PoseStamped" and msg.header.frame_id == fid
            p = msg.pose.position
            np.testing.assert_allclose([p.x, p.y, p.z], tpos[k], rtol=0, atol=1e-12)
            assert wrap_angle(yaw_of(msg.pose.orientation) - tyaw[k]) == pytest.approx(0, abs=1e-12)
    tf = topics["/tf"]
    assert [m[0] for m in tf] == [round(x * 1e9) for x in T]
    for ns, msg, typ in tf:
        assert typ == "tf2_msgs/msg/TFMessage"
        t = ns * 1e-9
        children = {x.child_frame_id: x for x in msg.transforms}
        assert set(children) == {
            "leader/base_link",
            "follower/base_link",
            "r3/base_link",
            "follower/common",
        }
        for i, name in enumerate(("leader", "follower", "r3")):
            x = children[f"{name}/base_link"]
            true = rec.truth[i].at(t)[0]
            assert x.header.frame_id == "map"
            tr = x.transform.translation
            np.testing.assert_allclose([tr.x, tr.y, tr.z], true[:3], atol=1e-9)
            assert wrap_angle(yaw_of(x.transform.rotation) - true[3]) == pytest.approx(0, abs=1e-9)
        c = children["follower/common"]
        assert c.header.frame_id == "follower/base_link"
        expected = 0.3 - rec.truth[1].at(t)[0, 3]
        assert wrap_angle(yaw_of(c.transform.rotation) - expected) == pytest.approx(0, abs=1e-9)
    for i, name in enumerate(("leader", "follower", "r3")):
        gt = topics[f"/ground_truth/{name}"]
        assert [m[0] for m in gt] == [round(x * 1e9) for x in T]
        true = rec.truth[i].at(T)
        for k, (_, msg, _) in enumerate(gt):
            assert msg.header.frame_id == "map"
            p = msg.pose.position
            np.testing.assert_array_equal([p.x, p.y, p.z], true[k, :3])
            assert wrap_angle(yaw_of(msg.pose.orientation) - true[k, 3]) == pytest.approx(
                0, abs=1e-12
            )


def test_mcap_reads_back_with_mcap_ros2(written):  # type: ignore[no-untyped-def]
    d, rec, est, section = written
    from mcap.reader import make_reader

    with open(d / "out.mcap", "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert all("offered_qos_profiles" in c.metadata for c in summary.channels.values())
        assert summary.statistics.message_count == section["mcap"]["messages"]
    topics = by_topic_mcap_ros2(d / "out.mcap")
    check_topics(topics, est, rec)
    assert {t: len(v) for t, v in topics.items()} == section["mcap"]["topics"]


def test_mcap_reads_back_with_rosbags(written):  # type: ignore[no-untyped-def]
    d, rec, est, _ = written
    topics, qos = by_topic_rosbags(d / "out.mcap")
    check_topics(topics, est, rec)
    assert all(v == [] for v in qos.values())


def test_skips_are_counted_and_names_are_ros_tokens(written):  # type: ignore[no-untyped-def]
    _, _, _, section = written
    assert section["skipped"] == {"frame without a pose meaning: range_bias": T.size}
    assert section["series"]["3->leader#bank/k2"]["topic"] == "/r3/estimates/leader/bank/k2"
    assert ros_token("robot 1") == "robot_1" and ros_token("") == "r"
    with pytest.raises(ConfigError, match="both become"):
        ros_names(["a b", "a_b"])


def test_non_finite_records_are_skipped_and_counted():  # type: ignore[no-untyped-def]
    import dataclasses

    rec = recording()
    est = estimates(np.random.default_rng(1))
    s = est.beliefs[0]
    mean = s.mean.copy()
    mean[3] = np.nan
    bad = dataclasses.replace(est, beliefs=(dataclasses.replace(s, mean=mean), *est.beliefs[1:]))
    poses = pose_set(bad, rec)
    assert poses.skipped["non-finite belief"] == 1
    assert poses.poses[0].t.size == T.size - 1


def test_stamps_outside_ros_time_are_a_data_error():
    assert stamp_ns(1.5, "x") == 1_500_000_000
    for t in (-0.1, math.nan, 2.0**31):
        with pytest.raises(DataError, match="cannot be a ROS stamp"):
            stamp_ns(t, "leader->3")


def test_a_folder_as_mcap_file_is_a_config_error(tmp_path):  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match="is a folder"):
        export_estimates(
            ExportRequest(mcap=tmp_path), estimates(np.random.default_rng(2)), recording(), run="x"
        )


def test_an_existing_file_of_another_kind_or_a_link_is_not_replaced(tmp_path, written):  # type: ignore[no-untyped-def]
    """``--mcap victim.txt`` once overwrote the file with MCAP bytes, and ``--mcap
    OUT/summary.json`` on a fresh ``OUT`` collided with the run's own summary."""
    victim = tmp_path / "victim.mcap"
    victim.write_text("keep me")
    with pytest.raises(ConfigError, match="exists and is not an MCAP file"):
        ExportRequest(mcap=victim)
    for name in ("victim.txt", "fresh/summary.json", "out"):
        with pytest.raises(ConfigError, match=r"does not end in \.mcap"):
            ExportRequest(mcap=tmp_path / name)
    link = tmp_path / "link.mcap"
    link.symlink_to(victim)
    with pytest.raises(ConfigError, match="is a link"):
        ExportRequest(mcap=link)
    assert victim.read_text() == "keep me"
    ExportRequest(mcap=written[0] / "out.mcap")  # an earlier export may be replaced


def test_tum_files_hold_the_poses(written):  # type: ignore[no-untyped-def]
    _, rec, est, section = written
    expected = expected_poses(est, rec)
    pairs = section["tum"]["pairs"]
    assert set(pairs) == {"leader->3", "3->leader#bank/k2", "team->follower", "follower->leader"}
    for label, files in pairs.items():
        topic = section["series"][label]["topic"]
        _, t, pos, yaw, _, tpos, tyaw = expected[topic]
        for path, p, y in ((files["estimate"], pos, yaw), (files["truth"], tpos, tyaw)):
            rows = np.loadtxt(path, comments="#")
            np.testing.assert_allclose(rows[:, 0], t, rtol=0, atol=1e-9)
            np.testing.assert_array_equal(rows[:, 1:4], p)  # every digit written
            q = rows[:, 4:]
            np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
            assert np.all(q[:, :2] == 0)
            np.testing.assert_allclose(
                wrap_angle(2 * np.arctan2(q[:, 2], q[:, 3]) - y), 0, atol=1e-12
            )


@pytest.mark.skipif(not have_evo(), reason="evo (extra 'bench') is not installed next to Python")
def test_evo_ape_rmse_is_relloc_position_rmse(written, tmp_path):  # type: ignore[no-untyped-def]
    """The real evo_ape, no alignment, on every pair: its RMSE is relloc's position RMSE."""
    _, _, _, section = written
    for label, files in section["tum"]["pairs"].items():
        stats = evo_ape(Path(files["truth"]), Path(files["estimate"]), tmp_path)
        ours = section["series"][label]["position_rmse_m"]
        assert stats["rmse"] == pytest.approx(ours, rel=1e-9), label


# Property tests (hypothesis, derandomized).
_TOKEN_RULE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.text(max_size=12))
def test_any_name_becomes_a_valid_ros_token(name):  # type: ignore[no-untyped-def]
    token = ros_token(name)
    assert _TOKEN_RULE.match(token), token
    assert ros_token(token) == token  # tokens are left alone


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    st.sampled_from(sorted(POSE_MAPS)),
    arrays(np.float64, (3, 4, 4), elements=st.floats(-3, 3, allow_subnormal=False)),
)
def test_ros_covariance_is_the_selected_block_and_stays_psd(name, a):  # type: ignore[no-untyped-def]
    for m in POSE_MAPS[name]:
        d = frame(name).dim
        P = a[:, :d, :d] @ np.swapaxes(a[:, :d, :d], 1, 2)
        C = select_covariance(P, m.dofs)
        np.testing.assert_array_equal(C, np.swapaxes(C, 1, 2))
        assert np.all(np.linalg.eigvalsh(C) >= -1e-9 * (1 + np.abs(P).max()))
        for i, si in enumerate(m.dofs):
            for j, sj in enumerate(m.dofs):
                if si >= 0 and sj >= 0:
                    np.testing.assert_array_equal(C[:, i, j], P[:, si, sj])
                elif i == j:
                    assert np.all(C[:, i, i] == (U if si == UNKNOWN else 0.0))
                else:
                    assert np.all(C[:, i, j] == 0.0)
