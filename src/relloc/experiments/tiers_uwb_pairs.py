"""The pair part of ``relloc reproduce tiers-uwb``: seed 000's relative localization of two
robots from UWB range and both odometries from an unknown start
(:class:`~relloc.estimators.uwb_range.RangePairBank`), beside odometry alone and uncalibrated
ranges, with the observability verdict of relloc's own tool along the recorded motion.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from relloc.core.kalman import chi2_threshold
from relloc.core.recording import Recording
from relloc.estimators.uwb_range import RangePairBank, RangePairSettings, RelativeDeadReckoning
from relloc.metrics.consistency import percent_beyond_interval
from relloc.models.motion import VelocityNoise
from relloc.models.symbolic import relative_nonlinear
from relloc.observability.analysis import InputRankEvaluator, analyse
from relloc.pipeline.evaluation import SeriesEvaluation, convergence_time, evaluate
from relloc.pipeline.replay import record_grid, replay

#: A robot whose odometry path is longer than this (m) moves.
MOVING_M = 0.2
#: Position error (m) and relative-yaw error (rad) below which a pair counts as converged.
CONVERGED_M = 0.3
CONVERGED_YAW = 0.5
#: Beliefs are recorded (and scored) at this rate.
RECORD_HZ = 10.0
#: Observability is checked at this many instants of the scored stretch.
OBSERVABILITY_SAMPLES = 40


def moving_pairs(rec: Recording) -> list[tuple[int, int]]:
    """Pairs with odometry on both robots, a range between them, and one moving by odometry."""
    m = rec.measurements
    has_odo = [od.t.size >= 2 for od in rec.odometry]
    path = [
        float(np.sum(np.linalg.norm(od.velocity[:-1, :3], axis=1) * np.diff(od.t)))
        if od.t.size >= 2
        else 0.0
        for od in rec.odometry
    ]
    out = []
    for i in range(rec.n_robots):
        for j in range(i + 1, rec.n_robots):
            linked = bool(
                (
                    ((m.observer == i) & (m.target == j)) | ((m.observer == j) & (m.target == i))
                ).any()
            )
            if has_odo[i] and has_odo[j] and linked and max(path[i], path[j]) > MOVING_M:
                out.append((i, j))
    return out


def observability(rec: Recording, i: int, j: int, t0: float, t1: float) -> dict[str, Any]:
    """Rank of the range-only seed-000 model along the recorded relative states and inputs."""
    evaluator = _range_pair_rank()
    model = evaluator.model
    t = np.linspace(t0, t1, OBSERVABILITY_SAMPLES)
    states = rec.relative_truth(i, j, t)
    u = np.hstack([rec.odometry[i].held_at(t), rec.odometry[j].held_at(t)])
    ranks = np.array([evaluator.rank(states[k], u[k]) for k in range(t.size)])
    full = float(np.mean(ranks == model.n))
    generic = _generic_conditions()
    if full == 1.0:
        verdict = "observable along the whole stretch"
    elif full > 0.0:
        verdict = f"observable at {100 * full:.0f} % of the sampled instants"
    else:
        verdict = f"unobservable along this stretch (rank ≤ {int(ranks.max())} of {model.n})"
    return {
        "verdict": verdict,
        "full_rank_share": full,
        "max_rank": int(ranks.max()),
        "state_dim": model.n,
        "samples": int(t.size),
        "generic_conditions": generic,
    }


@lru_cache(maxsize=1)
def _range_pair_rank() -> InputRankEvaluator:
    """The rank evaluator of the range-only seed-000 pair (built once per process)."""
    return InputRankEvaluator.build(relative_nonlinear(("range",)))


@lru_cache(maxsize=1)
def _generic_conditions() -> str:
    """The generic rank and input conditions of the range-only pair (once per process)."""
    result = analyse(relative_nonlinear(("range",)), order=3, samples=3, directions="none")
    return f"generic rank {result.rank} of {result.state_dim}; {result.conditions_text()}"


def _pair_score(ev: SeriesEvaluation) -> dict[str, Any]:
    pos = np.linalg.norm(ev.error[:, :3], axis=1)
    share = percent_beyond_interval(ev.nees, ev.t, chi2_threshold(4, 0.95))
    return {
        "pos_rmse_m": float(np.sqrt(np.mean(pos**2))) if pos.size else None,
        "nees_pct_beyond": share.percent if share.samples else None,
        "nees_beyond_interval": share.to_dict(),
        "converged_after_s": convergence_time(ev, [CONVERGED_M] * 3 + [CONVERGED_YAW]),
        "records": int(ev.t.size),
    }


def pair_case(
    rec: Recording, raw: Recording, i: int, j: int, t0: float, t1: float, sigma: float
) -> dict[str, Any]:
    """Range + odometry pair from an unknown start, with its baselines and observability."""
    noise = VelocityNoise.of(rec.odometry[i].sigma, rec.odometry[j].sigma)
    settings = RangePairSettings(sigma_range=sigma)
    grid = record_grid(t0, t1, RECORD_HZ)

    def score(recording: Recording, est: Any) -> dict[str, Any]:
        estimates = replay(recording, [est], record_times=grid, start=t0, end=t1)
        evs = evaluate(estimates, recording)
        scored = _pair_score(evs[0]) if evs else {"pos_rmse_m": None, "records": 0}
        return scored | {"ranges_gated": estimates.counts.get("ranges_gated", 0)}

    out = score(rec, RangePairBank(i, j, rec.robots, noise, settings))
    truth0 = rec.relative_truth(i, j, t0)[0]
    dead = RelativeDeadReckoning(i, j, rec.robots, noise, (t0, truth0, np.eye(4) * 1e-4))
    out["baselines"] = {
        "uncalibrated": {
            "pos_rmse_m": score(raw, RangePairBank(i, j, rec.robots, noise, settings))["pos_rmse_m"]
        },
        "odometry_alone": {"pos_rmse_m": score(rec, dead)["pos_rmse_m"]},
    }
    out["observability"] = observability(rec, i, j, t0, t1)
    return out
