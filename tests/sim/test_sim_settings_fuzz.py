"""Property-based fuzzing of the simulators' settings (hypothesis, derandomised and bounded).

The air-ground, cooperative and multi-hypothesis scenarios (and the air-ground sensor, drone
and leader settings) are built with one to three fields set to random values of random types —
numbers extreme or non-finite, strings, booleans, ``None``, lists of the wrong length. Whatever
the values, construction either succeeds or raises :class:`ConfigError`; a scenario that is
built and short enough (≤ 40 steps) then simulates without any other exception and with finite
truth.
"""

import dataclasses
import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from relloc.errors import ConfigError
from relloc.sim import cooperative, multihypothesis
from relloc.sim.airground import (
    AirGroundScenario,
    AirGroundWorld,
    CameraSettings,
    DroneSettings,
    LeaderPath,
)

FUZZ = settings(
    derandomize=True,
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
MAX_STEPS = 40

SPECIAL = [0, -1, 1, 2, 3, 0.5, 1e-300, 1e300, -1e300, 1.7e308, 2**63, math.nan, math.inf]
SPECIAL += [-math.inf, math.pi, 2 * math.pi, 7.0, True, False, None, "", "1", "sliding"]
scalars = st.sampled_from(SPECIAL) | st.floats(-1e3, 1e3) | st.integers(-5, 5) | st.text(max_size=4)
values = (
    scalars
    | st.lists(scalars, max_size=5).map(tuple)
    | st.lists(st.lists(scalars, max_size=3).map(tuple), max_size=4).map(tuple)
)


def _changes(cls, data, base):
    names = [f.name for f in dataclasses.fields(cls)]
    chosen = data.draw(st.lists(st.sampled_from(names), min_size=1, max_size=3, unique=True))
    return {**base, **{name: data.draw(values) for name in chosen}}


def _build(cls, kwargs):
    try:
        return cls(**kwargs)
    except ConfigError:
        return None


@FUZZ
@given(data=st.data())
def test_air_ground_settings_build_or_raise_config_error(data):
    for cls in (CameraSettings, DroneSettings, LeaderPath):
        _build(cls, _changes(cls, data, {}))
    base = {"offsets": ((0.5, 0.5), (-0.5, 0.5)), "offset_frame": "global", "duration": 0.5}
    sc = _build(AirGroundScenario, _changes(AirGroundScenario, data, base))
    if sc is None or sc.n_steps > MAX_STEPS:
        return
    world = AirGroundWorld.start(sc, np.random.default_rng(0))
    while not world.done:
        world.step(np.zeros((sc.n_followers + 1, 2)), np.zeros((sc.n_drones, 2)))
    assert all(np.isfinite(g.pose).all() for g in world.recording().truth or ())


@FUZZ
@given(data=st.data())
def test_cooperative_scenario_builds_or_raises_config_error(data):
    base = dataclasses.asdict(cooperative.sharma2013_scenario(duration=1.0))
    sc = _build(
        cooperative.CooperativeScenario, _changes(cooperative.CooperativeScenario, data, base)
    )
    if sc is None or sc.duration / sc.dt > MAX_STEPS:
        return
    rec = cooperative.simulate(sc, np.random.default_rng(0)).recording
    assert all(np.isfinite(g.pose).all() for g in rec.truth or ())


@FUZZ
@given(data=st.data())
def test_desilva_scenario_builds_or_raises_config_error(data):
    cls = multihypothesis.DeSilvaScenario
    sc = _build(cls, _changes(cls, data, {"duration": 1.0}))
    if sc is None or sc.duration * sc.filter_rate > MAX_STEPS:
        return
    rec = multihypothesis.simulate(sc, np.random.default_rng(0))
    assert all(np.isfinite(g.pose).all() for g in rec.truth or ())
