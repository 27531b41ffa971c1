"""Which midpoint ``m_i`` (between R_0 and follower R_i) each drone hovers on (seed 003, §3.2).

Time is cut into windows of ``k_m`` steps (the dwell time); ``b = ⌊k / k_m⌋`` counts windows.

- ``"sliding"`` (Section 3.2): drone ``D_j`` (j = 1..M) is commanded to ``m_{b' + j}`` with
  ``b' = b mod (N − M + 1)``: the window of M consecutive midpoints slides by one each dwell
  period until it reaches ``m_N`` and then jumps back to ``m_1 … m_M``. With ``M ≥ N`` every
  midpoint has its own drone (``D_j → m_{((j−1) mod N) + 1}``) and nothing moves.
- ``"partition"`` (the two-drone simulation of Section 4.1): the followers are split into M
  contiguous groups as even as possible and each drone cycles through its own group.

``offset`` shifts the starting window (the paper's one-drone run starts at ``m_4``: offset 3).
Followers are numbered 1..N like the paper; the returned tuple holds one follower per drone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from relloc.core import checks
from relloc.errors import ConfigError

Policy = Literal["sliding", "partition"]


@dataclass(frozen=True, kw_only=True)
class DroneSchedule:
    """Midpoint schedule for ``n_drones`` drones over ``n_followers`` followers.

    Counts are integers (a whole float such as ``2.0`` is not one): ``n_followers``,
    ``n_drones`` and ``dwell_steps`` ≥ 1, ``offset`` ≥ 0; else ConfigError naming the field.
    """

    n_followers: int
    n_drones: int
    dwell_steps: int
    policy: Policy = "sliding"
    offset: int = 0

    def __post_init__(self) -> None:
        checks.count(self.n_followers, "DroneSchedule.n_followers")
        checks.count(self.n_drones, "DroneSchedule.n_drones")
        checks.count(self.dwell_steps, "DroneSchedule.dwell_steps")
        checks.count(self.offset, "DroneSchedule.offset", low=0)
        if self.policy not in ("sliding", "partition"):
            raise ConfigError(
                f"DroneSchedule.policy: 'sliding' or 'partition', got {self.policy!r}"
            )

    def groups(self) -> tuple[tuple[int, ...], ...]:
        """The followers each drone cycles through (``partition``; for ``sliding`` all of them)."""
        n, m = self.n_followers, self.n_drones
        if self.policy == "sliding":
            return tuple(tuple(range(1, n + 1)) for _ in range(m))
        if m >= n:
            return tuple((j % n + 1,) for j in range(m))
        sizes = [n // m + (1 if j < n % m else 0) for j in range(m)]
        out, start = [], 1
        for size in sizes:
            out.append(tuple(range(start, start + size)))
            start += size
        return tuple(out)

    def targets(self, step: int) -> tuple[int, ...]:
        """Follower whose midpoint each drone is commanded to at time step ``step`` (an
        integer ≥ 0, else ConfigError)."""
        checks.count(step, "DroneSchedule.targets: step", low=0)
        n, m = self.n_followers, self.n_drones
        b = step // self.dwell_steps + self.offset
        if self.policy == "partition":
            return tuple(group[b % len(group)] for group in self.groups())
        if m >= n:
            return tuple(j % n + 1 for j in range(m))
        window = b % (n - m + 1)
        return tuple(window + j + 1 for j in range(m))
