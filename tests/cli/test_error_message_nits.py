"""Error messages a user reads name the option to fix and carry no empty or internal parts:
``--kill`` without ``@``, a bag folder run without ``--map``, a ``--pair`` robot the dataset
lacks; and ``bag inspect`` shows no time span for a topic without messages."""

from __future__ import annotations

import pytest

from relloc.cli import main
from relloc.cli.bag import topic_table
from relloc.datasets.rosbag import TopicInfo
from relloc.errors import ConfigError
from relloc.runtime.faults import parse_robot_event


def test_a_robot_event_without_at_says_what_is_missing():
    with pytest.raises(ConfigError) as info:
        parse_robot_event("aerial1", "--kill")
    message = str(info.value)
    assert not message.endswith("()") and "()" not in message
    assert message == "--kill: expected ROBOT@SECONDS, got 'aerial1' (missing '@')"


def test_team_up_kill_without_at_ends_with_the_reason(tmp_path, capsys):
    argv = ["team", "up", "default", "--out", str(tmp_path / "x"), "--kill", "aerial1"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--kill" in err and "missing '@'" in err and "()" not in err


@pytest.mark.parametrize("name", ["bag_folder", "rec.mcap", "rec.db3"])
def test_run_of_a_bag_without_map_asks_for_map(tmp_path, capsys, name):
    bag = tmp_path / name
    if name == "bag_folder":
        bag.mkdir()
    else:
        bag.write_bytes(b"\0")
    assert main(["run", str(bag), "--out", str(tmp_path / "y")]) == 2
    err = capsys.readouterr().err
    assert "needs --map" in err and "tiers_cooperative" in err
    assert "cannot read scenario file" not in err and "Is a directory" not in err
    assert not (tmp_path / "y").exists()


def test_a_pair_robot_missing_from_the_dataset_names_the_option(tmp_path, mrclam_run6_cut):
    from relloc.experiments.wanasinghe2014_mrclam import ReplaySettings, prepare_replay

    cut = mrclam_run6_cut(tmp_path / "cut", robots=(1, 2, 3))
    with pytest.raises(ConfigError) as info:
        prepare_replay(ReplaySettings(dataset=cut, observer=1, observed=9))
    message = str(info.value)
    assert message.startswith("--pair 1,9: robot(s) [9]")
    assert "ReplaySettings" not in message


def test_bag_inspect_shows_no_span_for_a_topic_without_messages():
    infos = [
        TopicInfo("/a/odom", "nav_msgs/msg/Odometry", 0, 0.0, 0.0),
        TopicInfo("/b/odom", "nav_msgs/msg/Odometry", 21, 1.0, 2.0),
    ]
    lines = topic_table(infos).splitlines()
    assert lines[1].split()[-1] == "—" and "0.00–0.00" not in lines[1]
    assert lines[2].split()[-2:] == ["20.00", "1.00–2.00"]
