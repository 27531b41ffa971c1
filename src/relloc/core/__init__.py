"""Core containers and math shared by every estimator (no filter logic here)."""

from relloc.core.angles import angle_diff, circular_interp, wrap_angle
from relloc.core.gaussian import Gaussian, GaussianMixture, InformationState
from relloc.core.linalg import (
    cholesky,
    condition_log10,
    is_psd,
    joseph_update,
    mahalanobis_sq,
    solve_psd,
    symmetrise,
)
from relloc.core.poses import compose, inverse, relative

__all__ = [
    "Gaussian",
    "GaussianMixture",
    "InformationState",
    "angle_diff",
    "cholesky",
    "circular_interp",
    "compose",
    "condition_log10",
    "inverse",
    "is_psd",
    "joseph_update",
    "mahalanobis_sq",
    "relative",
    "solve_psd",
    "symmetrise",
    "wrap_angle",
]
