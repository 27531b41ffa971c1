"""The per-row and per-file rules of the TIERS UWB csv loader on small hand-written files.

Each case states the documented rule (module docstring of :mod:`relloc.datasets.uwb`) at its
edge: the ends of the node-id and range intervals, the skip details, line numbers and which row
of a tie the time-order rule keeps.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from uwb_samples import recording_rows

from relloc.datasets.uwb import MAX_NODE_ID, UwbRecording, load_uwb_csv
from relloc.errors import DataError

HEADER = "timestamp,node1,node2,uwb_range,mocap_range"


def _load(tmp_path: Path, *rows: str, header: str = HEADER, name: str = "u.csv") -> UwbRecording:
    path = tmp_path / name
    path.write_bytes(("\n".join((header, *rows)) + "\n").encode())
    return load_uwb_csv(path)


def test_node_ids_zero_and_the_largest_int64_are_inside_the_interval(tmp_path):
    """Ids are integers in ``0 … MAX_NODE_ID``, both ends included."""
    rec = _load(
        tmp_path, "10.0,0,9223372036854775807,2.0,1.9", "10.1,9223372036854775807,0,2.5,2.4"
    )
    assert MAX_NODE_ID == 9223372036854775807
    assert recording_rows(rec) == [
        (10.0, 0, 9223372036854775807, 2.0, 1.9),
        (10.1, 9223372036854775807, 0, 2.5, 2.4),
    ]
    assert rec.skipped.n_skipped == 0


def test_one_past_the_largest_node_id_is_a_bad_node_id(tmp_path):
    rec = _load(tmp_path, "10.0,1,2,2.0,1.9", "10.1,1,9223372036854775808,2.0,1.9")
    assert rec.n_rows == 1
    assert dict(rec.skipped.skipped) == {"bad node id": 1}


def test_a_range_of_exactly_max_range_is_kept_and_just_above_is_skipped(tmp_path):
    """Ranges lie in ``(0, 1000]`` m: 1000 itself is a valid range."""
    rec = _load(
        tmp_path,
        "10.0,1,2,1000,999.5",
        "10.1,1,2,999.5,1000.0",
        "10.2,1,2,1000.001,999.5",
    )
    assert recording_rows(rec) == [(10.0, 1, 2, 1000.0, 999.5), (10.1, 1, 2, 999.5, 1000.0)]
    assert dict(rec.skipped.skipped) == {"range out of bounds": 1}
    assert rec.skipped.examples[0].line == 4


def test_invalid_utf8_detail_names_the_one_bad_byte_and_its_1_based_position(tmp_path):
    path = tmp_path / "u.csv"
    path.write_bytes(HEADER.encode() + b"\n10.0,1,2,2.0,1.9\n12\xff\xfe,1,2,2.0,1.9\n")
    rec = load_uwb_csv(path)
    assert rec.n_rows == 1
    (example,) = rec.skipped.examples
    assert (example.line, example.reason) == (3, "invalid UTF-8")
    assert example.text == "byte 3 (b'\\xff') is not UTF-8"


def test_an_error_column_off_by_exactly_the_tolerance_still_agrees(tmp_path):
    """A row is inconsistent only when ``error`` disagrees with ``uwb − mocap`` by *more* than
    1e-6 m; ``uwb = mocap`` makes the difference exactly the written error."""
    rec = _load(
        tmp_path,
        "10.0,1,2,2.0,2.0,1e-6",
        "10.1,1,2,2.0,2.0,-1e-6",
        "10.2,1,2,2.0,2.0,1.5e-6",
        header=HEADER + ",error",
    )
    assert rec.t.tolist() == [10.0, 10.1]
    assert dict(rec.skipped.skipped) == {"error column disagrees": 1}
    assert rec.skipped.examples[0].line == 4


def test_header_names_are_read_without_the_spaces_around_them(tmp_path):
    rec = _load(
        tmp_path,
        "10.0,1,2,2.0,1.5,0.5",
        header=" timestamp , node1,node2 ,uwb_range,  mocap_range,error ",
    )
    assert recording_rows(rec) == [(10.0, 1, 2, 2.0, 1.5)]


def test_an_error_column_named_twice_is_a_header_error_on_line_1(tmp_path):
    """The ``error`` column is read when present, so a header naming it twice is ambiguous."""
    with pytest.raises(DataError, match=r"u\.csv: line 1: column\(s\) \['error'\] appear more"):
        _load(tmp_path, "10.0,1,2,2.0,1.5,0.5,0.5", header=HEADER + ",error,error")


def test_two_rows_far_apart_are_each_implausible_to_the_other(tmp_path):
    """In a file of two rows each row's window is the other row, so two times 190 s apart
    leave no usable row."""
    with pytest.raises(DataError, match=r"no usable row \(2 data rows, 2 rows skipped: 2 implaus"):
        _load(tmp_path, "10.0,1,2,2.0,1.9", "200.0,1,2,2.0,1.9")


def test_a_time_exactly_max_time_gap_from_the_median_is_plausible(tmp_path):
    """Implausible means *more* than 60 s from the neighbours' median."""
    rec = _load(tmp_path, "10.0,1,2,2.0,1.9", "70.0,1,2,2.0,1.9")
    assert rec.t.tolist() == [10.0, 70.0]
    assert rec.skipped.n_skipped == 0


def test_of_an_even_count_of_neighbours_the_lower_middle_is_the_median(tmp_path):
    """Three rows: each is compared with the lower of its two neighbours' times.
    Row 10: median 50, 40 s off; row 50: median 10, 40 s off; row 100: median 10, 90 s off."""
    rec = _load(tmp_path, "10.0,1,2,2.0,1.9", "50.0,1,2,2.0,1.9", "100.0,1,2,2.0,1.9")
    assert rec.t.tolist() == [10.0, 50.0]
    assert dict(rec.skipped.skipped) == {"implausible timestamp": 1}
    assert rec.skipped.examples[0].line == 4


def test_skip_examples_are_listed_by_line_whatever_rule_skipped_them(tmp_path):
    """A time skipped by the cross-row rules (line 2) is listed before a later row skipped on
    its own (line 4), though the per-row checks run first."""
    rec = _load(
        tmp_path,
        "900.0,1,2,2.0,1.9",
        "10.0,1,2,2.0,1.9",
        "10.1,1,1,2.0,1.9",
        "10.2,1,2,2.0,1.9",
        "10.3,1,2,2.0,1.9",
    )
    assert rec.t.tolist() == [10.0, 10.2, 10.3]
    assert [(e.line, e.reason) for e in rec.skipped.examples] == [
        (2, "implausible timestamp"),
        (4, "node paired with itself"),
    ]


def test_the_time_window_is_centred_on_the_row(tmp_path):
    """Nine rows, four near 10 s then five near 110 s. Row 5 (110.0) is compared with rows
    2–4 and 6–8 (``TIME_WINDOW = 3`` each side): 10.1 10.2 10.3 110.1 110.2 110.3, lower middle
    10.3, 99.7 s off, implausible. Row 4 (10.3) is compared with rows 1–3 and 5–7: lower
    middle 10.2, plausible. Every other row's lower middle lies on its own side of the jump."""
    times = ["10.0", "10.1", "10.2", "10.3", "110.0", "110.1", "110.2", "110.3", "110.4"]
    rec = _load(tmp_path, *(f"{t},1,2,2.0,1.9" for t in times))
    assert rec.t.tolist() == [10.0, 10.1, 10.2, 10.3, 110.1, 110.2, 110.3, 110.4]
    assert [(e.line, e.reason) for e in rec.skipped.examples] == [(6, "implausible timestamp")]


def test_the_skip_report_counts_rows_dropped_by_time_order_as_not_kept(tmp_path):
    """``rows_read == rows_kept + skipped`` holds in the report itself: a row that passed the
    per-row checks but went back in time is not kept."""
    rec = _load(tmp_path, "10.0,1,2,2.0,1.9", "10.2,1,2,2.0,1.9", "10.1,1,2,2.0,1.9")
    report = rec.skipped
    assert (report.rows_read, report.rows_kept, dict(report.skipped)) == (
        3,
        2,
        {"timestamp out of order": 1},
    )


def test_a_link_is_unordered_in_links_and_link_mask(tmp_path):
    rec = _load(tmp_path, "10.0,4,2,2.0,1.9", "10.1,2,4,2.0,1.9", "10.2,2,3,2.0,1.9")
    assert rec.links() == [(2, 3), (2, 4)]
    assert rec.link_mask((2, 4)).tolist() == [True, True, False]
    assert rec.link_mask((4, 2)).tolist() == [True, True, False]


def test_a_header_only_file_says_there_is_nothing_after_the_header(tmp_path):
    with pytest.raises(
        DataError, match=r"u\.csv: no usable row \(0 data rows, none after the header\)"
    ):
        _load(tmp_path, "", "  ")
