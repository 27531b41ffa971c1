"""Simulator outcomes no scenario of the suite met: a drone that sees no robot has no marker
to re-anchor its guidance on, and one that sees only followers takes the first one's position
without a heading."""

from __future__ import annotations

import numpy as np

from relloc.sim.airground import AirGroundScenario, _marker_fix


def test_a_drone_seeing_no_robot_has_no_marker_fix() -> None:
    sc = AirGroundScenario(offsets=((0.5, 0.5), (-0.5, 0.5)))
    poses = np.array([[0.0, 0.0, 0.3], [1.0, 2.0, 0.1], [3.0, 4.0, 0.2]])
    assert _marker_fix([], poses, sc, np.random.default_rng(0)) is None
    fix = _marker_fix([2, 1], poses, sc, np.random.default_rng(0))
    assert fix is not None and fix.subject == 2 and fix.heading is None
    assert np.all(np.abs(fix.position - [3.0, 4.0]) < 6 * sc.drone.midpoint_sigma + 1e-12)
