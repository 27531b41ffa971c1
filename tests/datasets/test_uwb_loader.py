"""UWB csv loader: each malformed input is a DataError naming the file, or one counted skip.

Every case checks the row invariant ``n_rows + skipped.n_skipped == data_rows`` and, where one
line is bad, that exactly that line is lost (the other rows load exactly as from the clean file).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from uwb_samples import HEADER, Row, check_recording, recording_rows, tiers_lines, tiers_text

from relloc.calibration.uwb import fit_uwb_noise
from relloc.calibration.window import spanning
from relloc.datasets.paths import shared_data_dir
from relloc.datasets.uwb import MAX_TIME_GAP, UwbRecording, load_uwb_csv
from relloc.errors import DataError


def _write(tmp_path: Path, data: bytes, name: str = "uwb.csv") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _load(tmp_path: Path, data: bytes) -> UwbRecording:
    rec = load_uwb_csv(_write(tmp_path, data))
    check_recording(rec, data)
    return rec


def _clean_rows(tmp_path: Path, lines: list[bytes]) -> list[Row]:
    return recording_rows(load_uwb_csv(_write(tmp_path, b"\n".join(lines) + b"\n", "clean.csv")))


def _with_line(lines: list[bytes], k: int, new: bytes) -> bytes:
    """The file with line ``k`` (1-based, as the loader numbers them) replaced by ``new``."""
    out = list(lines)
    out[k - 1] = new
    return b"\n".join(out) + b"\n"


def _assert_only_line_lost(
    tmp_path: Path, lines: list[bytes], k: int, new: bytes, reason: str
) -> UwbRecording:
    rec = _load(tmp_path, _with_line(lines, k, new))
    clean = _clean_rows(tmp_path, lines)
    assert recording_rows(rec) == clean[: k - 2] + clean[k - 1 :]
    assert dict(rec.skipped.skipped) == {reason: 1}
    assert rec.skipped.examples[0].line == k
    return rec


# ----------------------------------------------------------------------------------------------
# The fuzz findings: each costs exactly its own line, counted, with its true line number
# ----------------------------------------------------------------------------------------------


def test_one_invalid_utf8_byte_costs_its_line_only(tmp_path):
    lines = tiers_lines(12)
    bad = lines[9][:20] + b"\xff" + lines[9][20:]
    rec = _assert_only_line_lost(tmp_path, lines, 10, bad, "invalid UTF-8")
    assert "not UTF-8" in rec.skipped.examples[0].text


def test_truncated_multibyte_character_costs_its_line_only(tmp_path):
    lines = tiers_lines(12)
    _assert_only_line_lost(tmp_path, lines, 30, lines[29] + "é".encode()[:1], "invalid UTF-8")


@pytest.mark.parametrize("where", ["start", "middle", "end"])
def test_one_stray_quote_costs_its_line_only(tmp_path, where):
    lines = tiers_lines(12)
    line = lines[19]
    bad = {"start": b'"' + line, "middle": line[:30] + b'"' + line[30:], "end": line + b',"'}
    rec = _load(tmp_path, _with_line(lines, 20, bad[where]))
    clean = _clean_rows(tmp_path, lines)
    assert recording_rows(rec) == clean[:18] + clean[19:]
    assert rec.skipped.n_skipped == 1 and rec.skipped.examples[0].line == 20


def test_stray_quote_in_the_shared_test_recording_is_reported_as_one_row(tmp_path):
    """A quote once cost up to 854 rows and was reported as 1; now the report is what was lost."""
    src = shared_data_dir() / "uwb" / "tiers" / "test.csv"
    if not src.is_file():
        pytest.skip(f"shared UWB data not found at {src} (outside the workspace)")
    lines = src.read_bytes().split(b"\n")
    lines[200] = b'"' + lines[200]
    data = b"\n".join(lines)
    rec = _load(tmp_path, data)
    assert (rec.data_rows, rec.n_rows, rec.skipped.n_skipped) == (1098, 1097, 1)
    summary = fit_uwb_noise(rec, spanning(rec.t, str(rec.path))).to_dict()
    assert (summary["n_rows"], summary["rows_skipped"]) == (1097, 1)


def test_a_leading_bom_is_accepted_and_stripped(tmp_path):
    data = tiers_text(4)
    rec = _load(tmp_path, b"\xef\xbb\xbf" + data)
    assert recording_rows(rec) == recording_rows(_load(tmp_path, data))
    assert rec.skipped.n_skipped == 0


def test_a_bom_inside_the_file_is_a_counted_skip(tmp_path):
    lines = tiers_lines(4)
    _assert_only_line_lost(
        tmp_path, lines, 5, b"\xef\xbb\xbf" + lines[4], "not a number"
    )  # U+FEFF before the timestamp


@pytest.mark.parametrize(
    "node", ["1e19", "18446744073709551617", "18446744073709551617.0", "9223372036854775808"]
)
def test_node_ids_out_of_int64_are_rejected_not_wrapped(tmp_path, node):
    lines = tiers_lines(6)
    fields = lines[7].split(b",")
    fields[1] = node.encode()
    rec = _assert_only_line_lost(tmp_path, lines, 8, b",".join(fields), "bad node id")
    assert "is not in 0" in rec.skipped.examples[0].text


@pytest.mark.parametrize("node", ["-1", "1.5", "nan", "inf", "sNaN", "one", ""])
def test_node_ids_must_be_non_negative_integers(tmp_path, node):
    lines = tiers_lines(6)
    fields = lines[7].split(b",")
    fields[2] = node.encode()
    _assert_only_line_lost(tmp_path, lines, 8, b",".join(fields), "bad node id")


def test_node_ids_in_int64_are_kept_exactly(tmp_path):
    big = 2**53 + 1  # not representable as a float64: must not be rounded into 2**53
    line = f"100.0,{big},{2**53},2.0,1.9,0.0,0.0,{2.0 - 1.9!r}".encode()
    rec = _load(tmp_path, HEADER + b"\n" + line + b"\n")
    assert rec.node1.tolist() == [big] and rec.node2.tolist() == [2**53]


def test_node_paired_with_itself_is_a_counted_skip(tmp_path):
    lines = tiers_lines(6)
    fields = lines[7].split(b",")
    fields[2] = fields[1]
    rec = _assert_only_line_lost(tmp_path, lines, 8, b",".join(fields), "node paired with itself")
    assert "node1 = node2 = 1" in rec.skipped.examples[0].text


def _with_time(lines: list[bytes], k: int, t: str) -> bytes:
    fields = lines[k - 1].split(b",")
    fields[0] = t.encode()
    return b",".join(fields)


@pytest.mark.parametrize("k", [2, 3, 100, 240, 241])
@pytest.mark.parametrize("t", ["2671462954.0", "1671472954.0", "1e300", "1.0", "0.0", "-5.0"])
def test_one_far_mistyped_timestamp_anywhere_costs_its_row_only(tmp_path, k, t):
    """Once, one future typo discarded 92 % of the rows; now it costs its own row."""
    lines = tiers_lines(40)
    rec = _assert_only_line_lost(
        tmp_path, lines, k, _with_time(lines, k, t), "implausible timestamp"
    )
    assert (
        f"more than {MAX_TIME_GAP:g} s from its neighbours' median" in rec.skipped.examples[0].text
    )


@pytest.mark.parametrize(
    "t, direction",
    [("1671462964.0110343", "is later than the rows after it"), ("1671462950.0", "back in time")],
)
def test_one_near_mistyped_timestamp_out_of_order_costs_its_row_only(tmp_path, t, direction):
    lines = tiers_lines(40)
    rec = _assert_only_line_lost(
        tmp_path, lines, 100, _with_time(lines, 100, t), "timestamp out of order"
    )
    assert direction in rec.skipped.examples[0].text


def test_a_few_bad_times_together_do_not_cost_good_rows(tmp_path):
    lines = tiers_lines(40)
    for k in (50, 51):
        lines[k - 1] = _with_time(lines, k, "0.0")
    rec = _load(tmp_path, b"\n".join(lines) + b"\n")
    clean = _clean_rows(tmp_path, tiers_lines(40))
    assert recording_rows(rec) == clean[:48] + clean[50:]
    assert dict(rec.skipped.skipped) == {"implausible timestamp": 2}


def test_a_swapped_pair_of_times_skips_the_earlier_row(tmp_path):
    rows = [(10.0, 1, 3), (20.0, 1, 4), (15.0, 1, 5), (30.0, 3, 4)]
    text = HEADER + b"\n" + b"".join(f"{t},{a},{b},2.0,1.5,0,0,0.5\n".encode() for t, a, b in rows)
    rec = _load(tmp_path, text)
    assert rec.t.tolist() == [10.0, 15.0, 30.0]
    assert [(e.line, e.text) for e in rec.skipped.examples] == [
        (3, "timestamp 20.0 is later than the rows after it")
    ]


def test_a_block_of_shuffled_rows_costs_the_fewest_rows_that_restore_order(tmp_path):
    lines = tiers_lines(20)
    shuffled = lines[:50] + lines[60:70] + lines[50:60] + lines[70:]
    rec = _load(tmp_path, b"\n".join(shuffled) + b"\n")
    assert rec.skipped.n_skipped == 10 and dict(rec.skipped.skipped) == {
        "timestamp out of order": 10
    }


@pytest.mark.parametrize(
    "column, value, reason",
    [
        (3, "nan", "not finite"),
        (3, "inf", "not finite"),
        (4, "-inf", "not finite"),
        (3, "-2.5", "range out of bounds"),
        (4, "0", "range out of bounds"),
        (3, "1e300", "range out of bounds"),
        (0, "nan", "not finite"),
        (0, "1e999", "not finite"),
        (0, "noon", "not a number"),
        (7, "nan", "not finite"),
        (7, "9.0", "error column disagrees"),
    ],
)
def test_bad_values_cost_their_row_only(tmp_path, column, value, reason):
    lines = tiers_lines(6)
    fields = lines[11].split(b",")
    fields[column] = value.encode()
    _assert_only_line_lost(tmp_path, lines, 12, b",".join(fields), reason)


@pytest.mark.parametrize("change", ["drop", "extra", "empty"])
def test_a_row_with_the_wrong_column_count_is_a_counted_skip(tmp_path, change):
    lines = tiers_lines(6)
    line = lines[11]
    bad = {"drop": line.rsplit(b",", 1)[0], "extra": line + b",7.0", "empty": b",,,"}
    _assert_only_line_lost(tmp_path, lines, 12, bad[change], "wrong column count")


def test_extra_and_reordered_columns_in_the_header_are_read_by_name(tmp_path):
    text = (
        b"mocap_range,uwb_range,node2,node1,timestamp,rssi\n"
        b"1.5,2.0,3,1,10.0,-80\n"
        b"1.6,2.1,4,1,10.0,-81\n"
    )
    rec = _load(tmp_path, text)
    assert recording_rows(rec) == [(10.0, 1, 3, 2.0, 1.5), (10.0, 1, 4, 2.1, 1.6)]


def test_quoted_fields_crlf_and_no_final_newline_are_fine(tmp_path):
    lines = tiers_lines(3)
    quoted = b",".join(b'"' + f + b'"' for f in lines[3].split(b","))
    data = b"\r\n".join([*lines[:3], quoted, *lines[4:]])  # no final newline
    rec = _load(tmp_path, data)
    assert recording_rows(rec) == _clean_rows(tmp_path, lines)


def test_blank_lines_are_counted_apart_from_data_rows(tmp_path):
    lines = tiers_lines(3)
    data = b"\n".join([*lines[:5], b"", b"  \t", b"\r", *lines[5:]]) + b"\n\n"
    rec = _load(tmp_path, data)
    assert (rec.data_rows, rec.blank_lines, rec.skipped.n_skipped) == (18, 4, 0)
    assert recording_rows(rec) == _clean_rows(tmp_path, lines)


def test_many_bad_rows_report_counts_by_reason_and_the_first_lines(tmp_path):
    lines = tiers_lines(6)
    for k in (5, 9, 13, 17, 21, 25, 29):
        lines[k - 1] = b"\xfe" + lines[k - 1]
    lines[30] = _with_time(lines, 31, "1e12")
    rec = _load(tmp_path, b"\n".join(lines) + b"\n")
    assert dict(rec.skipped.skipped) == {"invalid UTF-8": 7, "implausible timestamp": 1}
    assert [e.line for e in rec.skipped.examples] == [5, 9, 13, 17, 21]
    text = rec.describe()
    assert str(rec.path) in text and "28 of 36 rows read" in text
    assert "8 rows skipped: 1 implausible timestamp, 7 invalid UTF-8" in text


# ----------------------------------------------------------------------------------------------
# Unusable files: DataError naming the file
# ----------------------------------------------------------------------------------------------


def test_missing_file_names_it_and_says_how_to_point_relloc_at_data(tmp_path):
    path = tmp_path / "nowhere" / "uwb.csv"
    with pytest.raises(DataError, match="RELLOC_SHARED_DATA") as info:
        load_uwb_csv(path)
    assert str(path) in str(info.value) and "not found" in str(info.value)


def test_a_directory_given_as_the_file(tmp_path):
    with pytest.raises(DataError, match="is a directory") as info:
        load_uwb_csv(tmp_path)
    assert str(tmp_path) in str(info.value)


@pytest.mark.parametrize("data", [b"", b"\xef\xbb\xbf"])
def test_an_empty_file(tmp_path, data):
    with pytest.raises(DataError, match=r"uwb\.csv: empty file"):
        load_uwb_csv(_write(tmp_path, data))


@pytest.mark.parametrize("body", [b"", b"\n", b"\n\n  \n"])
def test_a_header_only_file_has_no_usable_row(tmp_path, body):
    with pytest.raises(DataError, match=r"uwb\.csv: no usable row \(0 data rows"):
        load_uwb_csv(_write(tmp_path, HEADER + b"\n" + body))


def test_a_file_of_bad_rows_says_why(tmp_path):
    data = HEADER + b"\n" + b"x,1,3,2.0,1.5,0,0,0.5\n" + b"\xff\n"
    with pytest.raises(DataError, match=r"no usable row \(2 data rows, 2 rows skipped") as info:
        load_uwb_csv(_write(tmp_path, data))
    assert "line 2: timestamp='x' is not a number" in str(info.value)


@pytest.mark.parametrize(
    "header, match",
    [
        (b"timestamp,node1,node2,uwb_range", r"line 1: missing column\(s\) \['mocap_range'\]"),
        (b"\n" + HEADER, r"line 1: missing column"),
        (HEADER + b",node1", r"line 1: column\(s\) \['node1'\] appear more than once"),
        (b"timestamp,node1\xff,node2", r"line 1: unreadable header: byte 16"),
        (b'"timestamp,node1,node2,uwb_range,mocap_range', r"line 1: unreadable header"),
    ],
)
def test_an_unusable_header_is_a_data_error_on_line_1(tmp_path, header, match):
    data = header + b"\n" + b"\n".join(tiers_lines(2)[1:]) + b"\n"
    with pytest.raises(DataError, match=match) as info:
        load_uwb_csv(_write(tmp_path, data))
    assert str(tmp_path / "uwb.csv") in str(info.value)


def test_real_recordings_load_every_row(tmp_path):
    folder = shared_data_dir() / "uwb" / "tiers"
    if not folder.is_dir():
        pytest.skip(f"shared UWB data not found at {folder} (outside the workspace)")
    for name, n in (("20221011_processed.csv", 8712), ("test.csv", 1098)):
        rec = load_uwb_csv(folder / name)
        check_recording(rec, (folder / name).read_bytes())
        assert (rec.n_rows, rec.data_rows, rec.skipped.n_skipped) == (n, n, 0)
        assert np.all(np.diff(rec.t) >= 0.0)
