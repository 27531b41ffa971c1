"""CLI smoke tests: help, version, unknown experiment, flags an experiment does not read, a bad
``--pair`` and a ``--sharing-policy`` / ``--sensing`` a team does not take → clear error and exit
code."""

import subprocess
import sys

import pytest

from relloc.cli import main


def test_help_and_version(capsys):
    assert main([]) == 2
    out = subprocess.run(
        [sys.executable, "-m", "relloc", "--version"], capture_output=True, text=True, check=True
    )
    assert "relloc" in out.stdout


def test_unknown_experiment_is_config_error(tmp_path, capsys):
    assert main(["reproduce", "no-such-paper", "--out", str(tmp_path)]) == 2
    assert "unknown experiment" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--dataset", "d"], "--dataset: sharma2013 does not read it; read by wanasinghe2014"),
        (
            ["--pair", "1,2"],
            "--pair: sharma2013 does not read it; read by wanasinghe2014, wanasinghe2014-pairs",
        ),
        (["--calibration-window", "first-half"], "--calibration-window: sharma2013 does not"),
        (["--bag", "b"], "--bag: sharma2013 does not read it; read by tiers-uwb"),
        (["--sensing", "all"], "--sensing: sharma2013 does not read it; read by desilva2015"),
        (["--runs", "7"], "--runs: mrclam-cl does not read it"),  # one replay of one run
        (["--runs", "7"], "--runs: tiers-uwb does not read it"),
        (["--seed", "7"], "--seed: tiers-uwb does not read it"),  # it draws nothing at random
        (["--executor", "serial"], "--executor: mrclam-association does not read it"),
        (["--executor", "serial"], "--executor: wanasinghe-observability does not read it"),
        (["--executor", "serial"], "--executor: tiers-uwb does not read it"),
        (["--runs", "0"], "--runs: must be in 1…1000000, got 0"),
    ],
)
def test_a_flag_the_experiment_does_not_read_is_refused(tmp_path, capsys, flags, message):
    out = tmp_path / "out"
    name = message.split()[1] if "does not read" in message else "sharma2013"
    assert main(["reproduce", name, "--out", str(out), *flags]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()  # refused before anything ran


@pytest.mark.parametrize(
    ("pair", "message"),
    [
        ("1", "--pair: two robots OBSERVER,OBSERVED, got '1'"),
        ("1,2,3", "--pair: two robots OBSERVER,OBSERVED, got '1,2,3'"),
        ("1,x", "--pair: '1,x' is not a comma-separated list of integers"),
        ("2,2", "--pair: two different robots OBSERVER,OBSERVED, got (2, 2)"),
    ],
)
def test_a_bad_pair_is_refused(tmp_path, capsys, pair, message):
    out = tmp_path / "out"
    assert main(["reproduce", "wanasinghe2014", "--out", str(out), "--pair", pair]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    ("name", "pairs", "message"),
    [
        (
            "wanasinghe2014-pairs",
            ["1,3", "1,3"],
            "--pair: a pair is given twice in [(1, 3), (1, 3)]",
        ),
        ("wanasinghe2014", ["1,3", "2,4"], "--pair: wanasinghe2014 replays one pair, got 2"),
        ("wanasinghe2014-pairs", ["1,3", "2,9"], "--pair 2,9: robot(s) [9] not in"),
    ],
)
def test_repeated_pairs_are_checked(tmp_path, capsys, name, pairs, message):
    out = tmp_path / "out"
    flags = [flag for pair in pairs for flag in ("--pair", pair)]
    assert main(["reproduce", name, "--out", str(out), *flags]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("sensing", ["Q1", "L1,L1", "", "L1,,P1", "all,L1"])
def test_bad_sensing_robots_are_refused(tmp_path, capsys, sensing):
    out = tmp_path / "out"
    assert main(["reproduce", "desilva2015", "--out", str(out), "--sensing", sensing]) == 2
    assert "--sensing: 'all' or distinct robot names from L1, L2, P1, P2, P3" in (
        capsys.readouterr().err
    )
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["team", "up", "default", "--sharing-policy", "all"],
            "--sharing-policy: only desilva2015 teams (desilva2015, desilva2015-kidnapped)",
        ),
        (
            ["team", "up", "desilva2015", "--sharing-policy", "none"],
            "sharing policy 'none': one of all, mutual-confirmed",
        ),
        (
            ["node", "--robot", "L1", "--scenario", "sharma2013", "--sharing-policy", "all"],
            "--sharing-policy: only desilva2015 teams",
        ),
    ],
)
def test_a_sharing_policy_is_refused_where_it_means_nothing(tmp_path, capsys, argv, message):
    out = tmp_path / "out"
    assert main([*argv, *(["--out", str(out)] if argv[0] == "team" else [])]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["team", "up", "default", "--sensing", "all"],
        ["team", "up", "sharma2013", "--sensing", "L1"],
        ["team", "up", "guler2023", "--sensing", "all"],
        ["node", "--robot", "L1", "--scenario", "sharma2013", "--sensing", "all"],
        ["node", "--robot", "L1", "--dataset", "somewhere", "--sensing", "all"],
    ],
)
def test_sensing_robots_are_refused_outside_desilva_teams(tmp_path, capsys, argv):
    out = tmp_path / "out"
    assert main([*argv, *(["--out", str(out)] if argv[0] == "team" else [])]) == 2
    err = capsys.readouterr().err
    assert "--sensing: only desilva2015 teams (desilva2015, desilva2015-kidnapped)" in err
    assert "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("sensing", ["Q1", "L1,L1", "", "L1,,P1", "all,L1"])
@pytest.mark.parametrize(
    "argv",
    [
        ["team", "up", "desilva2015"],
        ["team", "up", "desilva2015-kidnapped"],
        ["node", "--robot", "L1", "--scenario", "desilva2015"],
    ],
)
def test_bad_sensing_robots_of_a_team_are_refused_as_for_reproduce(tmp_path, capsys, argv, sensing):
    """The team's ``--sensing`` is parsed by the reproduction's parser: the same message."""
    out = tmp_path / "out"
    team = ["--out", str(out)] if argv[0] == "team" else []
    assert main([*argv, *team, "--sensing", sensing]) == 2
    assert "--sensing: 'all' or distinct robot names from L1, L2, P1, P2, P3" in (
        capsys.readouterr().err
    )
    assert not out.exists()


def test_an_input_the_experiment_does_not_read_is_refused_from_python_too(tmp_path):
    from relloc.errors import ConfigError
    from relloc.experiments import registry

    args = registry.ReproduceArgs(out_dir=tmp_path / "out", seed=5)
    with pytest.raises(ConfigError, match="--seed: tiers-uwb does not read it"):
        registry.get("tiers-uwb")(args)
    assert not (tmp_path / "out").exists()
