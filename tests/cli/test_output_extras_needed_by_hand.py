"""Which extras a parsed command needs, and the exit-5 message naming the missing one."""

from __future__ import annotations

import sys
import types
from argparse import Namespace

import pytest

from relloc.cli.extras import check_command, missing_modules, needed_extras, require_extras
from relloc.errors import DependencyError


@pytest.mark.parametrize(
    ("args", "extras"),
    [
        (Namespace(command="team", team_command="status"), ("runtime",)),
        (Namespace(command="team", team_command="up"), ("runtime", "plot")),
        (Namespace(command="bench", name="secure"), ("runtime",)),
        (Namespace(command="bench", name="filters"), ("bench",)),
        (Namespace(command="run", mcap=None, tum="out/tum"), ()),
        (Namespace(command="run", mcap="out.mcap", tum=None), ("ros",)),
        (Namespace(command="run", executor="process"), ()),
        (Namespace(command="run", executor="dask"), ()),  # not dask://HOST:PORT: no cluster
        (
            Namespace(command="reproduce", name="x", executor="dask://host:8786"),
            ("plot", "cluster"),
        ),
    ],
)
def test_needed_extras(args, extras):  # type: ignore[no-untyped-def]
    assert needed_extras(args) == extras


def test_a_missing_mcap_ros2_is_a_missing_ros_extra(monkeypatch):  # type: ignore[no-untyped-def]
    monkeypatch.setitem(sys.modules, "mcap_ros2", None)  # import blocked
    with pytest.raises(DependencyError) as info:
        check_command(Namespace(command="run", mcap="out.mcap"))
    assert str(info.value) == (
        "relloc run needs the 'ros' extra (mcap_ros2 not installed); "
        "install it with: pip install 'relloc[ros]'"
    )


def test_a_broken_package_counts_as_absent(monkeypatch):  # type: ignore[no-untyped-def]
    broken = types.ModuleType("zenoh")
    broken.__spec__ = None  # importlib.util.find_spec raises ValueError on it
    monkeypatch.setitem(sys.modules, "zenoh", broken)
    assert missing_modules("runtime") == ["zenoh"]
    with pytest.raises(DependencyError) as info:
        check_command(Namespace(command="bench", name="secure"))
    assert str(info.value) == (
        "relloc bench secure needs the 'runtime' extra (zenoh not installed); "
        "install it with: pip install 'relloc[runtime]'"
    )


def test_every_extra_is_checked_not_only_the_first(monkeypatch):  # type: ignore[no-untyped-def]
    pytest.importorskip("matplotlib", reason="extra 'plot' is not installed")
    monkeypatch.setitem(sys.modules, "msgpack", None)
    with pytest.raises(DependencyError, match=r"needs the 'runtime' extra \(msgpack not"):
        require_extras(("plot", "runtime"), "relloc team up")
