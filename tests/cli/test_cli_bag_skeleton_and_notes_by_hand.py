"""Small command-line functions checked on inputs worked out by hand: the robot names and radio
template of ``bag inspect``'s mapping skeleton, the note naming an earlier run's files, and
arguments of ``relloc run`` refused before any work (a negative ``--yaw-bank``, an upper-case
bag suffix, a bag's NaN ``--settle``)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from relloc.cli import _note_earlier_files, main
from relloc.cli.bag import _robot_name, mapping_skeleton
from relloc.datasets.rosbag import TopicInfo


def test_robot_names_drop_message_words_clean_odd_characters_and_count_up():
    taken: set[str] = set()
    assert _robot_name("/vrpn_client_node/pose", taken) == "robot"  # only message words
    assert _robot_name("/cf1/odom", taken) == "cf1"
    assert _robot_name("/a/cf1/pose", taken) == "cf1_2"
    assert _robot_name("/b/cf1/odom", taken) == "cf1_3"
    assert _robot_name("/x/r 1:a/odom", taken) == "r_1_a"
    assert taken == {"robot", "cf1", "cf1_2", "cf1_3", "r_1_a"}


def test_range_topics_differing_in_one_segment_share_no_template():
    infos = [TopicInfo(t, "sensor_msgs/msg/Range", 5, 0.0, 1.0) for t in ("/uwb/a1", "/uwb/a2")]
    text = mapping_skeleton(infos, name="b")
    assert "# 2 sensor_msgs/Range topics share no {a}/{b} template" in text
    assert "[uwb]" not in text


def test_a_topic_without_messages_gets_no_robot():
    infos = [
        TopicInfo("/r1/odom", "nav_msgs/msg/Odometry", 0, 0.0, 0.0),
        TopicInfo("/r2/odom", "nav_msgs/msg/Odometry", 3, 0.0, 1.0),
        TopicInfo("/mocap/r3/pose", "geometry_msgs/msg/PoseStamped", 0, 0.0, 0.0),
    ]
    text = mapping_skeleton(infos, name="b")
    assert text.count("\n[[robots]]\n") == 1 and 'odometry = "/r2/odom"' in text
    assert "r1" not in text and "r3" not in text


def _old_files(folder: Path, count: int) -> None:
    folder.mkdir()
    for k in range(count):
        (folder / f"f{k}.png").write_bytes(b"")
        os.utime(folder / f"f{k}.png", (0, 0))


@pytest.mark.parametrize(
    ("count", "tail"),
    [
        (
            5,
            "5 files under {out} from an earlier run, not this one: f0.png, f1.png, f2.png, "
            "f3.png, f4.png (remove them",
        ),
        (
            6,
            "6 files under {out} from an earlier run, not this one: f0.png, f1.png, f2.png, "
            "f3.png, f4.png and 1 more (remove them",
        ),
        (
            7,
            "7 files under {out} from an earlier run, not this one: f0.png, f1.png, f2.png, "
            "f3.png, f4.png and 2 more (remove them",
        ),
    ],
)
def test_the_earlier_files_note_names_five_and_counts_the_rest(tmp_path, capsys, count, tail):
    out = tmp_path / "out"
    _old_files(out, count)
    _note_earlier_files(out, started=1000.0)
    err = capsys.readouterr().err
    assert err.startswith("relloc: note: " + tail.format(out=out))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "--yaw-bank", "-1"], "--yaw-bank: 0 (off) or an integer in [2, 64], got -1"),
        (["run", "REC.MCAP"], "REC.MCAP: a bag, not a scenario TOML file; a bag needs --map MAP"),
        (
            ["run", "bag", "--map", "m.toml", "--settle", "nan"],
            "--settle: must be a finite number in [0, inf), got nan",
        ),
    ],
)
def test_run_refuses_before_any_work(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    assert f"relloc: error: {message}" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_a_topic_with_one_message_shows_its_one_instant_as_the_span():
    from relloc.cli.bag import topic_table

    line = topic_table([TopicInfo("/r/odom", "nav_msgs/msg/Odometry", 1, 2.5, 2.5)])
    assert line.splitlines()[1].split()[-1] == "2.50–2.50"
