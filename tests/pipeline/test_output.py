"""Output files are written whole or not at all, and a link in the output folder is replaced,
never followed (``relloc.pipeline.output.replace_file``)."""

from __future__ import annotations

import json

import pytest

from relloc.errors import ConfigError
from relloc.pipeline.output import replace_file, save_figure, write_report, write_summary
from relloc.plotting.setup import pyplot


def test_a_link_named_like_an_output_is_replaced_and_its_target_kept(tmp_path):
    """A ``summary.json`` that was a link to another file once had that file overwritten."""
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    for name in ("summary.json", "report.md", "fig.png"):
        (out / name).symlink_to(victim)
    write_summary(out, {"rmse": 0.5})
    write_report(out, "# report")
    assert save_figure(pyplot().figure(), out, "fig") == "fig.png"
    assert victim.read_text() == "keep me"
    for name in ("summary.json", "report.md", "fig.png"):
        assert not (out / name).is_symlink()
    assert json.loads((out / "summary.json").read_text()) == {"rmse": 0.5}
    assert (out / "fig.png").read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in out.iterdir()) == ["fig.png", "report.md", "summary.json"]


def test_a_write_that_fails_leaves_the_earlier_file_and_no_partial_one(tmp_path):
    path = tmp_path / "summary.json"
    path.write_text("earlier")

    def fails(tmp):  # type: ignore[no-untyped-def]
        tmp.write_text("half")
        raise OSError(28, "No space left on device")

    with pytest.raises(ConfigError, match=r"--out: cannot write .*summary.json \(No space left"):
        replace_file(path, "--out", fails)
    assert path.read_text() == "earlier"
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]

    def interrupted(tmp):  # type: ignore[no-untyped-def]
        tmp.write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        replace_file(path, "--out", interrupted)
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]
    with pytest.raises(ConfigError, match="--out: cannot write"):  # a folder of that name
        replace_file(tmp_path, "--out", lambda tmp: tmp.write_text("x"))
