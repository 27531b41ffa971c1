"""ROS stamps of recording times: seconds to the nearest nanosecond, inside ``[0, 2³¹)`` s."""

from __future__ import annotations

import pytest

from relloc.errors import DataError
from relloc.pipeline.export.mcap_file import stamp_ns


@pytest.mark.parametrize(
    ("t", "ns"),
    [(2.01, 2_010_000_000), (1.001, 1_001_000_000), (0.3, 300_000_000), (7e-9, 7), (0.0, 0)],
)
def test_a_time_is_rounded_to_the_nearest_nanosecond(t, ns):  # type: ignore[no-untyped-def]
    assert stamp_ns(t, "a->b") == ns


def test_the_last_representable_second_is_a_stamp_and_2_pow_31_is_not():
    assert stamp_ns(2.0**31 - 1, "a->b") == (2**31 - 1) * 1_000_000_000
    with pytest.raises(DataError) as info:
        stamp_ns(2.0**31, "a->b")
    assert str(info.value) == (
        "a->b: time 2147483648.0 s cannot be a ROS stamp (it must lie in [0, 2^31) s)"
    )


@pytest.mark.parametrize("name", ["runmcap", "run.tar.mcapx", "run_mcap", "mcap"])
def test_an_mcap_file_name_must_have_the_suffix_dot_mcap(tmp_path, name):  # type: ignore[no-untyped-def]
    from relloc.errors import ConfigError
    from relloc.pipeline.export.mcap_file import check_mcap_path

    with pytest.raises(ConfigError) as info:
        check_mcap_path(tmp_path / name)
    assert str(info.value) == (
        f"--mcap: {tmp_path / name} does not end in .mcap, by which ros2 bag play and Foxglove "
        "know the format; give a name such as out.mcap"
    )
    assert check_mcap_path(tmp_path / "run.mcap") == tmp_path / "run.mcap"
