"""The flag value parsers and the field → flag rewriting, with their exact messages."""

from __future__ import annotations

import pytest

from relloc.cli.flags import as_flag_message, barcode_map, flag_errors, integer_list, number_pair
from relloc.errors import ConfigError


def test_a_leading_field_becomes_its_flag():
    assert as_flag_message("keep_window_s: must be ≥ 0") == "--keep-window: must be ≥ 0"
    assert as_flag_message(" seed : must be an integer") == "--seed: must be an integer"
    assert as_flag_message("duration_s: must be > 0") == "--duration: must be > 0"


def test_a_message_without_a_known_leading_field_is_unchanged():
    assert as_flag_message("seed must be an integer") == "seed must be an integer"
    assert as_flag_message("speed_m_s: too fast") == "speed_m_s: too fast"
    assert as_flag_message("seed") == "seed"  # a field name alone, with no message after it


def test_flag_errors_renames_the_field_of_a_config_error():
    with pytest.raises(ConfigError) as info, flag_errors():
        raise ConfigError("runs: must be ≥ 1")
    assert str(info.value) == "--runs: must be ≥ 1"


def test_an_empty_integer_list_is_an_error_not_no_value():
    assert integer_list(None, "--runs-of") is None
    assert integer_list("1,3,5", "--runs-of") == [1, 3, 5]
    with pytest.raises(ConfigError) as info:
        integer_list("", "--runs-of")
    assert str(info.value) == "--runs-of: '' is not a comma-separated list of integers"


def test_a_number_pair_needs_exactly_two_numbers():
    assert number_pair("3.7,-1.2", "--at") == (3.7, -1.2)
    for text in ("1,2,3", "a,b", "1"):
        with pytest.raises(ConfigError) as info:
            number_pair(text, "--at")
        assert str(info.value) == f"--at: {text!r} is not two numbers X,Y (e.g. --at=3.7,-1.2)"


def test_barcode_map_reads_pairs_with_spaces_around_the_colon():
    assert barcode_map(" 5 : 11,14:12", "--relabel") == {5: 11, 14: 12}
    assert barcode_map(None, "--relabel") is None


@pytest.mark.parametrize("text", ["5:11x", "5:", ":5", "5-11"])
def test_a_barcode_pair_must_be_whole_numbers_old_new(text):  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError) as info:
        barcode_map(text, "--relabel")
    assert str(info.value) == (
        f"--relabel: {text!r} in {text!r} is not OLD:NEW (barcodes as whole numbers, "
        "pairs separated by commas, e.g. --relabel 5:11,14:12)"
    )


def test_an_old_barcode_mapped_twice_is_refused():
    with pytest.raises(ConfigError) as info:
        barcode_map("5:1,5:2", "--relabel")
    assert str(info.value) == "--relabel: barcode 5 is mapped twice in '5:1,5:2'"
