"""Bounds on what a robot reports: a value beyond them is a logging fault or hostile input,
never data, and would overflow a filter fed with it.

One set for every reader — scenario files (:mod:`relloc.sim.scenario`), recorded logs
(:mod:`relloc.datasets.mrclam`, :mod:`relloc.datasets.rosbag`), bag mappings
(:mod:`relloc.datasets.bag_mapping`) and network messages
(:mod:`relloc.runtime.messages`).
"""

from __future__ import annotations

MAX_SPEED_M_S = 100.0
"""Largest |linear velocity| of a body-velocity component (far beyond any ground robot or drone)."""
MAX_YAW_RATE_RAD_S = 100.0
"""Largest |turn rate| (16 turns a second)."""
MAX_ABS_POSITION_M = 1e5
"""Largest |coordinate| of a recorded position (a local metric frame within 100 km)."""
MAX_RADIO_RANGE_M = 1e4
"""Largest range of a radio, or its stated σ (m): ten times the reach of any UWB radio."""
