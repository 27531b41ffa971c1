"""UWB calibration of a ROS 2 bag: the error model fitted on readings whose radios have known
positions, per-link biases by radio name (so a fit transfers to another bag of the same radios),
the σ the filters give one corrected range, and the held-out check.

The calibration data is :func:`as_uwb_recording`: every reading of
:attr:`~relloc.datasets.rosbag.BagRecording.ranges` whose two radios have known positions
(motion capture ⊕ antenna offset, or surveyed), with the true 3-D distance beside it, in the
layout :func:`relloc.calibration.uwb.fit_uwb_noise` fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.inflation import gauss_markov_inflation
from relloc.calibration.uwb import UwbNoiseFit, fit_uwb_noise, link_masks
from relloc.calibration.window import CalibrationWindow
from relloc.core.recording import FileSkips, Measurements, Recording
from relloc.datasets.rosbag import BagRecording
from relloc.datasets.uwb import UwbRecording
from relloc.errors import DataError

Array = NDArray[np.float64]


def as_uwb_recording(bag: BagRecording) -> UwbRecording:
    """The readings whose two radios have known positions, with the true distance beside each
    (motion capture ⊕ offsets, 3-D), as the calibration's :class:`UwbRecording` (radio indices
    as node ids)."""
    r = bag.ranges
    true = np.full(r.t.size, np.nan)
    for a, b in r.links():
        m = r.link_mask(a, b)
        pa, pb = bag.node_truth(a, r.t[m]), bag.node_truth(b, r.t[m])
        true[m] = np.linalg.norm(pa - pb, axis=1)
    ok = np.isfinite(true) & (true > 0)
    if not ok.any():
        raise DataError(f"{bag.path}: no UWB reading between radios of known position to calibrate")
    return UwbRecording(
        path=bag.path,
        t=r.t[ok],
        node1=r.node_a[ok],
        node2=r.node_b[ok],
        uwb_range=r.value[ok],
        mocap_range=true[ok],
        data_rows=int(r.t.size),
        skipped=FileSkips(file=str(bag.path), rows_read=int(r.t.size), rows_kept=int(ok.sum())),
    )


def _names(bag: BagRecording, a: int, b: int) -> tuple[str, str]:
    assert bag.mapping.uwb is not None
    na, nb = bag.mapping.uwb.nodes[a].name, bag.mapping.uwb.nodes[b].name
    return (na, nb) if na <= nb else (nb, na)


@dataclass(frozen=True)
class Calibration:
    """The fit, the bag it came from, the bias per radio-name link, how much a link's bias
    moves within the window (``bias_drift``, m) and the σ the filters give one range."""

    fit: UwbNoiseFit
    source: str
    link_bias: dict[tuple[str, str], float]
    bias_drift: float
    range_sigma: float

    def bias(self, link: tuple[str, str]) -> float:
        return self.link_bias.get(link, self.fit.model.bias)


def bias_drift(rec: UwbRecording, window: CalibrationWindow) -> float:
    """How far a link's bias moves within ``window``: the RMS over the fitted links of the
    difference between the median errors of the window's two halves, divided by √2 (the σ of
    one half's median about the bias, if both halves are alike)."""
    mid = 0.5 * (window.start_s + window.end_s)
    diffs = []
    for mask in link_masks(rec, window).values():
        first, second = mask & (rec.t <= mid), mask & (rec.t > mid)
        if first.any() and second.any():
            diffs.append(float(np.median(rec.error[first]) - np.median(rec.error[second])))
    return float(np.sqrt(np.mean(np.square(diffs)) / 2.0)) if diffs else 0.0


def calibrate(bag: BagRecording, window: CalibrationWindow) -> Calibration:
    """Fit the UWB error model on ``bag`` inside ``window``, and the σ of one corrected range
    for the filters: ``σ² = f·spread² + drift²`` with ``f`` the Gauss–Markov variance
    inflation of the fitted correlation time at the fitted sampling period
    (:func:`~relloc.calibration.inflation.gauss_markov_inflation`: consecutive errors are far
    from independent) and ``drift`` the bias drift within the window (:func:`bias_drift`)."""
    rec = as_uwb_recording(bag)
    fit = fit_uwb_noise(rec, window)
    links: dict[tuple[str, str], float] = {}
    for key, value in fit.link_biases.items():
        a, b = (int(v) for v in key.split("-"))
        links[_names(bag, a, b)] = value
    m = fit.model
    inflation = (
        gauss_markov_inflation(fit.sample_period, m.correlation_time)
        if fit.sample_period > 0
        else 1.0
    )
    drift = bias_drift(rec, window)
    sigma = max(math.sqrt(inflation * m.spread**2 + drift**2), 1e-3)
    return Calibration(
        fit=fit, source=str(bag.path), link_bias=links, bias_drift=drift, range_sigma=sigma
    )


def heldout_errors(bag: BagRecording, cal: Calibration, t0: float, t1: float) -> dict[str, Any]:
    """Range error (reading − true distance) on ``[t0, t1]`` before and after the correction."""
    rec = as_uwb_recording(bag)
    inside = (rec.t >= t0) & (rec.t <= t1)
    if not inside.any():
        return {"rows": 0}
    bias = np.array(
        [
            cal.bias(_names(bag, int(a), int(b)))
            for a, b in zip(rec.node1[inside], rec.node2[inside], strict=True)
        ]
    )
    raw = rec.error[inside]
    fixed = raw - bias

    def stats(e: Array) -> dict[str, float]:
        return {
            "mean_m": float(np.mean(e)),
            "std_m": float(np.std(e)),
            "rmse_m": float(np.sqrt(np.mean(e**2))),
        }

    return {"rows": int(inside.sum()), "raw": stats(raw), "calibrated": stats(fixed)}


def row_links(bag: BagRecording) -> list[tuple[str, str] | None]:
    """The radio-name link of each ``range`` row of the recording (``None`` if the target
    robot carries several radios, so the row does not say which)."""
    m, mapping = bag.recording.measurements, bag.mapping
    assert mapping.uwb is not None and m.sensor is not None and m.landmark is not None
    nodes = mapping.uwb.nodes
    on_robot: dict[int, list[int]] = {}
    for k, n in enumerate(nodes):
        if n.robot is not None:
            on_robot.setdefault(mapping.robot_index(n.robot), []).append(k)
    static = [k for k, n in enumerate(nodes) if n.robot is None and n.position is not None]
    out: list[tuple[str, str] | None] = []
    for q in range(m.size):
        a = on_robot[int(m.observer[q])][int(m.sensor[q])]
        if m.target[q] >= 0:
            targets = on_robot[int(m.target[q])]
            if len(targets) != 1:
                out.append(None)
                continue
            b = targets[0]
        else:
            b = static[int(m.landmark[q])]
        out.append(_names(bag, a, b))
    return out


def corrected(bag: BagRecording, cal: Calibration | None, sigma: float) -> Recording:
    """The recording with every range corrected by its link's bias (none if ``cal`` is None)
    and the stated σ set to ``sigma``."""
    m = bag.recording.measurements
    value = np.array(m.value, copy=True)
    if cal is not None:
        bias = np.array([cal.bias(k) if k else cal.fit.model.bias for k in row_links(bag)])
        value[:, 0] = np.maximum(value[:, 0] - bias, 0.01)
    s = np.array(m.sigma, copy=True)
    s[:, 0] = sigma
    rows = Measurements(
        t=m.t,
        kind=m.kind,
        observer=m.observer,
        target=m.target,
        value=value,
        sigma=s,
        landmark=m.landmark,
        origin=m.origin,
        sensor=m.sensor,
    )
    return replace(bag.recording, measurements=rows)
