"""``--mcap FILE`` / ``--tum DIR``: parsing, the request, and the lines printed per file."""

from __future__ import annotations

import argparse

import pytest

from relloc.cli.export_args import add_export_arguments, export_request, print_export


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="relloc run")
    add_export_arguments(p)
    return p


@pytest.mark.parametrize("flag", ["--mcap", "--tum"])
def test_an_empty_path_is_refused_naming_the_flag(flag, capsys):  # type: ignore[no-untyped-def]
    with pytest.raises(SystemExit) as info:
        _parser().parse_args([flag, ""])
    assert info.value.code == 2
    assert f"argument {flag}: an empty path" in capsys.readouterr().err


def test_no_flag_asks_for_nothing_and_a_folder_asks_for_tum_files(tmp_path):  # type: ignore[no-untyped-def]
    assert export_request(_parser().parse_args([])) is None
    request = export_request(_parser().parse_args(["--tum", str(tmp_path / "tum")]))
    assert request is not None
    assert request.tum == tmp_path / "tum" and request.mcap is None


def test_print_export_names_every_file_and_every_skip(capsys):  # type: ignore[no-untyped-def]
    section = {
        "run": "run 0 of 1, seed 7",
        "mcap": {
            "path": "out.mcap",
            "messages": 10,
            "topics": {"/a": 4, "/b": 6},
            "bytes": 1_536_000,  # 1500 KiB
            "seconds": 0.126,
        },
        "tum": {"dir": "tum", "pairs": {"a->b": {}, "b->a": {}, "team->a": {}}},
        "skipped": {"non-finite belief": 3, "frame without a pose meaning: range_bias": 20},
    }
    print_export(section)
    assert capsys.readouterr().out.splitlines() == [
        "wrote out.mcap (10 messages on 2 topics, 1500 KiB, 0.13 s; run 0 of 1, seed 7)",
        "wrote 3 TUM pairs under tum",
        "not exported: 3 records (non-finite belief)",
        "not exported: 20 records (frame without a pose meaning: range_bias)",
    ]


def test_print_export_without_a_section_prints_nothing(capsys):  # type: ignore[no-untyped-def]
    print_export(None)
    print_export({})
    assert capsys.readouterr().out == ""
