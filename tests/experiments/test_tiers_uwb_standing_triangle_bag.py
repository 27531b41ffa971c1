"""tiers-uwb on hand-made bags of three robots standing at the corners of a 3-4-5 triangle, UWB
between every two at 10 Hz reading the true distance (+ a bias) − 0.02, + 0, + 0.02 m in turn.
The calibration window is the bag's first 30 % and everything is scored on the rest; with every
robot standing each is estimated with the other two as anchors, whose line leaves a mirror image
that ranges cannot tell from the robot's true place: the image closer to motion capture is
scored; the multilateration baseline is scored at 2 Hz."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

from relloc.datasets.bag_mapping import parse_mapping
from relloc.datasets.rosbag import BagRecording, load_bag
from relloc.estimators.uwb_range import RangeTeamSettings
from relloc.experiments import tiers_uwb
from relloc.experiments.tiers_uwb import analyse_bag
from relloc.experiments.tiers_uwb_team import team_case

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import POSE, RANGE, mocap, pose, uwb, write_bag

S = 1_000_000_000
T0 = 1_000 * S
XY = {"a": (0.0, 0.0), "b": (3.0, 0.0), "c": (0.0, 4.0)}
LINKS = (("a", "b"), ("a", "c"), ("b", "c"))
MAPPING = (
    "".join(f'[[robots]]\nname = "{r}"\ntruth = "/mocap/{r}"\n' for r in XY)
    + '[uwb]\ntopics = "/u/{a}/{b}/d"\nsigma = 0.25\n'
    + "".join(f'[[uwb.nodes]]\nname = "n_{r}"\nrobot = "{r}"\n' for r in XY)
)


def _bag(
    path: Path,
    bias: float,
    seconds: int,
    dense_until_s: float,
    off_half_s: float = 0.0,
    delay_ns: int = 1000,
) -> BagRecording:
    """Motion capture at 0, 0.1, … s; each link's range ``delay_ns`` after, true + ``bias`` −
    0.02, + 0, + 0.02 m in turn, + ``off_half_s`` away from whole and half seconds: at every
    motion-capture time up to ``dense_until_s``, then at every half second."""
    msgs = []
    for k in range(10 * seconds):
        t = T0 + k * S // 10
        for r, (x, y) in XY.items():
            msgs.append((f"/mocap/{r}", POSE, t, mocap(t, pose(x, y, 0.0, 0.0))))
        if k > 10 * dense_until_s + 1e-9 and k % 5:
            continue
        for a, b in LINKS:
            d = math.dist(XY[a], XY[b]) + bias + 0.02 * (k % 3 - 1) + (off_half_s if k % 5 else 0)
            msgs.append((f"/u/n_{a}/n_{b}/d", RANGE, t + delay_ns, uwb(t + delay_ns, d)))
    return load_bag(write_bag(path, msgs), parse_mapping(MAPPING, "m.toml"))


def test_the_model_is_fitted_on_the_first_30_percent_and_scored_on_the_rest(
    tmp_path: Path,
) -> None:
    """Motion capture spans [0, 6.9] s: fitted on [0, 2.07] s (the readings at 0.0, 0.1, …,
    2.0 s: 21 per link), scored on [2.07, 6.9] s (those at 2.1, 2.5, 3.0, …, 6.5 s: 10 per
    link)."""
    got = analyse_bag(_bag(tmp_path / "bag", 0.3, 7, 2.1), None)
    cal = got["calibration"]
    assert cal["source"] == "window" and cal["mapping_sigma_replaced_m"] == 0.25
    assert cal["window"]["start_s"] == 0.0
    assert cal["window"]["end_s"] == pytest.approx(2.07)
    assert got["scored_window_s"] == pytest.approx([2.07, 6.9])
    assert cal["fit"]["n_rows"] == 3 * 21
    assert cal["heldout"]["rows"] == 3 * 10
    assert cal["fit"]["bias_m"] == pytest.approx(0.3, abs=0.01)
    assert cal["heldout"]["raw"]["mean_m"] == pytest.approx(0.3, abs=0.01)
    assert cal["heldout"]["calibrated"]["mean_m"] == pytest.approx(0.0, abs=0.01)


def test_each_robot_given_the_other_two_is_scored_on_the_side_of_their_line_it_stands(
    tmp_path: Path,
) -> None:
    """Mirrored in the line of the other two, a would be 2 × 2.4 m off, b 2 × 3 m and c
    2 × 4 m; on the right side each is within centimetres (ranges true to ± 2 cm)."""
    rec = _bag(tmp_path / "bag", 0.0, 4, 4.0).recording
    settings = RangeTeamSettings(sigma_range=0.03)
    got = team_case(rec, rec, 1.0, 3.9, [0, 1, 2], settings, anchored=True)
    assert got["mode"] == "leave-one-out" and got["mirror_ambiguous"]
    assert got["per_robot"] == pytest.approx({"a": 0.0, "b": 0.0, "c": 0.0}, abs=0.1)
    assert got["pos_rmse_m"] < 0.1
    assert got["baselines"]["multilateration"]["pos_rmse_m"] < 0.1


def test_the_multilateration_baseline_is_scored_at_2_hz_on_every_fifth_record(
    tmp_path: Path,
) -> None:
    """c given anchors a and b, from 1 s on: the ranges at whole and half seconds are true
    (± 2 cm), the others 1 m long. At 2 Hz (1.0, 1.5, … s, as the module documents) the
    multilateration reads only true ranges; at any faster rate it would read long ones."""
    assert "``baselines.multilateration`` ``pos_rmse_m`` (the latter at\n2 Hz)" in tiers_uwb.__doc__
    rec = _bag(tmp_path / "bag", 0.0, 4, 4.0, off_half_s=1.0, delay_ns=0).recording
    settings = RangeTeamSettings(sigma_range=0.03)
    got = team_case(rec, rec, 1.0, 3.9, [0, 1], settings, anchored=True)
    assert got["mode"] == "anchors" and got["anchors"] == ["a", "b"]
    assert got["baselines"]["multilateration"]["pos_rmse_m"] < 0.05
