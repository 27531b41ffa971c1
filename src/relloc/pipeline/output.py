"""Writing the machine-checkable outputs every experiment produces.

``summary.json`` (numbers, each beside the paper's value where there is one), ``report.md``
(the same as tables, figures inline) and ``*.png`` figures, all inside one output folder.
"""

from __future__ import annotations

import json
import math
import os
import uuid
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from relloc.errors import ConfigError


def to_jsonable(value: Any) -> Any:
    """Convert numpy scalars/arrays, tuples and paths to JSON types; NaN/inf become None."""
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


SKIPPED_ROWS_START = "Input rows"
"""How the report line of :func:`skipped_rows_line` starts; ``relloc reproduce`` prints the
report's lines that start so on the console (:mod:`relloc.cli.comparison`)."""


def skipped_rows_line(
    n_skipped: int, by_reason: Mapping[str, int], source: str = "the dataset"
) -> str:
    """report.md's account of the data rows of ``source`` that the loaders (and the
    conversion to a recording) skipped: their count and the count of each reason, or that
    every row was used."""
    if not n_skipped:
        return f"{SKIPPED_ROWS_START}: every data row of {source} was used."
    reasons = ", ".join(f"{n} {why}" for why, n in sorted(by_reason.items()))
    return f"{SKIPPED_ROWS_START} of {source} skipped (not used): {n_skipped} ({reasons})."


def bag_rows_source(not_in_recording: Mapping[str, int]) -> str:
    """How :func:`skipped_rows_line` names a ROS 2 bag: the UWB readings the loader kept out of
    the recording (``uwb_readings_not_in_recording``, reason → count, reported on their own)
    are set aside, so that "every data row was used" does not claim them."""
    aside = sum(not_in_recording.values())
    return f"the bag (less its {aside} UWB readings not in the recording)" if aside else "the bag"


def prepare_out_dir(out_dir: Path | str, flag: str = "--out") -> Path:
    """Create the output folder (and parents); raise ConfigError naming ``flag`` if a file is
    in the way or the folder cannot be created."""
    path = Path(out_dir)
    if path.exists() and not path.is_dir():
        raise ConfigError(f"{flag}: {path} exists and is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{flag}: cannot create {path} ({exc.strerror or exc})") from None
    return path


EARLIER_SLACK_S = 0.1
"""A file's modification time may lag the clock by a timer tick: a file is an earlier run's
only if it is older than the run's start by more than this."""


def earlier_files(out_dir: Path, started: float) -> list[Path]:
    """The files under ``out_dir`` last written before ``started`` (a :func:`time.time`):
    an earlier run's, which this run did not replace (its outputs are all written anew).
    Links are not followed."""
    since = started - EARLIER_SLACK_S
    found = []
    for root, _, names in os.walk(out_dir):
        for name in names:
            path = Path(root) / name
            try:
                if path.lstat().st_mtime < since:
                    found.append(path)
            except OSError:  # removed meanwhile
                continue
    return sorted(found)


def check_writable_file(path: Path, flag: str) -> None:
    """ConfigError naming ``flag`` unless a file can be written at ``path``: not a folder,
    its folder existing or creatable, writable (checked before a long run, not after it)."""
    if path.is_dir():
        raise ConfigError(f"{flag}: {path} is a folder; give a file name")
    prepare_out_dir(path.parent, flag)
    if not os.access(path.parent, os.W_OK):
        raise ConfigError(f"{flag}: {path.parent} is not writable")


def replace_file(path: Path, flag: str, write: Callable[[Path], object]) -> Path:
    """Write ``path`` whole or not at all: ``write`` fills a new file beside it, which then
    takes its name (:func:`os.replace`). A link at ``path`` is replaced, never followed (its
    target is left as it was), and a run stopped midway leaves the earlier file. A path that
    cannot be written (a folder in the way, no permission) raises ConfigError naming ``flag``."""
    tmp = prepare_out_dir(path.parent, flag) / f".{path.name}.{uuid.uuid4().hex}.tmp"
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        raise ConfigError(f"{flag}: cannot write {path} ({exc.strerror or exc})") from None
    finally:
        tmp.unlink(missing_ok=True)
    return path


def write_json_file(path: Path, data: Any, flag: str) -> Path:
    """Write ``data`` as JSON to ``path`` (its folder created; :func:`replace_file`)."""
    text = json.dumps(to_jsonable(data), indent=2) + "\n"
    return replace_file(path, flag, lambda tmp: tmp.write_text(text))


def _write_out(out_dir: Path, name: str, text: str) -> Path:
    """Write ``text`` to ``out_dir/name`` (:func:`replace_file`)."""
    return replace_file(Path(out_dir) / name, "--out", lambda tmp: tmp.write_text(text))


def write_summary(out_dir: Path, summary: Mapping[str, Any]) -> Path:
    """Write ``summary.json`` (sorted keys kept in insertion order, 2-space indent)."""
    return _write_out(
        out_dir, "summary.json", json.dumps(to_jsonable(summary), indent=2, allow_nan=False) + "\n"
    )


def write_report(out_dir: Path, markdown: str) -> Path:
    """Write ``report.md``."""
    return _write_out(out_dir, "report.md", markdown.rstrip() + "\n")


def save_figure(fig: Any, out_dir: Path, name: str, *, dpi: int = 110) -> str:
    """Save a matplotlib figure as ``name.png`` in ``out_dir``, close it, return the file name.

    A figure without a layout engine is laid out first (``tight_layout``), so legends placed
    outside their axes (:func:`relloc.plotting.style.legend_outside`) get room beside them."""
    import warnings

    filename = f"{name}.png"
    if fig.get_layout_engine() is None:
        with warnings.catch_warnings():  # "not compatible with tight_layout" for odd axes
            warnings.simplefilter("ignore", UserWarning)
            fig.tight_layout()
    from relloc.plotting.setup import pyplot

    try:
        replace_file(
            Path(out_dir) / filename,
            "--out",
            lambda tmp: fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="png"),
        )
    finally:
        pyplot().close(fig)
    return filename


def fmt(value: Any, digits: int = 4) -> str:
    """Format a number for a markdown table (``—`` for None/NaN)."""
    if value is None:
        return "—"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(float(value)):
            return "—"
        return f"{float(value):.{digits}g}"
    return str(value)


def interval_text(share: Mapping[str, Any] | None) -> str:
    """A share beyond a χ² bound's interval and verdict for a table cell, from
    :meth:`relloc.metrics.consistency.BeyondShare.to_dict`: ``"3.1–7.4 consistent"``
    (``—`` without one); when its time blocks are short against the values' correlation time
    (``blocks_short``, so the interval is the batch means' one widened to the correlation-time
    interval) it adds both and that interval's effective sample size, ``"1.2–19.0 inconclusive
    (45 s blocks, errors correlated over 29 s: widened to 78 effective samples)"``."""
    if not share or share.get("interval") is None:
        return "—"
    lo, hi = share["interval"]
    text = f"{lo:.1f}–{hi:.1f} {share['verdict']}"
    if share.get("blocks_short"):
        text += (
            f" ({share['batch_s']:.2g} s blocks, errors correlated over "
            f"{share['correlation_time_s']:.2g} s: widened to "
            f"{share['correlation_samples']:.0f} effective samples)"
        )
    return text


def run_average_verdict_text(band: Mapping[str, Any] | None) -> str:
    """The verdict of a :func:`relloc.metrics.run_average_band` result for a report, marked
    ``"(blocks short)"`` when its intervals' blocks of times last less than ten correlation
    times (``blocks_short``; the intervals behind the verdict are then widened to the
    correlation-time interval, :func:`relloc.metrics.percent_beyond_interval`);
    ``—`` without a verdict."""
    if not band or band.get("verdict") is None:
        return "—"
    return f"{band['verdict']} (blocks short)" if band.get("blocks_short") else band["verdict"]


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[Any]], digits: int = 4) -> str:
    """A GitHub-flavoured markdown table."""
    head = "| " + " | ".join(headers) + " |"
    sep = "|" + "|".join("---" for _ in headers) + "|"
    body = ["| " + " | ".join(fmt(c, digits) for c in row) + " |" for row in rows]
    return "\n".join([head, sep, *body])


def figure_md(filename: str, caption: str) -> str:
    """Inline a figure in report.md."""
    return f"![{caption}]({filename})\n\n*{caption}*\n"
