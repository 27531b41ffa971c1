"""Core containers and math shared by every estimator: angles, poses, PSD-safe linear algebra,
the belief containers, and the one Kalman update and χ² gate (:mod:`relloc.core.kalman`)."""

from relloc.core.angles import angle_diff, circular_interp, wrap_angle
from relloc.core.gaussian import Gaussian, GaussianMixture, InformationState
from relloc.core.kalman import Innovation, chi2_threshold, gated_update, kalman_update
from relloc.core.linalg import (
    cholesky,
    condition_log10,
    mahalanobis_sq,
    solve_psd,
    symmetrise,
)
from relloc.core.poses import compose, inverse, relative

__all__ = [
    "Gaussian",
    "GaussianMixture",
    "InformationState",
    "Innovation",
    "angle_diff",
    "chi2_threshold",
    "cholesky",
    "circular_interp",
    "compose",
    "condition_log10",
    "gated_update",
    "inverse",
    "kalman_update",
    "mahalanobis_sq",
    "relative",
    "solve_psd",
    "symmetrise",
    "wrap_angle",
]
