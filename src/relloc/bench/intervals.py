"""``relloc bench intervals``: how often the NEES-share intervals hold the true share.

Every consistency verdict on a single run or a shared recording rests on the interval of
:func:`relloc.metrics.consistency.percent_beyond_interval`. This benchmark measures its
coverage by seeded Monte Carlo on values whose share beyond the bound is known exactly: the
NEES ``ε_t = |e_t|²`` of a consistent filter's 3-DOF errors, each error component an AR(1)
series of unit stationary variance,

    e_t = ρ e_{t−1} + √(1 − ρ²) w_t,   w_t ~ N(0, I₃),   e_0 ~ N(0, I₃),

so every ``ε_t`` is χ²(3) and exactly 5 % of them lie beyond ``χ²₃(0.95)``, while neighbours
are correlated: ``corr(ε_t, ε_{t+k}) = ρ^{2k}`` (for a Gaussian ``e``, ``cov(e², e'²) =
2 cov(e, e')²``), an integrated correlation time of ``τ = (1 + ρ²)/(1 − ρ²)`` samples. One
sample is one second.

Designs, each ``draws`` times:

* ``one_run``: one run of ``samples`` values per ρ of ``rhos``, ten time blocks (the default
  of every report). Beside the coverage: the mean estimated correlation time
  (``correlation_time_s``, :func:`~relloc.metrics.consistency.integrated_time` on ranks)
  against the true ``τ``, a block's length in true ``τ``, the share of draws flagged
  ``blocks_short`` and the coverage among flagged and unflagged draws — whether the flag
  marks the intervals that are too narrow.
* ``subjects``: one run of ``samples`` values of ``subjects`` subjects (robots of one team) at
  ρ ``subjects_rho``, a share ``c`` of each error's variance common to every subject at the
  same instant (a shared landmark, a shared drift) and the rest each subject's own, for each
  ``c`` of ``subject_shares`` — whether the correlation-time interval counts subjects right
  (``N_τ`` from the spread of the share over the instants).
* ``independent_runs``: ``runs`` independent runs of ``run_samples`` values at ρ
  ``runs_rho``, each run a cluster (Monte Carlo experiments).
* ``shared_recording``: ``shared_runs`` runs of ``samples`` values replaying one recording,
  half of each error's variance shared by every run at the same instant (the recording's
  odometry) and half the run's own (fresh sensor noise), both AR(1) with ρ ``runs_rho``;
  two-way clustered by runs and time blocks (``shared_recording=True``).

The named baseline, measured on the same draws: the binomial interval that takes every value
as independent (the same function given each value as its own run: ``N_eff = N``), which is
what a report quoting ``√(p(1−p)/N)`` would claim. Where time blocks are clustered a second
comparison (``batch_means_coverage``): the batch means' interval alone, before it is widened to
the correlation-time interval on short blocks (what the reports used until that widening). A
valid interval covers 5 % in about 95 % of draws; the Monte Carlo error of a coverage is about
``√(0.95·0.05/draws)`` (0.013 for 300).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from scipy.signal import lfilter

from relloc.core.checks import count, number
from relloc.errors import ConfigError
from relloc.metrics.consistency import (
    INTERVAL_BATCHES,
    BeyondShare,
    chi2_upper,
    percent_beyond_interval,
)

DOF = 3
TRUE_PERCENT = 5.0
"""The share (%) of χ²(3) values beyond χ²₃(0.95): what every interval should hold."""
SEED = 20261206
"""The Monte Carlo's seed root (printed and written with the numbers)."""


@dataclass(frozen=True, kw_only=True)
class IntervalBenchSize:
    """The Monte Carlo's size (module docstring)."""

    draws: int = 300
    samples: int = 4500
    rhos: tuple[float, ...] = (0.9, 0.97, 0.99, 0.995, 0.997)
    runs: int = 30
    run_samples: int = 150
    runs_rho: float = 0.97
    shared_runs: int = 5
    subjects: int = 5
    subjects_rho: float = 0.997
    subject_shares: tuple[float, ...] = (0.0, 0.5, 0.9, 0.97, 0.99, 1.0)

    def __post_init__(self) -> None:
        for name in ("draws", "samples", "runs", "run_samples", "shared_runs", "subjects"):
            count(getattr(self, name), f"IntervalBenchSize.{name}", low=2)
        rhos = {
            "rhos": self.rhos,
            "runs_rho": (self.runs_rho,),
            "subjects_rho": (self.subjects_rho,),
        }
        for name, values in rhos.items():
            for rho in values:
                number(rho, f"IntervalBenchSize.{name} (a ρ)", low=0.0, high=1.0, open_high=True)
        for share in self.subject_shares:
            number(share, "IntervalBenchSize.subject_shares", low=0.0, high=1.0)
        if not self.rhos:
            raise ConfigError("IntervalBenchSize.rhos: at least one ρ")


def ar1_errors(rng: np.random.Generator, rho: float, shape: tuple[int, ...]) -> np.ndarray:
    """Errors of ``shape`` (time on axis −2, the DOF on axis −1), AR(1) along time with unit
    stationary variance (module docstring)."""
    w = rng.standard_normal(shape)
    w[..., 1:, :] *= np.sqrt(1.0 - rho**2)
    return lfilter([1.0], [1.0, -rho], w, axis=-2)


def correlation_time(rho: float) -> float:
    """``τ = (1 + ρ²)/(1 − ρ²)``: the integrated correlation time (samples) of the NEES."""
    return (1.0 + rho**2) / (1.0 - rho**2)


def _holds(interval: tuple[float, float] | None) -> bool:
    return interval is not None and interval[0] <= TRUE_PERCENT <= interval[1]


def _independent_baseline(values: np.ndarray) -> BeyondShare:
    """The baseline: every value taken as its own independent run."""
    v = values.reshape(-1)
    return percent_beyond_interval(v, np.zeros(v.size), chi2_upper(DOF), runs=np.arange(v.size))


def _mean_of_known(values: list[float | None]) -> float | None:
    """The mean of the values the draws gave (a share without an interval has no effective
    sample size: left out, not counted as 0); None when no draw gave one."""
    known = [v for v in values if v is not None]
    return float(np.mean(known)) if known else None


def _coverage(draws: int, draw: Callable[[], tuple[BeyondShare, BeyondShare]]) -> dict[str, Any]:
    """Coverage of the interval and of the baseline over ``draws`` draws, with the mean
    interval widths and, for time blocks, the correlation-time figures."""
    shares = [draw() for _ in range(draws)]
    ours = [s for s, _ in shares]
    base = [b for _, b in shares]
    covered = np.array([_holds(s.interval) for s in ours])
    out: dict[str, Any] = {
        "coverage": float(covered.mean()),
        "baseline_coverage": float(np.mean([_holds(b.interval) for b in base])),
        "mean_width_pct": float(
            np.mean([s.interval[1] - s.interval[0] for s in ours if s.interval])
        ),
        "baseline_mean_width_pct": float(
            np.mean([b.interval[1] - b.interval[0] for b in base if b.interval])
        ),
        "mean_effective_samples": _mean_of_known([s.effective_samples for s in ours]),
    }
    if ours[0].batch_s is not None and ours[0].correlation_time_s is not None:
        short = np.array([bool(s.blocks_short) for s in ours])
        batch = [s.batch_means_interval for s in ours if s.batch_means_interval]
        out |= {
            "batch_means_coverage": float(np.mean([_holds(s.batch_means_interval) for s in ours])),
            "batch_means_mean_width_pct": float(np.mean([hi - lo for lo, hi in batch])),
            "mean_correlation_samples": float(np.mean([s.correlation_samples for s in ours])),
            "mean_correlation_time_s": float(np.mean([s.correlation_time_s for s in ours])),
            "blocks_short_share": float(short.mean()),
            "blocks_short_draws": int(short.sum()),
            "coverage_blocks_short": float(covered[short].mean()) if short.any() else None,
            "coverage_blocks_long": float(covered[~short].mean()) if (~short).any() else None,
        }
    return out


def _one_run(rng: np.random.Generator, rho: float, n: int) -> tuple[BeyondShare, BeyondShare]:
    v = np.sum(ar1_errors(rng, rho, (n, DOF)) ** 2, axis=-1)
    return percent_beyond_interval(v, np.arange(n, dtype=float), chi2_upper(DOF)), (
        _independent_baseline(v)
    )


def _subjects(
    rng: np.random.Generator, rho: float, subjects: int, common: float, n: int
) -> tuple[BeyondShare, BeyondShare]:
    """One run of ``subjects`` subjects' ``n`` values, a share ``common`` of each error's
    variance the same for every subject at an instant."""
    e = np.sqrt(common) * ar1_errors(rng, rho, (n, DOF))[None] + np.sqrt(1.0 - common) * (
        ar1_errors(rng, rho, (subjects, n, DOF))
    )
    v = np.sum(e**2, axis=-1)
    t = np.broadcast_to(np.arange(n, dtype=float), v.shape)
    return percent_beyond_interval(v.reshape(-1), t.reshape(-1), chi2_upper(DOF)), (
        _independent_baseline(v)
    )


def _several_runs(
    rng: np.random.Generator, rho: float, runs: int, n: int, *, shared: bool
) -> tuple[BeyondShare, BeyondShare]:
    """``runs`` runs of ``n`` values: independent, or (``shared``) replaying one recording,
    half of each error's variance common to every run at the same instant."""
    common = ar1_errors(rng, rho, (n, DOF)) if shared else None
    e = ar1_errors(rng, rho, (runs, n, DOF))
    if common is not None:
        e = np.sqrt(0.5) * (common[None] + e)
    v = np.sum(e**2, axis=-1)
    t = np.broadcast_to(np.arange(n, dtype=float), v.shape)
    r = np.broadcast_to(np.arange(runs)[:, None], v.shape)
    share = percent_beyond_interval(
        v.reshape(-1), t.reshape(-1), chi2_upper(DOF), runs=r.reshape(-1), shared_recording=shared
    )
    return share, _independent_baseline(v)


def run(
    quiet: bool = False, size: IntervalBenchSize | None = None, seed: int = SEED
) -> dict[str, Any]:
    size = size or IntervalBenchSize()
    rngs = [
        np.random.default_rng(s)
        for s in np.random.SeedSequence(seed).spawn(len(size.rhos) + 2 + len(size.subject_shares))
    ]
    started = time.perf_counter()
    one_run = {}
    for rho, rng in zip(size.rhos, rngs, strict=False):
        figures = _coverage(size.draws, partial(_one_run, rng, rho, size.samples))
        tau = correlation_time(rho)
        block = size.samples / INTERVAL_BATCHES
        one_run[f"{rho:g}"] = {
            "rho": rho,
            "true_correlation_time_s": tau,
            "block_s": block,
            "block_in_correlation_times": block / tau,
            **figures,
        }
    independent = _coverage(
        size.draws,
        partial(
            _several_runs,
            rngs[len(size.rhos)],
            size.runs_rho,
            size.runs,
            size.run_samples,
            shared=False,
        ),
    )
    shared = _coverage(
        size.draws,
        partial(
            _several_runs,
            rngs[len(size.rhos) + 1],
            size.runs_rho,
            size.shared_runs,
            size.samples,
            shared=True,
        ),
    )
    subjects = {
        f"{common:g}": {
            "common_share": common,
            **_coverage(
                size.draws,
                partial(_subjects, rng, size.subjects_rho, size.subjects, common, size.samples),
            ),
        }
        for common, rng in zip(size.subject_shares, rngs[len(size.rhos) + 2 :], strict=True)
    }
    result: dict[str, Any] = {
        "seed": seed,
        "true_percent": TRUE_PERCENT,
        "size": size.__dict__,
        "one_run": one_run,
        "subjects": {
            "subjects": size.subjects,
            "rho": size.subjects_rho,
            "block_in_correlation_times": size.samples
            / INTERVAL_BATCHES
            / correlation_time(size.subjects_rho),
            "by_common_share": subjects,
        },
        "independent_runs": {"rho": size.runs_rho, "runs": size.runs, **independent},
        "shared_recording": {"rho": size.runs_rho, "runs": size.shared_runs, **shared},
        "baseline": "binomial: every value taken as independent (N_eff = N)",
        "monte_carlo_error": float(np.sqrt(0.95 * 0.05 / size.draws)),
        "wall_s": time.perf_counter() - started,
        "load_average": list(os.getloadavg()),
    }
    if not quiet:
        _print(result)
    return result


def _print(r: dict[str, Any]) -> None:
    print(
        f"coverage of the 95 % NEES-share interval (true share {r['true_percent']:g} %), "
        f"seed {r['seed']}, {r['size']['draws']} draws each (Monte Carlo error "
        f"±{r['monte_carlo_error']:.3f}); baseline: {r['baseline']}"
    )
    print(
        f"{'one run, 10 blocks':>22} {'τ (s)':>7} {'τ̂ (s)':>7} {'block/τ':>8} "
        f"{'coverage':>9} {'batch':>6} {'baseline':>9} {'width':>6} {'batch':>6} "
        f"{'short':>6} {'cov|short':>12} {'cov|long':>12}"
    )
    for v in r["one_run"].values():
        short, long = v["blocks_short_draws"], r["size"]["draws"] - v["blocks_short_draws"]
        short_cov, long_cov = (
            _of(v["coverage_blocks_short"], short),
            _of(v["coverage_blocks_long"], long),
        )
        print(
            f"{'ρ = ' + format(v['rho'], 'g'):>22} {v['true_correlation_time_s']:7.1f} "
            f"{v['mean_correlation_time_s']:7.1f} {v['block_in_correlation_times']:8.1f} "
            f"{v['coverage']:9.3f} {v['batch_means_coverage']:6.3f} "
            f"{v['baseline_coverage']:9.3f} {v['mean_width_pct']:6.1f} "
            f"{v['batch_means_mean_width_pct']:6.1f} {short:6d} "
            f"{short_cov:>12} {long_cov:>12}"
        )
    print(
        "  (coverage: the interval the reports use; batch: batch means alone, before the "
        "widening on short blocks; width: mean width, %)"
    )
    s = r["subjects"]
    for v in s["by_common_share"].values():
        print(
            f"{s['subjects']} subjects, ρ {s['rho']:g} (blocks of "
            f"{s['block_in_correlation_times']:.1f} τ), {v['common_share']:.0%} of the error "
            f"common: coverage {v['coverage']:.3f}, batch means alone "
            f"{v['batch_means_coverage']:.3f}, baseline {v['baseline_coverage']:.3f}; width "
            f"{v['mean_width_pct']:.1f} % against {v['batch_means_mean_width_pct']:.1f} %"
        )
    for name in ("independent_runs", "shared_recording"):
        v = r[name]
        print(
            f"{name.replace('_', ' ')} ({v['runs']} runs, ρ {v['rho']:g}): coverage "
            f"{v['coverage']:.3f}, baseline {v['baseline_coverage']:.3f}; mean width "
            f"{v['mean_width_pct']:.2f} % against {v['baseline_mean_width_pct']:.2f} %"
        )
    print(f"wall {r['wall_s']:.1f} s, load average {r['load_average'][0]:.2f}")


def _of(coverage: float | None, draws: int) -> str:
    """A coverage with the number of draws it is measured on."""
    return "—" if coverage is None else f"{coverage:.3f} ({draws})"
