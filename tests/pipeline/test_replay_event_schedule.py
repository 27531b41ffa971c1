"""The replay's schedule, derived by hand from its documented rules: which event times exist,
which velocities are held over each step (each robot's last report at or before the previous
event), which readings are fed at which event (stamps in ``(t_{k−1}, t_k]``, ties within
TIME_TOL merged, both ends of the window inclusive), the clock mode (first tick at or after the
stamp, every tick recorded), and the small helpers ``feed_ticks``, ``merge_times`` and
``record_grid``."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.contract import Belief, HeldOdometry, Silent
from relloc.core.recording import Measurements, Odometry, Recording, measurement_rows
from relloc.errors import ConfigError
from relloc.pipeline.replay import feed_ticks, merge_times, record_grid, replay


class _Probe(Silent):
    """Logs every call of the event loop."""

    owner = "a"
    name = "probe"

    def __init__(self) -> None:
        self.advanced: list[tuple[float, np.ndarray, np.ndarray]] = []
        self.fed: list[tuple[float, list[float]]] = []

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        self.advanced.append((t, odometry.velocity.copy(), odometry.stamp.copy()))

    def measure(self, batch: Measurements) -> None:
        self.fed.append((self.advanced[-1][0], [float(v) for v in batch.t]))

    def beliefs(self) -> list[Belief]:
        return [Belief(subject="b", frame="world_position2", mean=np.zeros(2), cov=np.eye(2))]


def _velocities(n: int, base: float) -> np.ndarray:
    return np.array([[base + k, 0.0, 0.0, 0.1 * (k + 1)] for k in range(n)])


def _recording() -> Recording:
    odo_a = Odometry(t=np.array([0.0, 0.5]), velocity=_velocities(2, 1.0), sigma=(0, 0, 0, 0))
    odo_b = Odometry(
        t=np.array([0.0, 0.25, 0.75]), velocity=_velocities(3, 10.0), sigma=(0, 0, 0, 0)
    )
    stamps = np.array([0.0, 0.1, 0.5, 0.5 + 5e-10, 0.9, 1.0, 1.2])
    rows = measurement_rows("range", t=stamps, observer=1, target=0, value=np.ones(stamps.size))
    return Recording(
        robots=("a", "b"), platforms=("ground",) * 2, odometry=(odo_a, odo_b), measurements=rows
    )


def test_events_held_velocities_and_fed_readings() -> None:
    probe = _Probe()
    est = replay(_recording(), [probe], record_times=np.array([0.0, 1.0]), start=0.0, end=1.0)
    times = [t for t, _, _ in probe.advanced]
    # {window ends} ∪ {record times} ∪ {reading stamps, 0.5 and 0.5 + 5e-10 merged} ∪
    # {odometry stamps strictly inside the window}
    assert times == pytest.approx([0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0], abs=1e-12)
    # velocity over the step ending at t_k: last report at or before t_{k−1}
    a_held = [v[0, 0] for _, v, _ in probe.advanced]
    b_held = [v[1, 0] for _, v, _ in probe.advanced]
    assert a_held == [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]
    assert b_held == [10.0, 10.0, 10.0, 11.0, 11.0, 12.0, 12.0]
    b_stamp = [s[1] for _, _, s in probe.advanced]
    assert b_stamp == [0.0, 0.0, 0.0, 0.25, 0.25, 0.75, 0.75]
    # readings: at their own event, both ends of the window included; the 1.2 s one left out
    assert probe.fed == [
        (0.0, [0.0]),
        (0.1, [0.1]),
        (0.5, [0.5, 0.5 + 5e-10]),
        (0.9, [0.9]),
        (1.0, [1.0]),
    ]
    assert est.counts["rows_outside_window"] == 1
    assert est.series("a", "b").t.tolist() == [0.0, 1.0]


def test_clock_mode_feeds_at_the_first_tick_at_or_after_the_stamp() -> None:
    probe = _Probe()
    est = replay(_recording(), [probe], clock=np.array([0.0, 0.3, 0.6, 0.9, 1.2]))
    assert [t for t, _, _ in probe.advanced] == [0.0, 0.3, 0.6, 0.9, 1.2]
    assert probe.fed == [
        (0.0, [0.0]),
        (0.3, [0.1]),
        (0.6, [0.5, 0.5 + 5e-10]),
        (0.9, [0.9]),
        (1.2, [1.0, 1.2]),
    ]
    # held at the previous tick: b reported 11 at 0.25 (before tick 0.3) and 12 at 0.75
    # (before tick 0.9, so first held over the step that ends at 1.2)
    assert [v[1, 0] for _, v, _ in probe.advanced] == [10.0, 10.0, 11.0, 11.0, 12.0]
    # every tick is a record time by default, the first included
    assert est.series("a", "b").t.tolist() == [0.0, 0.3, 0.6, 0.9, 1.2]


def test_feed_ticks_uses_the_tick_at_the_stamp_itself() -> None:
    ticks = np.array([0.0, 0.5, 1.0, 1.5])
    got = feed_ticks(np.array([0.0, 0.2, 1.0, 1.0 + 5e-10, 1.0 - 5e-10, 1.4]), ticks)
    np.testing.assert_array_equal(got, [0.0, 0.5, 1.0, 1.0, 1.0, 1.5])


def test_merge_times_merges_only_stamps_within_the_tolerance() -> None:
    got = merge_times(np.array([0.3, 0.1]), np.array([0.1 + 5e-10, 0.2, 0.3 + 1e-6]))
    np.testing.assert_allclose(got, [0.1, 0.2, 0.3, 0.3 + 1e-6], rtol=0, atol=1e-15)


def test_record_grid_includes_an_end_that_rounding_puts_just_short() -> None:
    # (0.6 − 0.2) · 10 = 3.9999999999999996 in floating point: the end still belongs to the grid
    np.testing.assert_allclose(record_grid(0.2, 0.6, 10.0), [0.2, 0.3, 0.4, 0.5, 0.6])
    np.testing.assert_allclose(record_grid(1.0, 1.25, 4.0), [1.0, 1.25])


@pytest.mark.parametrize("clock", [[0.0, 0.5, 0.5, 1.0], [0.0, 0.5, 0.5 + 1e-10, 1.0]])
def test_clock_ticks_closer_than_the_tolerance_are_refused(clock: list[float]) -> None:
    with pytest.raises(ConfigError, match="strictly increasing"):
        replay(_recording(), [_Probe()], clock=np.array(clock))


def test_a_record_time_just_after_an_event_records_at_that_event() -> None:
    probe = _Probe()
    est = replay(
        _recording(), [probe], record_times=np.array([0.0, 0.5 + 5e-10, 1.0]), start=0.0, end=1.0
    )
    assert est.series("a", "b").t.tolist() == [0.0, 0.5, 1.0]
