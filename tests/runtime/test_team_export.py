"""``relloc team up --mcap FILE --tum DIR``: a real 3-robot team over loopback Zenoh writes the
distributed estimates, and the files read back to the numbers of its summary.json."""

from __future__ import annotations

import json
from collections import defaultdict

import numpy as np
import pytest

from relloc.cli import main
from relloc.runtime.transport import free_loopback_port

pytest.importorskip("mcap_ros2", reason="extra 'ros' (mcap-ros2-support) is not installed")
pytestmark = pytest.mark.slow


def test_team_up_writes_the_distributed_estimates(trio_scenario, tmp_path):  # type: ignore[no-untyped-def]
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path = trio_scenario(8.0)
    out = tmp_path / "out"
    code = main(
        ["team", "up", str(path), "--out", str(out), "--seed", "3", "--quiet",
         "--port", str(free_loopback_port()), "--filter", "tekf",
         "--mcap", str(tmp_path / "team.mcap"), "--tum", str(tmp_path / "tum")]
    )  # fmt: skip
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    # --filter (not the default plkf) reaches every robot as it does the in-process reference:
    # on this perfect network the two agree (the robots' own default would not)
    assert summary["filter"] == "tekf"
    assert summary["agreement"]["within_tolerance"], summary["agreement"]
    export = summary["export"]
    assert set(export["series"]) == set(summary["pairs"]) == {"observer->flyer", "observer->rover"}
    poses: dict[str, dict[int, np.ndarray]] = defaultdict(dict)
    with open(tmp_path / "team.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            if schema.name == "geometry_msgs/msg/PoseWithCovarianceStamped":
                p = msg.pose.pose.position
            elif schema.name == "geometry_msgs/msg/PoseStamped":
                p = msg.pose.position
            else:
                continue
            poses[channel.topic][message.log_time] = np.array([p.x, p.y, p.z])
    for label, s in export["series"].items():
        est = poses[s["topic"]]
        truth = poses[s["topic"].replace("/estimates/", "/ground_truth/", 1)]
        assert len(est) == s["records"] == len(truth) > 0
        err = np.array([est[ns] - truth[ns] for ns in sorted(est)])
        rmse = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
        assert rmse == pytest.approx(s["position_rmse_m"], rel=1e-12), label
        steady = summary["pairs"][label]["position_rmse_m"]
        assert s["steady_position_rmse_m"] == pytest.approx(steady, rel=1e-12)
        tum = export["tum"]["pairs"][label]
        assert np.loadtxt(tum["estimate"]).shape == (s["records"], 8)
