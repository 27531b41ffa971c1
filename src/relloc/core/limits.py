"""Bounds on what a robot reports: a value beyond them is a logging fault or hostile input,
never data, and would overflow a filter fed with it.

One set for every reader — scenario files (:mod:`relloc.sim.scenario`), recorded logs
(:mod:`relloc.datasets.mrclam`, :mod:`relloc.datasets.rosbag`), bag mappings
(:mod:`relloc.datasets.bag_mapping`), network messages (:mod:`relloc.runtime.messages`) and
every recording's measurements (:mod:`relloc.core.recording`).
"""

from __future__ import annotations

MAX_SPEED_M_S = 100.0
"""Largest |linear velocity| of a body-velocity component (far beyond any ground robot or drone)."""
MAX_YAW_RATE_RAD_S = 100.0
"""Largest |turn rate| (16 turns a second)."""
MAX_ABS_POSITION_M = 1e5
"""Largest |coordinate| of a recorded position (a local metric frame within 100 km)."""
MAX_SENSOR_RANGE_M = 1e4
"""Largest range any sensor reports, or a radio's stated σ (m): ten times the reach of any UWB
radio, far beyond any camera or lidar."""
