"""Settings refuse values of the wrong type or range with a ConfigError naming the field
(:mod:`relloc.core.checks`); each of these was accepted (and used, or failed later naming
nothing) or raised a raw ``TypeError``/``ValueError``."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from relloc.core.checks import count, number, positive, probability, sequence
from relloc.errors import ConfigError
from relloc.estimators.cooperative import CooperativeSettings, OdometryModel, SensorModel
from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.estimators.initialisation import FieldOfView
from relloc.estimators.switching_ekf import SwitchingEkfSettings
from relloc.estimators.uwb_range import RangePairSettings, RangeTeamSettings
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.models.motion import VelocityNoise

SIG = (0.05, 0.05, 0.01, 0.05)


def _gaussian_sum(**kw: Any) -> GaussianSumSettings:
    base: dict[str, Any] = {
        "velocity_noise": VelocityNoise(observer=SIG, observed=SIG),
        "sigma_height": 0.01,
        "sigma_range": 0.1,
        "sigma_azimuth": 0.03,
        "sigma_elevation": 0.03,
    }
    return GaussianSumSettings(**(base | kw))


def _cooperative(**kw: Any) -> CooperativeSettings:
    sensor = SensorModel(sigma_bearing=0.05)
    base = {"odometry": OdometryModel(q_v0=1e-3, q_w0=1e-3), "sensor": sensor}
    return CooperativeSettings(**(base | kw))


CASES: list[tuple[Callable[[], object], str]] = [
    (lambda: RangePairSettings(gate=1.5), "RangePairSettings.gate"),
    (lambda: RangePairSettings(gate=math.nan), "RangePairSettings.gate"),
    (lambda: RangePairSettings(n_bearing=2.5), "RangePairSettings.n_bearing: expected an int"),
    (lambda: RangePairSettings(sigma_range="0.1"), "RangePairSettings.sigma_range: expected a"),
    (lambda: RangeTeamSettings(gate=0.0), "RangeTeamSettings.gate"),
    (lambda: RangeTeamSettings(gate=-1.0), "RangeTeamSettings.gate"),
    (lambda: FieldOfView(elevation_fov_deg=math.nan), "FieldOfView.elevation_fov_deg"),
    (lambda: FieldOfView(elevation_fov_deg=-30.0), "FieldOfView.elevation_fov_deg"),
    (lambda: FieldOfView(fov_deg=720.0), "FieldOfView.fov_deg"),
    (lambda: FieldOfView(range_limits=(0.3, 5.0, 9.0)), "range_limits: need (min, max)"),
    (lambda: _gaussian_sum(nscan_depth=2.5), "GaussianSumSettings.nscan_depth: expected an"),
    (lambda: _gaussian_sum(max_components=1.5), "GaussianSumSettings.max_components"),
    (lambda: _cooperative(anchors=(0.5,)), "CooperativeSettings.anchors: expected an integer"),
    (lambda: _cooperative(anchors=None), "CooperativeSettings.anchors: expected a tuple"),
    (lambda: _cooperative(odometry=None), "odometry must be an OdometryModel"),
    (
        lambda: SensorModel(sigma_bearing=0.05, range_bias_coeffs=None),
        "SensorModel.range_bias_coeffs",
    ),
    (lambda: OdometryModel(q_v0="1", q_w0=1e-3), "OdometryModel.q_v0: expected a number"),
    (lambda: VelocityNoise(observer=None, observed=SIG), "VelocityNoise.observer: needs 4"),
    (lambda: VelocityNoise(observer="abcd", observed=SIG), "VelocityNoise.observer: needs 4"),
    (lambda: YawBankSettings(prune_ratio="x"), "YawBankSettings.prune_ratio: expected a"),
    (lambda: SwitchingEkfSettings(sigma_v="x"), "SwitchingEkfSettings.sigma_v: expected a"),
]


@pytest.mark.parametrize(("make", "message"), CASES)
def test_a_bad_setting_is_refused_naming_the_field(make, message):
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
        make()


def test_the_checks_take_numpy_scalars_and_refuse_bools_and_strings():
    assert number(np.float64(2.5), "x", low=0.0) == 2.5
    assert count(np.int64(3), "n") == 3
    assert positive(1, "s") == 1.0 and probability(0.95, "p") == 0.95
    for bad in (True, "1", None, math.inf):
        with pytest.raises(ConfigError, match=r"^x: "):
            number(bad, "x")
    with pytest.raises(ConfigError, match=r"x: must be a finite number in \(0, 1\), got 1\.0"):
        probability(1.0, "x")
    with pytest.raises(ConfigError, match=r"n: expected an integer, got 3\.0"):
        count(3.0, "n")
    with pytest.raises(ConfigError, match=r"s: must be a finite number in \(0, inf\)"):
        positive(0.0, "s")


def test_an_integer_beyond_every_float_is_refused_not_an_overflow():
    with pytest.raises(ConfigError, match=r"^x: must be a finite number"):
        number(10**400, "x")
    with pytest.raises(ConfigError, match=r"^n: must be in 1…5, got 10000000000"):
        count(10**400, "n", high=5)
    assert count(5, "n", high=5) == 5


def test_a_sequence_is_a_list_tuple_or_array_of_the_length_asked():
    assert sequence((1, 2), "w", "two numbers", length=2) == (1, 2)
    assert len(sequence(np.zeros(3), "w", "numbers")) == 3
    for bad in ("ab", b"ab", None, 3, {"a": 1}, (1, 2, 3)):
        with pytest.raises(ConfigError, match=r"^w: expected two numbers, got "):
            sequence(bad, "w", "two numbers", length=2)
