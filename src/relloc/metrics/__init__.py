"""Metrics: errors with angle wrapping, RMSE, NEES/NIS with chi-square bands, conditioning,
convergence time."""

from relloc.metrics.conditioning import ILL_CONDITIONED_LOG10, condition_log10_batch
from relloc.metrics.consistency import (
    BeyondShare,
    anees,
    anees_band,
    chi2_upper,
    clopper_pearson,
    integrated_time,
    mean_chi2_band,
    nees,
    nis,
    normalised_squared,
    percent_beyond,
    percent_beyond_interval,
    projected_nees,
    run_average_band,
)
from relloc.metrics.convergence import (
    FIXED_THRESHOLDS,
    PAPER_MARGIN,
    paper_thresholds,
    updates_to_converge,
    updates_to_converge_per_state,
)
from relloc.metrics.errors import RELPOSE4_ANGLES, radial_errors, rmse, state_errors

__all__ = [
    "FIXED_THRESHOLDS",
    "ILL_CONDITIONED_LOG10",
    "PAPER_MARGIN",
    "RELPOSE4_ANGLES",
    "BeyondShare",
    "anees",
    "anees_band",
    "chi2_upper",
    "clopper_pearson",
    "condition_log10_batch",
    "integrated_time",
    "mean_chi2_band",
    "nees",
    "nis",
    "normalised_squared",
    "paper_thresholds",
    "percent_beyond",
    "percent_beyond_interval",
    "projected_nees",
    "radial_errors",
    "rmse",
    "run_average_band",
    "state_errors",
    "updates_to_converge",
    "updates_to_converge_per_state",
]
