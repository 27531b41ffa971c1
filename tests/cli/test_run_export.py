"""``relloc run --mcap FILE --tum DIR``: the files read back to the numbers of summary.json."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

from relloc.cli import main

pytest.importorskip("mcap_ros2", reason="extra 'ros' (mcap-ros2-support) is not installed")

EVO_APE = Path(sys.executable).with_name("evo_ape")


def _positions(path: Path) -> dict[str, dict[int, np.ndarray]]:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, dict[int, np.ndarray]] = defaultdict(dict)
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            if schema.name == "tf2_msgs/msg/TFMessage":
                out[channel.topic][message.log_time] = np.zeros(3)
                continue
            pose = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
            p = pose.position
            out[channel.topic][message.log_time] = np.array([p.x, p.y, p.z])
    return out


@pytest.fixture(scope="module")
def run_out(tmp_path_factory):  # type: ignore[no-untyped-def]
    d = tmp_path_factory.mktemp("run_export")
    code = main(
        [
            "run",
            "--out", str(d / "out"),
            "--runs", "1",
            "--seed", "11",
            "--duration", "12",
            "--executor", "serial",
            "--quiet",
            "--mcap", str(d / "team.mcap"),
            "--tum", str(d / "tum"),
        ]
    )  # fmt: skip
    assert code == 0
    return d, json.loads((d / "out" / "summary.json").read_text())


def test_mcap_reads_back_to_the_summary(run_out):  # type: ignore[no-untyped-def]
    d, summary = run_out
    export = summary["export"]
    assert export["run"] == "run 0 of 1 (seed 11)"
    assert set(export["series"]) == set(summary["pairs"])
    topics = _positions(d / "team.mcap")
    assert {t: len(v) for t, v in topics.items()} == export["mcap"]["topics"]
    for label, s in export["series"].items():
        est = topics[s["topic"]]
        truth = topics[s["topic"].replace("/estimates/", "/ground_truth/", 1)]
        assert len(est) == s["records"] == s["records_with_truth"] == len(truth)
        err = np.array([est[ns] - truth[ns] for ns in sorted(est)])
        rmse = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
        assert rmse == pytest.approx(s["position_rmse_m"], rel=1e-12), label
        # one run: the exported run is the run the summary pools, same steady-state samples
        assert s["steady_position_rmse_m"] == pytest.approx(
            summary["pairs"][label]["position_rmse_m"], rel=1e-12
        )


@pytest.mark.skipif(not EVO_APE.exists(), reason="evo (extra 'bench') is not installed")
def test_evo_ape_on_the_tum_files_gives_the_summary_rmse(run_out, tmp_path):  # type: ignore[no-untyped-def]
    _, summary = run_out
    export = summary["export"]
    env = {**os.environ, "HOME": str(tmp_path), "MPLBACKEND": "Agg"}
    for label, files in export["tum"]["pairs"].items():
        results = tmp_path / f"{Path(files['estimate']).stem}.zip"
        subprocess.run(
            [
                str(EVO_APE),
                "tum",
                files["truth"],
                files["estimate"],
                "--save_results",
                str(results),
            ],
            check=True,
            capture_output=True,
            env=env,
            timeout=120,
        )
        with zipfile.ZipFile(results) as z:
            stats = json.loads(z.read("stats.json"))
        assert stats["rmse"] == pytest.approx(export["series"][label]["position_rmse_m"], rel=1e-9)


def test_mcap_into_a_folder_is_exit_code_2(tmp_path, capsys):  # type: ignore[no-untyped-def]
    code = main(
        ["run", "--out", str(tmp_path / "o"), "--runs", "1", "--duration", "3",
         "--executor", "serial", "--quiet", "--mcap", str(tmp_path)]
    )  # fmt: skip
    assert code == 2
    assert "is a folder" in capsys.readouterr().err
