"""Motion control of the air-ground team: drone midpoint scheduling and follower formation."""

from relloc.control.drone_schedule import DroneSchedule
from relloc.control.formation import (
    FormationController,
    FormationSettings,
    desired_relative,
    formation_command,
)

__all__ = [
    "DroneSchedule",
    "FormationController",
    "FormationSettings",
    "desired_relative",
    "formation_command",
]
