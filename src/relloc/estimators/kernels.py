"""Hand-unrolled predict/update kernels for the 4-state relative filter (the hot path).

Numpy on 4 × 4 matrices is dominated by per-call overhead, so the same algebra as
:mod:`relloc.estimators.relative` (exact-ZOH predict, Joseph-form update) is written out entry
by entry here. Every kernel works on "scalars" that are either Python floats (one pair,
:data:`SCALAR_OPS`) or numpy arrays of shape ``(B,)`` holding one entry for ``B`` pairs
(structure of arrays, :data:`ARRAY_OPS`); only the elementary functions differ. The results
equal the general matrix implementation to rounding (tests/estimators/test_kernels.py).

Storage: a mean is ``(x, y, z, φ)``; a symmetric 4 × 4 covariance is its upper triangle
``(p00, p01, p02, p03, p11, p12, p13, p22, p23, p33)``; a symmetric 3 × 3 matrix is
``(s00, s01, s02, s11, s12, s22)``. Both measurement matrices (TEKF and PLKF) have a zero last
column (the yaw does not enter range or bearing), so an update takes the left 3 × 3 block ``A``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from relloc.models.motion import SINC_SERIES_LIMIT, sinc_and_derivative

Scalar = Any  # float, or a numpy array (B,) of one entry for B pairs
Vec = tuple[Scalar, ...]


def _sinc_scalar(a: float) -> tuple[float, float]:
    """Float version of :func:`relloc.models.motion.sinc_and_derivative` (math is ~50x faster
    than numpy on one number)."""
    if abs(a) < SINC_SERIES_LIMIT:
        a2 = a * a
        return 1.0 - a2 / 6.0 + a2 * a2 / 120.0, -a / 3.0 + a * a2 / 30.0
    s, c = math.sin(a), math.cos(a)
    return s / a, (a * c - s) / (a * a)


def _all_scalar(value: bool) -> bool:
    return bool(value)


def _all_array(value: Any) -> bool:
    return bool(np.all(value))


def _any_scalar(value: bool) -> bool:
    return bool(value)


def _any_array(value: Any) -> bool:
    return bool(np.any(value))


def _where_scalar(cond: bool, a: Any, b: Any) -> Any:
    return a if cond else b


@dataclass(frozen=True)
class Ops:
    """The elementary functions a kernel needs, for one kind of scalar."""

    cos: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    sqrt: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    sinc: Callable[[Any], tuple[Any, Any]]
    all: Callable[[Any], bool]
    any: Callable[[Any], bool]
    where: Callable[[Any, Any, Any], Any]


SCALAR_OPS = Ops(
    cos=math.cos,
    sin=math.sin,
    sqrt=math.sqrt,
    atan2=math.atan2,
    sinc=_sinc_scalar,
    all=_all_scalar,
    any=_any_scalar,
    where=_where_scalar,
)
ARRAY_OPS = Ops(
    cos=np.cos,
    sin=np.sin,
    sqrt=np.sqrt,
    atan2=np.arctan2,
    sinc=sinc_and_derivative,
    all=_all_array,
    any=_any_array,
    where=np.where,
)


def predict_kernel(
    m: Vec, P: Vec, u_l: Vec, u_c: Vec, dt: float, var: Vec, ops: Ops
) -> tuple[Vec, Vec]:
    """Exact-ZOH predict: ``x⁻ = f_d(x, u)``, ``P⁻ = F P Fᵀ + G diag(var) Gᵀ``.

    ``var`` are the 8 input variances ``(observer v_x, v_y, v_z, ω, observed v_x, v_y, v_z, ω)``.
    See :func:`relloc.models.motion.relative_jacobians` for ``F`` and ``G``.
    """
    x, y, z, phi = m
    vxl, vyl, vzl, wl = u_l
    vxc, vyc, vzc, wc = u_c
    al = 0.5 * wl * dt
    ac = 0.5 * wc * dt
    snl, dsnl = ops.sinc(al)
    snc, dsnc = ops.sinc(ac)
    c1, s1 = ops.cos(wl * dt), ops.sin(wl * dt)  # R_l = R(−ω_l dt) = [[c1, s1], [−s1, c1]]
    cl, sl = ops.cos(al), ops.sin(al)
    cc, sc = ops.cos(phi + ac), ops.sin(phi + ac)
    cb, sb = ops.cos(phi + ac - wl * dt), ops.sin(phi + ac - wl * dt)
    rvl0, rvl1 = cl * vxl - sl * vyl, sl * vxl + cl * vyl  # R(ω_l dt/2) v_l
    rvc0, rvc1 = cc * vxc - sc * vyc, sc * vxc + cc * vyc  # R(φ + ω_c dt/2) v_c
    dtl, dtc = dt * snl, dt * snc
    dcx, dcy = dtc * rvc0, dtc * rvc1
    wx = x + dcx - dtl * rvl0
    wy = y + dcy - dtl * rvl1
    px = c1 * wx + s1 * wy
    py = -s1 * wx + c1 * wy
    mean = (px, py, z + dt * (vzc - vzl), phi + dt * (wc - wl))

    # F: rotation block R_l and yaw column f = R_l J d_c
    f0 = -c1 * dcy + s1 * dcx
    f1 = s1 * dcy + c1 * dcx
    p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = P
    t00 = c1 * p00 + s1 * p01 + f0 * p03
    t01 = c1 * p01 + s1 * p11 + f0 * p13
    t02 = c1 * p02 + s1 * p12 + f0 * p23
    t03 = c1 * p03 + s1 * p13 + f0 * p33
    t10 = -s1 * p00 + c1 * p01 + f1 * p03
    t11 = -s1 * p01 + c1 * p11 + f1 * p13
    t12 = -s1 * p02 + c1 * p12 + f1 * p23
    t13 = -s1 * p03 + c1 * p13 + f1 * p33

    # G columns that are not constant
    h = 0.5 * dt * dt
    g00, g01 = -dtl * cl, -dtl * sl  # −dt sinc_l R(−ω_l dt/2)
    g10, g11 = dtl * sl, -dtl * cl
    ddl0 = h * (dsnl * rvl0 - snl * rvl1)
    ddl1 = h * (dsnl * rvl1 + snl * rvl0)
    g03 = dt * py - (c1 * ddl0 + s1 * ddl1)
    g13 = -dt * px - (-s1 * ddl0 + c1 * ddl1)
    g04, g05 = dtc * cb, -dtc * sb  # dt sinc_c R(φ + ω_c dt/2 − ω_l dt)
    g14, g15 = dtc * sb, dtc * cb
    ddc0 = h * (dsnc * rvc0 - snc * rvc1)
    ddc1 = h * (dsnc * rvc1 + snc * rvc0)
    g07 = c1 * ddc0 + s1 * ddc1
    g17 = -s1 * ddc0 + c1 * ddc1
    v0, v1, v2, v3, v4, v5, v6, v7 = var
    q00 = v0 * g00 * g00 + v1 * g01 * g01 + v3 * g03 * g03 + v4 * g04 * g04
    q00 = q00 + v5 * g05 * g05 + v7 * g07 * g07
    q01 = v0 * g00 * g10 + v1 * g01 * g11 + v3 * g03 * g13 + v4 * g04 * g14
    q01 = q01 + v5 * g05 * g15 + v7 * g07 * g17
    q11 = v0 * g10 * g10 + v1 * g11 * g11 + v3 * g13 * g13 + v4 * g14 * g14
    q11 = q11 + v5 * g15 * g15 + v7 * g17 * g17
    q03 = dt * (v7 * g07 - v3 * g03)
    q13 = dt * (v7 * g17 - v3 * g13)
    dt2 = dt * dt
    cov = (
        c1 * t00 + s1 * t01 + f0 * t03 + q00,
        -s1 * t00 + c1 * t01 + f1 * t03 + q01,
        t02,
        t03 + q03,
        -s1 * t10 + c1 * t11 + f1 * t13 + q11,
        t12,
        t13 + q13,
        p22 + dt2 * (v2 + v6),
        p23,
        p33 + dt2 * (v3 + v7),
    )
    return mean, cov


def gain_kernel(P: Vec, A: Vec, R: Vec, ops: Ops) -> tuple[Vec, Vec, Vec] | None:
    """Kalman gain for ``H = [A | 0]`` (``A`` row-major 3 × 3): ``S = H P Hᵀ + R``,
    ``K = P Hᵀ S⁻¹`` (``S⁻¹`` by cofactors).

    Returns ``(K, S, S⁻¹)`` with ``K`` row-major 4 × 3 and ``S``, ``S⁻¹`` as upper triangles, or
    ``None`` if some ``S`` is not positive definite (Sylvester's criterion on its leading minors).
    """
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = A
    p00, p01, p02, p03, p11, p12, p13, p22, p23, _p33 = P  # φφ does not enter H P Hᵀ
    # U = P Hᵀ (4 × 3)
    u00 = p00 * a00 + p01 * a01 + p02 * a02
    u01 = p00 * a10 + p01 * a11 + p02 * a12
    u02 = p00 * a20 + p01 * a21 + p02 * a22
    u10 = p01 * a00 + p11 * a01 + p12 * a02
    u11 = p01 * a10 + p11 * a11 + p12 * a12
    u12 = p01 * a20 + p11 * a21 + p12 * a22
    u20 = p02 * a00 + p12 * a01 + p22 * a02
    u21 = p02 * a10 + p12 * a11 + p22 * a12
    u22 = p02 * a20 + p12 * a21 + p22 * a22
    u30 = p03 * a00 + p13 * a01 + p23 * a02
    u31 = p03 * a10 + p13 * a11 + p23 * a12
    u32 = p03 * a20 + p13 * a21 + p23 * a22
    r00, r01, r02, r11, r12, r22 = R
    # S = H U + R
    s00 = a00 * u00 + a01 * u10 + a02 * u20 + r00
    s01 = a00 * u01 + a01 * u11 + a02 * u21 + r01
    s02 = a00 * u02 + a01 * u12 + a02 * u22 + r02
    s11 = a10 * u01 + a11 * u11 + a12 * u21 + r11
    s12 = a10 * u02 + a11 * u12 + a12 * u22 + r12
    s22 = a20 * u02 + a21 * u12 + a22 * u22 + r22
    c00 = s11 * s22 - s12 * s12
    c01 = s02 * s12 - s01 * s22
    c02 = s01 * s12 - s02 * s11
    c11 = s00 * s22 - s02 * s02
    c12 = s01 * s02 - s00 * s12
    c22 = s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    if not (ops.all(s00 > 0.0) and ops.all(c22 > 0.0) and ops.all(det > 0.0)):
        return None
    inv = 1.0 / det
    i00, i01, i02, i11, i12, i22 = c00 * inv, c01 * inv, c02 * inv, c11 * inv, c12 * inv, c22 * inv
    K = (
        u00 * i00 + u01 * i01 + u02 * i02,
        u00 * i01 + u01 * i11 + u02 * i12,
        u00 * i02 + u01 * i12 + u02 * i22,
        u10 * i00 + u11 * i01 + u12 * i02,
        u10 * i01 + u11 * i11 + u12 * i12,
        u10 * i02 + u11 * i12 + u12 * i22,
        u20 * i00 + u21 * i01 + u22 * i02,
        u20 * i01 + u21 * i11 + u22 * i12,
        u20 * i02 + u21 * i12 + u22 * i22,
        u30 * i00 + u31 * i01 + u32 * i02,
        u30 * i01 + u31 * i11 + u32 * i12,
        u30 * i02 + u31 * i12 + u32 * i22,
    )
    return K, (s00, s01, s02, s11, s12, s22), (i00, i01, i02, i11, i12, i22)


def update_kernel(
    m: Vec, P: Vec, A: Vec, nu: Vec, R: Vec, ops: Ops
) -> tuple[Vec, Vec, Vec, Scalar] | None:
    """Joseph-form update with ``H = [A | 0]`` (``A`` row-major 3 × 3), residual ``ν``, ``R``.

    Returns ``(mean, cov, S, nis)``, or ``None`` if some ``S`` is not positive definite.
    """
    gain = gain_kernel(P, A, R, ops)
    if gain is None:
        return None
    K, S, S_inv = gain
    k00, k01, k02, k10, k11, k12, k20, k21, k22, k30, k31, k32 = K
    i00, i01, i02, i11, i12, i22 = S_inv
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = A
    p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = P
    r00, r01, r02, r11, r12, r22 = R
    n0, n1, n2 = nu
    w0 = i00 * n0 + i01 * n1 + i02 * n2
    w1 = i01 * n0 + i11 * n1 + i12 * n2
    w2 = i02 * n0 + i12 * n1 + i22 * n2
    nis = n0 * w0 + n1 * w1 + n2 * w2
    x, y, z, phi = m
    mean = (
        x + k00 * n0 + k01 * n1 + k02 * n2,
        y + k10 * n0 + k11 * n1 + k12 * n2,
        z + k20 * n0 + k21 * n1 + k22 * n2,
        phi + k30 * n0 + k31 * n1 + k32 * n2,
    )
    # Joseph form P⁺ = M P Mᵀ + K R Kᵀ with M = I − K H; (KH)_ij = Σ_k K_ik A_kj, j < 3
    b00 = 1.0 - (k00 * a00 + k01 * a10 + k02 * a20)
    b01 = -(k00 * a01 + k01 * a11 + k02 * a21)
    b02 = -(k00 * a02 + k01 * a12 + k02 * a22)
    b10 = -(k10 * a00 + k11 * a10 + k12 * a20)
    b11 = 1.0 - (k10 * a01 + k11 * a11 + k12 * a21)
    b12 = -(k10 * a02 + k11 * a12 + k12 * a22)
    b20 = -(k20 * a00 + k21 * a10 + k22 * a20)
    b21 = -(k20 * a01 + k21 * a11 + k22 * a21)
    b22 = 1.0 - (k20 * a02 + k21 * a12 + k22 * a22)
    b30 = -(k30 * a00 + k31 * a10 + k32 * a20)
    b31 = -(k30 * a01 + k31 * a11 + k32 * a21)
    b32 = -(k30 * a02 + k31 * a12 + k32 * a22)
    # C = M P (rows i, columns j); M_i3 = δ_i3
    c_00 = b00 * p00 + b01 * p01 + b02 * p02
    c_01 = b00 * p01 + b01 * p11 + b02 * p12
    c_02 = b00 * p02 + b01 * p12 + b02 * p22
    c_03 = b00 * p03 + b01 * p13 + b02 * p23
    c_10 = b10 * p00 + b11 * p01 + b12 * p02
    c_11 = b10 * p01 + b11 * p11 + b12 * p12
    c_12 = b10 * p02 + b11 * p12 + b12 * p22
    c_13 = b10 * p03 + b11 * p13 + b12 * p23
    c_20 = b20 * p00 + b21 * p01 + b22 * p02
    c_21 = b20 * p01 + b21 * p11 + b22 * p12
    c_22 = b20 * p02 + b21 * p12 + b22 * p22
    c_23 = b20 * p03 + b21 * p13 + b22 * p23
    c_30 = b30 * p00 + b31 * p01 + b32 * p02 + p03
    c_31 = b30 * p01 + b31 * p11 + b32 * p12 + p13
    c_32 = b30 * p02 + b31 * p12 + b32 * p22 + p23
    c_33 = b30 * p03 + b31 * p13 + b32 * p23 + p33
    # E = K R (4 × 3)
    e00 = k00 * r00 + k01 * r01 + k02 * r02
    e01 = k00 * r01 + k01 * r11 + k02 * r12
    e02 = k00 * r02 + k01 * r12 + k02 * r22
    e10 = k10 * r00 + k11 * r01 + k12 * r02
    e11 = k10 * r01 + k11 * r11 + k12 * r12
    e12 = k10 * r02 + k11 * r12 + k12 * r22
    e20 = k20 * r00 + k21 * r01 + k22 * r02
    e21 = k20 * r01 + k21 * r11 + k22 * r12
    e22 = k20 * r02 + k21 * r12 + k22 * r22
    e30 = k30 * r00 + k31 * r01 + k32 * r02
    e31 = k30 * r01 + k31 * r11 + k32 * r12
    e32 = k30 * r02 + k31 * r12 + k32 * r22
    # P⁺_ij = Σ_k C_ik M_jk + Σ_k E_ik K_jk (upper triangle)
    cov = (
        c_00 * b00 + c_01 * b01 + c_02 * b02 + e00 * k00 + e01 * k01 + e02 * k02,
        c_00 * b10 + c_01 * b11 + c_02 * b12 + e00 * k10 + e01 * k11 + e02 * k12,
        c_00 * b20 + c_01 * b21 + c_02 * b22 + e00 * k20 + e01 * k21 + e02 * k22,
        c_00 * b30 + c_01 * b31 + c_02 * b32 + c_03 + e00 * k30 + e01 * k31 + e02 * k32,
        c_10 * b10 + c_11 * b11 + c_12 * b12 + e10 * k10 + e11 * k11 + e12 * k12,
        c_10 * b20 + c_11 * b21 + c_12 * b22 + e10 * k20 + e11 * k21 + e12 * k22,
        c_10 * b30 + c_11 * b31 + c_12 * b32 + c_13 + e10 * k30 + e11 * k31 + e12 * k32,
        c_20 * b20 + c_21 * b21 + c_22 * b22 + e20 * k20 + e21 * k21 + e22 * k22,
        c_20 * b30 + c_21 * b31 + c_22 * b32 + c_23 + e20 * k30 + e21 * k31 + e22 * k32,
        c_30 * b30 + c_31 * b31 + c_32 * b32 + c_33 + e30 * k30 + e31 * k31 + e32 * k32,
    )
    return mean, cov, S, nis


#: An estimate whose horizontal range is at most this fraction of its range, ``ρ̂ ≤ ε r̂``
#: (within 1e-9 rad of the vertical axis through the observer), is treated as *on the axis* by
#: the TEKF linearisation (:func:`tekf_terms_on_axis`).
POLE_FRACTION = 1e-9


def tekf_terms(m: Vec, z: Vec, var: Vec, ops: Ops) -> tuple[Vec, Vec, Vec]:
    """TEKF ``(A, ν, R)``: Jacobian block of ``h = (r, θ, α)`` at the prior, wrapped residual.

    ``var`` are the sensor variances ``(σ_r², σ_θ², σ_α²)``. An estimate on the vertical axis
    through the observer (``ρ̂ ≤ POLE_FRACTION · r̂``, including the observer's own position)
    is linearised by :func:`tekf_terms_on_axis`; every other estimate by the Jacobian of
    :func:`relloc.models.measurement.range_bearing_jacobian`.
    """
    x, y, zz = m[0], m[1], m[2]
    rho2 = x * x + y * y
    rho = ops.sqrt(rho2)
    r2 = rho2 + zz * zz
    r = ops.sqrt(r2)
    if ops.any(rho <= POLE_FRACTION * r):
        return tekf_terms_on_axis(m, z, var, ops)
    rr = rho * r2
    zero = 0.0 * x  # a zero shaped like the batch
    A = (x / r, y / r, zz / r, -y / rho2, x / rho2, zero, -x * zz / rr, -y * zz / rr, rho / r2)
    two_pi = 2.0 * math.pi
    d_az = z[1] - ops.atan2(y, x)
    d_el = z[2] - ops.atan2(zz, rho)
    nu = (
        z[0] - r,
        (d_az + math.pi) % two_pi - math.pi,
        (d_el + math.pi) % two_pi - math.pi,
    )
    R = (var[0], 0.0, 0.0, var[1], 0.0, var[2])
    return A, nu, R


def tekf_terms_on_axis(m: Vec, z: Vec, var: Vec, ops: Ops) -> tuple[Vec, Vec, Vec]:
    """TEKF ``(A, ν, R)`` that stays finite when the estimate is on the vertical axis.

    A drone straight above (or below) its observer has elevation ``α = ±π/2`` and no azimuth:
    at ``ρ = √(x² + y²) = 0`` the map ``h = (r, θ, α)`` is not differentiable. Its Jacobian
    (:mod:`relloc.models.measurement`) divides by ``ρ²`` (azimuth row ``[−y, x, 0]/ρ²``) and by
    ``ρ r²`` (elevation row ``[−x z/ρ, −y z/ρ, ρ]/r²``), which raised ``ZeroDivisionError`` (one
    pair) or gave NaN and a "not positive definite" error (a batch). Entries with
    ``ρ̂ ≤ ε r̂`` (``ε =`` :data:`POLE_FRACTION`) are linearised as follows; every other entry
    of the batch keeps the formulas of :func:`tekf_terms` bit for bit.

    * **Azimuth: no first-order information.** ``θ = atan2(y, x)`` has no derivative on the
      axis (its gradient ``u_θ/ρ`` is unbounded and its direction is that of the unknown
      horizontal offset). The row is dropped: ``A_θ = 0``, ``ν_θ = 0``, and ``R_θθ = σ_θ²``
      is kept so that ``S`` stays positive definite; the azimuth then adds nothing to the gain
      and 0 to the NIS (which has 2 effective degrees of freedom at such an update). Near the
      axis a kept row would collapse the tangential variance to ``(ρ̂ σ_θ)² ≤ (ε r̂ σ_θ)²``,
      far below anything the prior can resolve, so dropping it loses no usable information.
    * **Elevation: the one-sided derivative on the measured half-plane.** ``α = atan2(z, ρ)``
      is a cone at the axis. Restricted to the half-plane of the *measured* azimuth
      ``θ̃`` (``p = ρ (cθ̃, sθ̃) + z e_z``, ``ρ ≥ 0``) it is smooth, with gradient
      ``u_α(θ̃, α̂)/r̂ = [−cθ̃ sα̂, −sθ̃ sα̂, cα̂]/r̂`` (``sα̂ = ẑ/r̂``, ``cα̂ = ρ̂/r̂``) — the
      Jacobian row rewritten without the removable ``x/ρ``, ``y/ρ`` and with the direction
      taken from the measurement, where the estimate has none. The residual is the usual
      wrapped ``α̃ − atan2(ẑ, ρ̂)``, so an elevation short of ``±π/2`` moves the estimate off
      the axis towards the measured azimuth.
    * **Range** keeps ``p̂ᵀ/r̂``; at the observer's own position (``r̂ = 0``, where ``r`` is a
      cone too) it is the one-sided derivative along the measured ray ``u_r(θ̃, α̃)``, and the
      elevation row is dropped like the azimuth (``A_α = 0``, ``ν_α = 0``).
    """
    x, y, zz = m[0], m[1], m[2]
    rho2 = x * x + y * y
    rho = ops.sqrt(rho2)
    r2 = rho2 + zz * zz
    r = ops.sqrt(r2)
    axis = rho <= POLE_FRACTION * r
    origin = r <= 0.0
    # safe denominators: 1 where the quotient is not used
    rho2_s = ops.where(axis, 1.0, rho2)
    r_s = ops.where(origin, 1.0, r)
    rr_s = ops.where(axis, 1.0, rho * r2)
    r2_s = ops.where(origin, 1.0, r2)
    ct, st = ops.cos(z[1]), ops.sin(z[1])
    ca, sa = ops.cos(z[2]), ops.sin(z[2])
    zero = 0.0 * (x + ct)  # a zero shaped like the batch
    sa_hat, ca_hat = zz / r_s, rho / r_s
    A = (
        ops.where(origin, ct * ca, x / r_s),
        ops.where(origin, st * ca, y / r_s),
        ops.where(origin, sa, zz / r_s),
        ops.where(axis, zero, -y / rho2_s),
        ops.where(axis, zero, x / rho2_s),
        zero,
        ops.where(axis, ops.where(origin, zero, -ct * sa_hat / r_s), -x * zz / rr_s),
        ops.where(axis, ops.where(origin, zero, -st * sa_hat / r_s), -y * zz / rr_s),
        ops.where(axis, ops.where(origin, zero, ca_hat / r_s), rho / r2_s),
    )
    two_pi = 2.0 * math.pi
    d_az = z[1] - ops.atan2(y, x)
    d_el = z[2] - ops.atan2(zz, rho)
    nu = (
        z[0] - r,
        ops.where(axis, zero, (d_az + math.pi) % two_pi - math.pi),
        ops.where(origin, zero, (d_el + math.pi) % two_pi - math.pi),
    )
    R = (var[0], 0.0, 0.0, var[1], 0.0, var[2])
    return A, nu, R


def plkf_terms(
    m: Vec, z: Vec, var: Vec, ops: Ops, *, full_covariance: bool = False
) -> tuple[Vec, Vec, Vec]:
    """PLKF ``(A, ν, R)``: ``H_pmo`` from the measured bearings, ``ν = [r̃, 0, 0] − H x`` and
    ``R_pmo`` at the prior: simplified (seed 000 Eq. 6) or, with ``full_covariance``,
    ``J Σ Jᵀ`` (Eqs. 4–5, ``J`` of :func:`relloc.models.measurement.pseudo_linear_noise_jacobian`).
    """
    x, y, zz = m[0], m[1], m[2]
    ct, st = ops.cos(z[1]), ops.sin(z[1])
    ca, sa = ops.cos(z[2]), ops.sin(z[2])
    zero = 0.0 * ct  # a zero shaped like the batch
    A = (ct * ca, st * ca, sa, -st, ct, zero, -ct * sa, -st * sa, ca)
    nu = (
        z[0] - (A[0] * x + A[1] * y + sa * zz),
        st * x - ct * y,
        -(A[6] * x + A[7] * y + ca * zz),
    )
    v0, v1, v2 = var
    if full_covariance:
        a = -st * x + ct * y
        b = ct * x + st * y
        j01, j02 = -ca * a, sa * b - zz * ca
        j11, j21, j22 = b, sa * a, ca * b + zz * sa
        R = (
            v0 + j01 * j01 * v1 + j02 * j02 * v2,
            j01 * j11 * v1,
            j01 * j21 * v1 + j02 * j22 * v2,
            j11 * j11 * v1,
            j11 * j21 * v1,
            j21 * j21 * v1 + j22 * j22 * v2,
        )
    else:
        rho2 = x * x + y * y
        R = (v0, 0.0, 0.0, rho2 * v1, 0.0, (rho2 + zz * zz) * v2)
    return A, nu, R


def plkf_bias_kernel(
    prior: Vec,
    P: Vec,
    posterior: Vec,
    var: Vec,
    ops: Ops,
    *,
    full_covariance: bool = False,
) -> Vec | None:
    """``b̂ = E_ν[K ν_pm]`` of one PLKF update (see :mod:`relloc.estimators.relative`).

    Evaluated at the uncompensated ``posterior`` with the 6-point third-degree cubature rule over
    the sensor noise ``(ν_r, ν_θ, ν_α)``: points ``ẑ ± √3 σ_i e_i`` with ``ẑ = h(posterior)``,
    weights 1/6. Each point's gain uses the prior covariance and ``R_pmo`` at the prior, as the
    update itself does. ``None`` if some innovation covariance is not positive definite.
    """
    x, y, zz = posterior[0], posterior[1], posterior[2]
    rho = ops.sqrt(x * x + y * y)
    z_hat = (ops.sqrt(x * x + y * y + zz * zz), ops.atan2(y, x), ops.atan2(zz, rho))
    total = [0.0, 0.0, 0.0, 0.0]
    for axis in range(3):
        step = math.sqrt(3.0 * var[axis])
        for sign in (1.0, -1.0):
            zj = tuple(z_hat[i] + sign * step if i == axis else z_hat[i] for i in range(3))
            A, _, R = plkf_terms(prior, zj, var, ops, full_covariance=full_covariance)
            _, nu, _ = plkf_terms(posterior, zj, var, ops)
            gain = gain_kernel(P, A, R, ops)
            if gain is None:
                return None
            K = gain[0]
            for i in range(4):
                total[i] = total[i] + (
                    K[3 * i] * nu[0] + K[3 * i + 1] * nu[1] + K[3 * i + 2] * nu[2]
                )
    return tuple(t / 6.0 for t in total)


_UPPER4 = ((0, 0), (0, 1), (0, 2), (0, 3), (1, 1), (1, 2), (1, 3), (2, 2), (2, 3), (3, 3))
_UPPER3 = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
#: For each entry of the row-major full matrix, its index in the upper-triangle tuple.
_FULL_FROM_UPPER = {
    n: tuple(upper.index((min(i, j), max(i, j))) for i in range(n) for j in range(n))
    for n, upper in ((3, _UPPER3), (4, _UPPER4))
}


def split_vector(v: np.ndarray, single: bool) -> Vec:
    """``(..., n)`` array → tuple of ``n`` entries (floats when ``single``)."""
    if single:
        return tuple(v.tolist())
    return tuple(v[..., i] for i in range(v.shape[-1]))


def split_cov4(P: np.ndarray, single: bool) -> Vec:
    """``(..., 4, 4)`` symmetric array → its 10 upper-triangle entries."""
    if single:
        rows = P.tolist()
        return tuple(rows[i][j] for i, j in _UPPER4)
    return tuple(P[..., i, j] for i, j in _UPPER4)


def join_vector(parts: Vec) -> np.ndarray:
    """Tuple of entries (floats or broadcastable arrays) → array ``(..., n)``."""
    if all(isinstance(p, float) for p in parts):
        return np.array(parts)
    return np.stack(np.broadcast_arrays(*(np.asarray(p, dtype=float) for p in parts)), axis=-1)


def join_symmetric(parts: Vec) -> np.ndarray:
    """Upper-triangle entries of a 3 × 3 (6 entries) or 4 × 4 (10) matrix → full ``(..., n, n)``."""
    upper = _UPPER4 if len(parts) == 10 else _UPPER3
    n = 4 if len(parts) == 10 else 3
    if all(isinstance(p, float) for p in parts):
        return np.array([parts[k] for k in _FULL_FROM_UPPER[n]]).reshape(n, n)
    arrays = np.broadcast_arrays(*(np.asarray(p, dtype=float) for p in parts))
    out = np.empty((*arrays[0].shape, n, n))
    for (i, j), value in zip(upper, arrays, strict=True):
        out[..., i, j] = value
        out[..., j, i] = value
    return out
