"""``relloc reproduce mrclam-cl --mcap/--tum`` on an MRCLAM-layout folder: the exported case's
world poses and their RMSE per robot, against the summary's."""

from __future__ import annotations

import json

import pytest

from relloc.cli import main

pytest.importorskip("mcap", reason="extra 'ros' is not installed")


def test_mrclam_cl_exports_the_range_bearing_all_landmarks_case(synthetic_mrclam, tmp_path):  # type: ignore[no-untyped-def]
    out = tmp_path / "out"
    code = main(
        ["reproduce", "mrclam-cl", "--out", str(out), "--dataset", str(synthetic_mrclam),
         "--executor", "serial", "--quiet",
         "--mcap", str(tmp_path / "cl.mcap"), "--tum", str(tmp_path / "tum")]
    )  # fmt: skip
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    export = summary["export"]
    expected = summary["cases"]["range_bearing/all_landmarks"]["pos_rmse_m"]
    assert set(export["series"]) == {f"team->{r}" for r in "12345"}
    for robot in "12345":
        s = export["series"][f"team->{robot}"]
        assert s["frame_id"] == "map" and s["topic"] == f"/team/estimates/r{robot}"
        assert s["position_rmse_m"] == pytest.approx(expected[robot], rel=1e-9)
    assert (tmp_path / "tum" / "team" / "r1.truth.tum").is_file()
