"""First-estimates Jacobians (FEJ) for the team filter: keeping the unobservable frame unobservable.

Huang, Mourikis & Roumeliotis (2008, 2010: observability-based consistent EKF estimators for
cooperative localization) show why a linearised filter of a robot team without absolute
information is inconsistent, and that evaluating every Jacobian at the *first* estimate of the
state it differentiates restores the right observability. This module holds that choice for
:class:`relloc.estimators.cooperative.CooperativeEstimator` (setting
``CooperativeSettings.linearisation = "first_estimates"``); the EIF and the EKF use it alike,
because it only changes the Jacobians they are handed.

Why the standard EKF/EIF gains spurious information
---------------------------------------------------
With ``X_i = (p_i, ψ_i)``, ``J = [[0, −1], [1, 0]]``, the midpoint unicycle step of robot ``i``
has the error-state transition

    Φ_k,i = [[I₂, J (p̂_{k+1} − p̂_k)], [0ᵀ, 1]],

(the heading column of the step's Jacobian is ``J`` times the displacement it produced), and a
bearing or range between robots depends only on ``p_j − p_i`` and ``ψ_i − (direction)``. Without
landmarks the nonlinear team (seed 001 Theorem 2) cannot see a common translation of all robots
nor a common rotation of the whole team about the origin: per robot, the directions

    N_t,i = [[I₂], [0ᵀ]],          N_r,i = [[J p_i], [1]]

span the unobservable subspace ``N`` (3 directions); with one landmark at ``p_L`` only the
rotation about it, ``[[J (p_i − p_L)], [1]]``, is left (Theorem 3). The linearised system has
the same unobservable subspace only if ``N`` travels with the transitions and stays in the
null space of every measurement Jacobian:

    N_{k+1} = Φ_k N_k,      H_{k+1} N_{k+1} = 0      for every k.

Translation satisfies this at any linearisation point (``Φ N_t = N_t``, ``H N_t = 0``). Rotation
does not for the standard filter: ``H_{k+1}`` is evaluated at the predicted ``p̂_{k+1|k}`` and
``N_k`` at the prior ``p̂_{k|k−1}`` used by ``H_k``, but ``Φ_k`` at the *updated* ``p̂_{k|k}``, so

    Φ_k N_r,k = [[J (p̂_{k+1|k} − p̂_{k|k} + p̂_{k|k−1})], [1]]
              = N_r,k+1 + [[J (p̂_{k|k−1} − p̂_{k|k})], [0]],

and ``H_{k+1}`` sees the extra column, the update's correction. The linearised system then
"observes" the global rotation (rank ``3n − 2`` instead of ``3n − 3``): the filter removes
uncertainty along a direction on which no measurement carries information, its covariance ends
up smaller than its error (NEES far above χ², ``relloc reproduce sharma2013``), and through the
rotation–translation coupling the positions are over-confident too.

The first-estimates choice
--------------------------
Evaluate ``Φ_k`` with the two *propagated* estimates, ``J (p̂_{k+1|k} − p̂_{k|k−1})``, and every
``H_k`` at ``p̂_{k|k−1}``: each state ``X_k`` is then differentiated at one point only, its first
estimate, and

    Φ_k N_r(p̂_{k|k−1}) = N_r(p̂_{k+1|k}),      H_{k+1} N_r(p̂_{k+1|k}) = 0,

so the linearised system keeps exactly the nonlinear system's unobservable subspace (the
rotation about the landmark likewise, with ``p_i − p_L``). Residuals ``z − h(X̂)`` and the mean
propagation stay at the latest estimate; the input Jacobian ``G`` does not enter ``N`` and stays
there too. Between two measurement epochs the only estimate of each intermediate pose is the
propagated one, so of the steps accumulated since the last epoch only the first changes: the
composite transition (:func:`first_estimates_transition`) is

    Φ_i = [[I₂, J (p̂_i(now) − p̂_i(last epoch, before its update))], [0ᵀ, 1]].

A second epoch at the same instant (no motion between) keeps ``Φ = I`` and linearises its rows
at the first estimate of that instant (the prior of the first epoch there).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def first_estimates_transition(pose_now: Array, first: Array) -> Array:
    """Per-robot composite ``Φ_i (n, 3, 3)`` from the first estimates ``first (n, 3)`` (the
    poses before the last epoch's update) to the propagated poses ``pose_now (n, 3)``."""
    n = pose_now.shape[0]
    F = np.tile(np.eye(3), (n, 1, 1))
    F[:, 0, 2] = -(pose_now[:, 1] - first[:, 1])
    F[:, 1, 2] = pose_now[:, 0] - first[:, 0]
    return F
