"""The output helpers on hand-made values: JSON conversion, the skipped-rows line, table cells,
the output folder, report.md's ending and the files an earlier run left."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.pipeline.output import (
    earlier_files,
    fmt,
    interval_text,
    markdown_table,
    prepare_out_dir,
    run_average_verdict_text,
    skipped_rows_line,
    to_jsonable,
    write_report,
)


def test_to_jsonable_turns_numpy_paths_and_non_finite_values_into_json_types():
    value = {
        "a": np.float32("nan"),
        "b": (1, np.int64(2)),
        "c": Path("out/x.png"),
        3: np.array([1.0, math.inf]),
        "d": -math.inf,
    }
    assert to_jsonable(value) == {
        "a": None,
        "b": [1, 2],
        "c": "out/x.png",
        "3": [1.0, None],
        "d": None,
    }


def test_skipped_rows_line_counts_each_reason_in_order_of_the_reason():
    assert skipped_rows_line(0, {}) == "Input rows: every data row of the dataset was used."
    assert skipped_rows_line(3, {"z: unknown robot": 1, "a: bad time": 2}, "bag 1") == (
        "Input rows of bag 1 skipped (not used): 3 (2 a: bad time, 1 z: unknown robot)."
    )


def test_table_cells():
    assert fmt(np.bool_(True)) == "yes" and fmt(False) == "no"
    assert fmt(math.inf) == "—" and fmt(np.float64("nan")) == "—" and fmt(None) == "—"
    assert fmt(np.int64(12345678)) == "12345678" and fmt(0.123456) == "0.1235"
    assert markdown_table(["a", "b"], [[1, 0.123456], [None, True]]) == (
        "| a | b |\n|---|---|\n| 1 | 0.1235 |\n| — | yes |"
    )


def test_interval_and_verdict_texts():
    share = {"interval": [3.14, 7.36], "verdict": "consistent"}
    assert interval_text(share) == "3.1–7.4 consistent"
    assert interval_text({"interval": None, "verdict": "consistent"}) == "—"
    assert interval_text(None) == "—"
    short = {
        "interval": [1.24, 19.05],
        "verdict": "inconclusive",
        "blocks_short": True,
        "batch_s": 45.0,
        "correlation_time_s": 29.2,
        "correlation_samples": 78.4,
    }
    assert interval_text(short) == (
        "1.2–19.1 inconclusive (45 s blocks, errors correlated over 29 s: "
        "widened to 78 effective samples)"
    )
    assert run_average_verdict_text({"verdict": "consistent"}) == "consistent"
    assert (
        run_average_verdict_text({"verdict": "inconsistent", "blocks_short": True})
        == "inconsistent (blocks short)"
    )
    assert run_average_verdict_text({"verdict": None}) == "—"


def test_a_file_in_the_way_of_the_output_folder_is_named(tmp_path):  # type: ignore[no-untyped-def]
    blocker = tmp_path / "out"
    blocker.write_text("x")
    with pytest.raises(ConfigError) as info:
        prepare_out_dir(blocker, "--tum")
    assert str(info.value) == f"--tum: {blocker} exists and is not a folder"


def test_report_md_ends_in_exactly_one_newline(tmp_path):  # type: ignore[no-untyped-def]
    path = write_report(tmp_path, "# Report\n\ntext\n\n\n")
    assert path.read_text() == "# Report\n\ntext\n"


def test_earlier_files_allow_a_timer_tick_and_do_not_follow_links(tmp_path):  # type: ignore[no-untyped-def]
    started = time.time()
    old, tick, fresh = tmp_path / "old.png", tmp_path / "tick.png", tmp_path / "sub" / "new.png"
    for path in (old, tick, fresh):
        path.parent.mkdir(exist_ok=True)
        path.write_text("x")
    os.utime(old, (started - 5.0, started - 5.0))
    os.utime(tick, (started - 0.05, started - 0.05))  # within the 0.1 s slack: this run's
    link = tmp_path / "link.png"
    link.symlink_to(old)  # a link made now to an old file is this run's
    assert earlier_files(tmp_path, started) == [old]


def test_a_figure_without_a_layout_engine_is_laid_out_before_it_is_saved(tmp_path):  # type: ignore[no-untyped-def]
    pytest.importorskip("matplotlib", reason="extra 'plot' is not installed")
    from matplotlib.figure import Figure

    from relloc.pipeline.output import save_figure

    fig = Figure(figsize=(4, 3))
    fig.add_subplot().set_ylabel("a label")
    default_left = fig.subplotpars.left
    assert save_figure(fig, tmp_path, "plain") == "plain.png"
    assert (tmp_path / "plain.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # laid out (tight_layout): the axes moved off matplotlib's default margins
    assert fig.subplotpars.left != default_left
