"""Reproduction of seed 001 §4.1: bearing-only cooperative localization of five robots.

``relloc reproduce sharma2013 --out DIR [--runs N] [--seed S] [--executor E]``

Scenario (:func:`relloc.sim.cooperative.sharma2013_scenario`): five unicycles at V = 5 m/s, two
landmarks, omnidirectional bearing sensor with R_sensor = 120 m, Ts = 0.1 s, initial σ
(5 m, 5 m, 0.2 rad), σ_v = 0.2 m/s, σ_ω = 0.2 rad/s, σ_η = 0.1 rad. The paper lists no
way-points or duration; we use 300 s (about 2.3 laps of a 200 m × 120 m circuit) and, for the
GPS case, an absolute pose fix of robot 1 at 1 Hz with σ = (1 m, 1 m, 0.05 rad) (not stated in the
paper). Each Monte-Carlo run draws new noise and a new initial estimate and runs two centralised
EIFs (:mod:`relloc.estimators.eif`) on four cases: the plain EIF of seed 001 (every Jacobian at
the latest estimate) and two observability-aware EIFs, which keep the unobservable global
translation/rotation out of the linearised filter's information: first-estimates Jacobians (FEJ,
:mod:`relloc.estimators.first_estimates`) and observability-constrained Jacobians (OC,
:mod:`relloc.estimators.observability_constrained`). Both also carry each bearing's
second-order mean and variance under the prior (:mod:`relloc.estimators.second_order`): with
5 m initial errors on robots that start 6–35 m apart, a linearised bearing update is wrong
over the prior's spread, and what it wrongly removes along the unobservable directions is
never given back. The cases:

- ``no_landmark``: robot→robot bearings only;
- ``one_landmark``: plus bearings to landmark 1;
- ``two_landmarks``: plus bearings to both landmarks;
- ``gps_robot1``: robot→robot bearings plus robot 1's absolute pose.

Run count: the paper shows one realisation; the default here is 30 Monte-Carlo runs (4.4 min
on 2 cores, 8.6 min of CPU, with the symbolic observability ranks), ``--runs`` changes it.
Why 30 and not fewer: see "How far the runs carry the NEES share" below.

NEES: each robot's 3-DOF NEES of its world-frame pose ``(x, y, ψ)`` (its marginal belief against
the truth), not of relative quantities. It is a fair test even where the world frame is
unobservable because the initial estimate is drawn from the stated prior: a consistent filter
keeps the prior's uncertainty (plus the odometry's diffusion) along the unobservable
directions, and the NEES checks exactly that.

How far the runs carry the NEES share. A run's share is heavy-tailed: most runs of the
observability-aware filters leave about 1 % beyond the bound and a few leave 20–80 %, so the
runs are the clusters of the share's interval, and ten runs say little: with seed 2026 ten runs
gave the OC EIF's no-landmark share 9.78 % with interval 0.2–44.6 % (``N_eff`` 13; one run at
83.4 %), and with seed 91, 1.73 % (0.6–4.0 %). The default of 30 runs (seed 2026; its first ten
runs are those ten) gives 6.89 % (2.0–16.4 %, ``N_eff`` 67) with no landmark and 4.58 %
(2.7–7.3 %) with one. ``relloc reproduce sharma2013 --runs 60 --seed 20261204`` (about 13 min
on 2 cores) gives for the OC EIF 3.79 % (2.2–6.2 %, ANEES 0.99) with no landmark and 4.76 %
(3.0–7.2 %, ANEES 1.00) with one; a run's own share has median 1.0 % and 2.5 %, and 5 and 6 of
the 60 runs leave more than 10 %. The FEJ EIF gives 3.42 % and 4.78 %; the plain EIF 43.6 %
(33.1–54.5 %) and 22.5 % (14.6–32.1 %). Why the tail: the world frame's translation and rotation
are unobservable with no landmark, so what the initial estimate's draw puts along them stays for
the whole run, in every robot's error, and a run's NEES samples share it. Projected on those
directions (generalised least squares under the prior, where the rotation's σ is 0.056 rad), the
draw's squared Mahalanobis length ranks with the run's share (Spearman 0.64 over the 60 runs
above). Run 7 of seed 2026 (83.4 % beyond; the other nine runs 0.2–4.9 %) drew the largest of
its ten (7.91 of χ²₃, p 0.048), a rotation of −0.153 rad: the robots' heading errors stay near
it from the first second on (−0.14 rad at 0.5 s, −0.18 at 300 s, against the filter's σ of
0.061–0.069), as a consistent filter keeps them. Some runs are not explained so. Run 53 of seed
20261204 (28.3 %) drew 1.74; its error is mostly one translation shared by the robots (6.5 m at
300 s), its position RMSE 7.3–11.0 m through the run, and its share 57–98 % from 60 to 150 s,
2–19 % in the other 30 s blocks, while the filter's position σ (√(σ_x² + σ_y²), mean over the
robots) swings between 5.3 and 10.3 m with the team's place on its loop. In run 3 (20.9 %, drew
4.34) the heading error grows through the run (0.11 to 0.19 rad RMS over the robots, against σ
0.066 to 0.072) and the share with it, from 3 % in the first minute to 56 % in the ninth.
The frame NEES below, taken along each of these two runs (the OC EIF replayed to 10, 30, 60, …,
300 s), accounts for both: in run 53 it climbs from 2.1 at 10 s to 6.5–9.3 between 60 and 150
s (p 0.09–0.03 for χ²₃), where all five robots' NEES sit at 9–14 together, and falls to 3.9 by
300 s; in run 3 it stays at 3.8–6.5 throughout (the upper 9–28 % of χ²₃), enough to hold the
robots' NEES near the 7.81 bound for the whole run. A frame error at such a level is what a
consistent filter has in some runs; what it does to the per-sample share is that every robot
and every instant of the run carries it.

Along the unobservable directions (``frame_nees``): each run's final NEES of the team's joint
error along the global translation and rotation (d = 3 with no landmark; the rotation about
the landmark, d = 1, with one), by generalised least squares under the filter's joint
covariance (:func:`relloc.metrics.projected_nees`). It is χ²(d) for a consistent filter and
independent across runs, so it is a run-level test with exact bands, aimed where a linearised
filter gains spurious information. The default 30 runs (seed 2026): OC EIF mean 3.10 (95 %
band of a mean of 30 χ²₃ values 2.19–3.94) with no landmark and 0.78 (0.56–1.57) with one, one
run in 30 beyond χ²_d(0.95) in each, consistent by the band of the mean (the share's
interval, 0.1–17.6 % for one in 30, holds 5 % but reaches above 10 %: inconclusive); FEJ
EIF the same to two digits; plain EIF 33.8 and 12.2, 50 % and 30 % of the runs beyond,
over-confident. Run 7 of seed 2026 (83.4 % of its NEES samples beyond) has the OC EIF's
largest, 11.1 (p 0.011 for χ²₃); over the 30 runs the frame NEES ranks with a run's share
beyond (Spearman 0.79): the tail runs are the runs whose error along the unobservable
directions is large, as a consistent filter's are in a few runs. Along the run (every 30 s,
``frame_nees.along_the_run``, the joint beliefs kept by
``CooperativeEstimator(joint_times=…)``) the OC EIF's mean over the runs stays at 2.86–3.10
with no landmark and 0.76–1.09 with one, inside the band at every one of the ten times; the
plain EIF's at 28.1–36.8 and 11.0–21.7, above it at every one: the plain filter is already
over-confident along the frame at 30 s. ``tests/cooperative/test_observability_behaviour.py``
checks the final value on twelve 150 s runs of a root not used while developing (OC 3.44
within the 99.9 % band 1.20–5.88, plain 17.1 above it).

summary.json keys
-----------------
``experiment``, ``seed``, ``runs`` (Monte-Carlo runs); ``scenario``: the simulated team's
settings (``n_robots``, ``landmarks`` (a count), ``sensing_range_m``, ``speed_mps``, ``ts_s``,
``duration_s``, ``initial_sigma`` (m, m, rad), ``sigma_v`` (m/s), ``sigma_w`` (rad/s),
``sigma_bearing`` (rad), ``gps_sigma`` (m, m, rad), ``gps_period_s``);
``cases.<case>`` (the plain EIF), ``cases_first_estimates.<case>`` (the FEJ EIF) and
``cases_observability_constrained.<case>`` (the OC EIF):
``pos_rmse_m``, ``x_rmse_m``, ``y_rmse_m``, ``heading_rmse_rad`` — each a map
robot ("1"…"5") → RMSE over runs and the output instants (every ``OUTPUT_EVERY_S`` = 0.5 s
from t = 0; ``pos_rmse_m`` planar), plus ``"mean"`` (RMS over robots); ``bounded``
(true/false) with ``paper_bounded``; ``growth`` (the ratios behind ``bounded``, criterion
below: ``error_ratio`` of ``e``, ``sigma_ratio`` of ``s``, last quarter over second quarter);
``final_pos_err_m`` (RMS over runs and robots of the planar position error at the last output
instant, m); ``nees_pct_beyond`` (share of per-robot NEES samples beyond χ²₃(0.95),
about 5 % for a consistent filter; ``nees_beyond_interval`` its 95 % interval by cluster
means, each independent run one cluster, with the verdict — over-confident, conservative,
consistent or inconclusive, :func:`relloc.metrics.consistency.share_verdict` —:
:class:`relloc.metrics.BeyondShare`'s keys), ``nees_pct_beyond_per_run`` (each run's own
share, %) and ``anees`` (mean NEES / 3);
``nees_run_average``: the NEES averaged over the independent runs at each output instant, per
robot, against the two-sided 95 % band of such a mean (:func:`relloc.metrics.run_average_band`:
``in_band_percent``, about 95 % when consistent, ``below_band_percent``,
``above_band_percent`` with their intervals ``below_band_interval``, ``above_band_interval``,
``band``, ``runs``, ``instants``, ``blocks_short``, ``verdict``; with one run only
``verdict`` null, ``runs`` and ``reason``); ``used`` / ``rejected`` measurement counts
(mean per run); ``frame_nees`` (``None`` with two landmarks or GPS): each run's final NEES
along the unobservable directions (:func:`frame_nees`; ``dof`` d, ``per_run``, their ``mean``
against the 95 % ``band`` of a mean of that many χ²(d) values and the ``verdict``,
``pct_beyond`` χ²_d(0.95) with its ``beyond_interval``, and ``along_the_run``: ``t``, the
``mean_over_runs`` at each and :func:`relloc.metrics.run_average_band`'s keys); in ``cases`` only,
``observability_rank`` (:func:`observability_ranks`: ``rank`` of ``state_dim`` at run 0's
mid-run RPMG, ``full_rank``, ``paper_rank`` the paper's predicted rank (Theorems 2–4),
``robot_edges`` (the edges of the spanning tree used), ``landmark_edges`` (one per anchor
landmark seen then)).
``observability_aware``: the headline observability-aware filter (``block``, ``filter``),
whether it meets the target (``target_met``, ``target``: NEES beyond ≤ 10 % in
``no_landmark`` and ``one_landmark`` with position RMSE not above the plain EIF's), each
filter's ``meets_target`` and ``worst_nees_pct_beyond`` (block → value; the worst over those
two cases), and the headline filter's ``nees_beyond_interval``, ``nees_pct_beyond_per_run``
and ``frame_nees`` in those cases (case → the case's entry). ``filters``: what each block ran
(block name → text); ``nees_on``: what the NEES is computed on; ``departures``: every
choice that departs from the paper.
``rpmg``: over run 0's detection epochs, the fraction at which every robot is in one
component of that epoch's detection graph of robots and landmarks, possibly through a landmark
(``connected_fraction``), and the fraction with β(G₅²) = 1 (``beta_fraction``; seed 001
Eq. 22: every robot has a path to both landmarks).

Boundedness criterion (fixed before looking at results): with ``e(t)`` the position RMS error
over runs and robots and ``s(t)`` the mean 1σ position bound, the error is *bounded* when
both ``mean e`` and ``mean s`` over the last quarter of the run exceed those over the second
quarter by less than 20 %.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import networkx as nx
import numpy as np
from numpy.typing import NDArray

from relloc.core.estimates import Estimates
from relloc.core.recording import Measurements, Recording
from relloc.experiments.registry import ReproduceArgs
from relloc.pipeline.montecarlo import run_monte_carlo, spawn_seeds
from relloc.pipeline.output import (
    figure_md,
    interval_text,
    markdown_table,
    prepare_out_dir,
    run_average_verdict_text,
    save_figure,
    write_report,
    write_summary,
)

if TYPE_CHECKING:
    from relloc.estimators.cooperative import CooperativeSettings, Linearisation
    from relloc.sim.cooperative import CooperativeSim

Array = NDArray[np.float64]

DEFAULT_RUNS = 30
DURATION_S = 300.0
OUTPUT_EVERY_S = 0.5
#: The frame NEES (:func:`frame_nees`) is taken this often (s) along each run, and at its end.
FRAME_EVERY_S = 30.0
GROWTH_LIMIT = 1.2
CASES: dict[str, dict[str, Any]] = {
    "no_landmark": {"anchors": ()},
    "one_landmark": {"anchors": (0,)},
    "two_landmarks": {"anchors": (0, 1)},
    "gps_robot1": {"anchors": (), "use_fixes": True},
}
CASE_LABELS = {
    "no_landmark": "no landmark",
    "one_landmark": "one landmark",
    "two_landmarks": "two landmarks",
    "gps_robot1": "GPS on robot 1",
}
#: The case ``--mcap``/``--tum`` write, and what that is.
EXPORTED_CASE = "two_landmarks"
EXPORTED_RUN = (
    "the centralised EIF of the two-landmark case: every robot's (x, y, heading) in the world "
    "frame, owner 'team'"
)
#: summary.json block → the EIF's linearisation (``CooperativeSettings.linearisation``).
FILTERS: dict[str, Linearisation] = {
    "cases": "latest",
    "cases_first_estimates": "first_estimates",
    "cases_observability_constrained": "observability_constrained",
}
FILTER_LABELS = {
    "cases": "plain EIF (seed 001)",
    "cases_first_estimates": "FEJ EIF, second-order bearings (observability-aware)",
    "cases_observability_constrained": "OC EIF, second-order bearings (observability-aware)",
}
#: The observability-aware filters and the target the headline one must meet: NEES beyond
#: χ²₃(0.95) at most this share (%) in the unanchored cases, position RMSE not above the plain
#: EIF's there.
AWARE_BLOCKS = ("cases_first_estimates", "cases_observability_constrained")
AWARE_CASES = ("no_landmark", "one_landmark")
AWARE_NEES_LIMIT_PCT = 10.0
NEES_ON = (
    "each robot's world-frame pose (x, y, ψ), 3 DOF, its marginal belief against the truth; "
    "the initial estimate is drawn from the stated prior, so the world frame's unobservable "
    "directions carry a proper uncertainty that a consistent filter must keep"
)


def departures(duration_s: float, runs: int) -> list[str]:
    """Every choice of this reproduction that departs from the paper (summary and report)."""
    return [
        "Motion model discretised with the midpoint heading ψ + ω Ts/2 (relloc.models.unicycle) "
        "instead of the paper's Euler step (Eqs. 8-9 at ψ(k)): no heading bias on arcs; its "
        "Jacobians follow the same step.",
        f"Way-points, run duration ({duration_s:g} s) and GPS noise (σ = 1 m, 1 m, 0.05 rad at "
        "1 Hz on robot 1) are not given in the paper; ours are stated in `scenario`.",
        f"{runs} Monte-Carlo runs instead of the paper's single realisation, so accuracy and "
        "consistency are averages over runs.",
        "Detections are gated (χ² at 99.9 %) before the update; the paper does not gate.",
        "The observability-aware filters (first-estimates and observability-constrained "
        "Jacobians, Huang et al. 2008-2011) are an addition; the paper runs the plain EIF only, "
        "whose results are in `cases`.",
        "The observability-aware filters also use each bearing's second-order mean and variance "
        "under the prior (Gaussian second-order filter, Athans et al. 1968; "
        "relloc.estimators.second_order), which de-weights bearings whose linearisation fails "
        "over the 5 m initial spread; the plain EIF is the paper's first-order filter.",
    ]


PAPER_BOUNDED = {
    "no_landmark": False,
    "one_landmark": False,
    "two_landmarks": True,
    "gps_robot1": True,
}


def _scenario(duration_s: float | None = None):  # type: ignore[no-untyped-def]
    """The paper's scenario, :data:`DURATION_S` long unless ``duration_s`` is given."""
    from relloc.sim.cooperative import sharma2013_scenario

    return sharma2013_scenario(
        gps_robots=(0,), duration=DURATION_S if duration_s is None else duration_s
    )


def _detections(recording: Recording) -> Measurements:
    """The recording's detection rows (of a robot or a landmark)."""
    return recording.measurements.of_kind("bearing", "range_bearing")


def _rpmg_stats(recording: Recording) -> dict[str, float]:
    """Fractions of detection epochs with a connected robot graph and with β(G) = 1.

    Per epoch, the undirected graph over the robots and the landmarks (nodes ``n …``)
    of that epoch's detections: *connected* when all robots lie in one component (possibly
    through a landmark), β(G) = 1 when, with at least two landmarks, every robot reaches
    every landmark (the whole graph is one component).
    """
    det = _detections(recording)
    assert det.landmark is not None
    n, n_lm = recording.n_robots, recording.landmarks.shape[0]
    epochs = np.unique(det.t)
    connected = 0
    beta = 0
    for te in epochs:
        sel = det.t == te
        obs, tgt, lm = det.observer[sel], det.target[sel], det.landmark[sel]
        graph = nx.Graph()
        graph.add_nodes_from(range(n + n_lm))
        graph.add_edges_from(
            (int(i), int(j) if j >= 0 else n + int(k)) for i, j, k in zip(obs, tgt, lm, strict=True)
        )
        connected += set(range(n)) <= nx.node_connected_component(graph, 0)
        beta += n_lm >= 2 and nx.is_connected(graph)
    k = max(len(epochs), 1)
    return {"connected_fraction": connected / k, "beta_fraction": beta / k}


def _poses(recording: Recording, every: int) -> Array:
    """True poses ``(T, n, 3)`` = (x, y, ψ) at every ``every``-th truth sample."""
    truth = recording.require_truth("sharma2013")
    return np.stack([g.pose[::every][:, [0, 1, 3]] for g in truth], axis=1)


def _case_estimates(
    sim: CooperativeSim, settings: CooperativeSettings, out_t: Array
) -> tuple[Estimates, Any]:
    """The team EIF over the simulated recording, beliefs at ``out_t``; and the filter."""
    from relloc.estimators.cooperative import CooperativeEstimator
    from relloc.pipeline.replay import replay

    rec = sim.recording
    estimator = CooperativeEstimator(
        rec.robots,
        sim.prior,
        settings,
        rec.landmarks,
        record_updates=False,
        joint_times=frame_times(out_t),
    )
    estimates = replay(rec, [estimator], record_times=out_t, start=0.0, end=float(out_t[-1]))
    return estimates, estimator


def frame_times(out_t: Array) -> Array:
    """The output times at which the frame NEES is taken: every :data:`FRAME_EVERY_S` after the
    start, and the last."""
    since = out_t - out_t[0]
    k = np.round(since / FRAME_EVERY_S)
    picked = out_t[(k >= 1) & np.isclose(since, k * FRAME_EVERY_S, atol=1e-6)]
    return np.unique(np.append(picked, out_t[-1]))


def frame_nees(
    sim: CooperativeSim, settings: CooperativeSettings, estimator: Any
) -> tuple[Array, int] | None:
    """The NEES of the team's joint error along its unobservable directions
    (:func:`relloc.metrics.projected_nees`; translation and rotation with no landmark, the
    rotation about the landmark with one) at each of :func:`frame_times`, from the filter's
    joint beliefs then (``CooperativeEstimator.joint_beliefs``) against the truth, with ``d``;
    ``None`` where the case has no unobservable direction. Each value is χ²(d) for a
    consistent filter; the runs are independent."""
    from relloc.core.angles import wrap_angle
    from relloc.estimators.observability_constrained import unobservable_directions
    from relloc.metrics import projected_nees

    rec = sim.recording
    anchors_xy = rec.landmarks[list(settings.anchors), :2]
    truth_t = rec.require_truth("sharma2013")[0].t
    poses = _poses(rec, 1)
    values, dof = [], 0
    for t, belief in estimator.joint_beliefs:
        X = belief.mean.reshape(-1, 3)
        N = unobservable_directions(X, anchors_xy, settings.use_fixes)
        if N.shape[1] == 0:
            return None
        error = X - poses[int(np.argmin(np.abs(truth_t - t)))]
        error[:, 2] = wrap_angle(error[:, 2])
        values.append(projected_nees(error.reshape(-1), belief.cov, N))
        dof = int(N.shape[1])
    return np.array(values), dof


def run_case(sim: CooperativeSim, settings: CooperativeSettings, out_t: Array) -> dict[str, Any]:
    """The team EIF over the simulated recording: errors ``(T, n, 3)`` against the truth
    (:func:`relloc.pipeline.evaluation.evaluate`), the estimates, the filter's counts and the
    final NEES along the unobservable directions (:func:`frame_nees`)."""
    from relloc.estimators.cooperative import CooperativeEstimator
    from relloc.pipeline.evaluation import evaluate

    rec = sim.recording
    estimates, estimator = _case_estimates(sim, settings, out_t)
    _, mean, cov = estimates.stacked(CooperativeEstimator.owner, rec.robots)
    scored = {e.subject: e for e in evaluate(estimates, rec)}
    errors = np.stack([scored[r].error for r in rec.robots], axis=1)
    return {
        "errors": errors,
        "cov": cov,
        "mean": mean,
        "used": estimator.counts.used,
        "rejected": estimator.counts.rejected,
        "frame_nees": frame_nees(sim, settings, estimator),
    }


def _simulated(seed_sequence: np.random.SeedSequence) -> tuple[Any, CooperativeSim, Array, int]:
    """One run's scenario, simulation, truth times and output step (every ``step``-th)."""
    from relloc.sim.cooperative import simulate

    scenario = _scenario()
    sim = simulate(scenario, np.random.default_rng(seed_sequence))
    t = sim.recording.require_truth("sharma2013")[0].t
    return scenario, sim, t, round(OUTPUT_EVERY_S / scenario.dt)


def case_settings(
    scenario: Any, case: str, linearisation: Linearisation = "latest"
) -> CooperativeSettings:
    """The team EIF's settings of one case (:data:`CASES`) on the scenario's noise, with the
    given linearisation (plain, first-estimates or observability-constrained Jacobians); the
    observability-aware ones also carry the bearings' second-order terms
    (:mod:`relloc.estimators.second_order`), the plain one is seed 001's filter."""
    from relloc.estimators.cooperative import CooperativeSettings, OdometryModel, SensorModel

    odometry = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt)
    sensor = SensorModel(sigma_bearing=scenario.sigma_bearing)
    return CooperativeSettings(
        odometry=odometry,
        sensor=sensor,
        filter="eif",
        linearisation=linearisation,
        second_order=linearisation != "latest",
        **CASES[case],
    )


def run_once(seed_sequence: np.random.SeedSequence, run_index: int) -> dict[str, Any]:
    """One Monte-Carlo run: simulate, then the plain, the FEJ and the OC EIF on every case
    (picklable task)."""
    scenario, sim, t, step = _simulated(seed_sequence)
    rec = sim.recording
    out_t = t[::step]
    result: dict[str, Any] = {"t": out_t, "truth": _poses(rec, step)}
    for block, linearisation in FILTERS.items():
        result[block] = {}
        for case in CASES:
            run = run_case(sim, case_settings(scenario, case, linearisation), out_t)
            if run_index != 0:
                run["mean"] = None
            result[block][case] = run
    if run_index == 0:
        k_mid = len(t) // 2
        result["prior"] = sim.prior
        result["rpmg"] = _rpmg_stats(rec)
        result["first_edges"] = _edges_at(rec, float(t[1]))
        result["mid_edges"] = _edges_at(rec, float(t[k_mid]))
        result["mid_state"] = _poses(rec, 1)[k_mid]
        result["mid_inputs"] = np.array([od.velocity[k_mid, [0, 3]] for od in rec.odometry])
    return result


def export_run0(args: ReproduceArgs, runs: int) -> dict[str, Any]:
    """``--mcap``/``--tum``: run 0's :data:`EXPORTED_CASE` again in this process (the same
    simulation: a run depends only on the seed and its index) and write its estimates."""
    from relloc.pipeline.export import export_estimates

    assert args.export is not None
    scenario, sim, t, step = _simulated(spawn_seeds(args.master_seed, runs)[0])
    estimates, _ = _case_estimates(sim, case_settings(scenario, EXPORTED_CASE), t[::step])
    return export_estimates(
        args.export,
        estimates,
        sim.recording,
        run=f"run 0 of {runs} (seed {args.master_seed}): {EXPORTED_RUN}",
    )


def _edges_at(recording: Recording, t: float) -> dict[str, list[tuple[int, int]]]:
    det = _detections(recording)
    assert det.landmark is not None
    sel = np.isclose(det.t, t)
    robot = sel & (det.target >= 0)
    lm = sel & (det.landmark >= 0)
    return {
        "robots": [
            (int(i), int(j)) for i, j in zip(det.observer[robot], det.target[robot], strict=True)
        ],
        "landmarks": [
            (int(i), int(k)) for i, k in zip(det.observer[lm], det.landmark[lm], strict=True)
        ],
    }


def _spanning_edges(edges: list[tuple[int, int]], n: int) -> list[tuple[int, int]]:
    """Breadth-first spanning tree of robot 0's component of the robot graph (keeps the symbolic
    rank test small); each tree edge keeps the direction ``observer → target`` it was measured
    in (the first such bearing when both robots see each other)."""
    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    for i, j in edges:
        if not graph.has_edge(i, j):
            graph.add_edge(i, j, measured=(i, j))
    return [graph.edges[a, b]["measured"] for a, b in nx.bfs_edges(graph, 0)]


def observability_ranks(first: dict[str, Any], n: int) -> dict[str, dict[str, Any]]:
    """Rank of the nonlinear observability matrix (``relloc.observability``) at the mid-run RPMG.

    Robot edges are reduced to a spanning tree of the observed RPMG (Theorem 2: any connected
    proper RPMG has the same rank); each landmark contributes one robot→landmark edge.
    """
    from relloc.models.symbolic import unicycle_team
    from relloc.observability.analysis import rank_at

    edges = first["mid_edges"]
    tree = [(i + 1, j + 1) for i, j in _spanning_edges(edges["robots"], n)]
    seen_lm: dict[int, int] = {}
    for i, k in edges["landmarks"]:
        seen_lm.setdefault(k, i)
    lm_xy = first["landmarks_xy"]
    state = first["mid_state"].reshape(-1)
    inputs = first["mid_inputs"].reshape(-1)
    out: dict[str, dict[str, Any]] = {}
    predicted = {
        "no_landmark": 3 * (n - 1),
        "one_landmark": 3 * n - 1,
        "two_landmarks": 3 * n,
        "gps_robot1": 3 * n,
    }
    for case, options in CASES.items():
        anchors = [k for k in options["anchors"] if k in seen_lm]
        lm_edges = [(seen_lm[k] + 1, a + 1) for a, k in enumerate(anchors)]
        model = unicycle_team(
            n,
            robot_edges=tree,
            landmark_edges=lm_edges,
            n_landmarks=len(anchors),
            gps=[1] if options.get("use_fixes") else [],
        )
        params = [float(c) for k in anchors for c in lm_xy[k]] or None
        rank = rank_at(model, state, inputs, params=params, order=2)
        out[case] = {
            "rank": int(rank),
            "state_dim": 3 * n,
            "full_rank": bool(rank == 3 * n),
            "paper_rank": predicted[case],
            "robot_edges": len(tree),
            "landmark_edges": len(lm_edges),
        }
    return out


def _growth(errors: Array, cov: Array) -> dict[str, float]:
    """Ratios (last quarter / second quarter) of the RMS position error and mean 1σ bound."""
    e = np.sqrt(np.mean(np.sum(errors[..., :2] ** 2, axis=-1), axis=(0, 2)))
    s = np.mean(np.sqrt(cov[..., 0, 0] + cov[..., 1, 1]), axis=(0, 2))
    T = e.size
    q2, q4 = slice(T // 4, T // 2), slice(3 * T // 4, T)
    return {
        "error_ratio": float(e[q4].mean() / e[q2].mean()),
        "sigma_ratio": float(s[q4].mean() / s[q2].mean()),
    }


def summarise(results: list[dict[str, Any]], n: int, block: str = "cases") -> dict[str, Any]:
    """Per-case accuracy, boundedness and consistency over all runs of one filter (``block``)."""
    from relloc.metrics import (
        chi2_upper,
        nees,
        percent_beyond,
        percent_beyond_interval,
        run_average_band,
    )

    cases: dict[str, Any] = {}
    for case in CASES:
        err = np.stack([r[block][case]["errors"] for r in results])  # (R, T, n, 3)
        cov = np.stack([r[block][case]["cov"] for r in results])  # (R, T, n, 3, 3)
        pos = np.sqrt(np.mean(np.sum(err[..., :2] ** 2, axis=-1), axis=(0, 1)))
        xr = np.sqrt(np.mean(err[..., 0] ** 2, axis=(0, 1)))
        yr = np.sqrt(np.mean(err[..., 1] ** 2, axis=(0, 1)))
        hr = np.sqrt(np.mean(err[..., 2] ** 2, axis=(0, 1)))
        ne = nees(err, cov)  # (R, T, n)
        times = np.broadcast_to(np.stack([r["t"] for r in results])[:, :, None], ne.shape)
        run = np.broadcast_to(np.arange(len(results))[:, None, None], ne.shape)
        bound = chi2_upper(3, 0.95)
        share = percent_beyond_interval(ne, times, bound, runs=run)
        growth = _growth(err, cov)
        bounded = growth["error_ratio"] < GROWTH_LIMIT and growth["sigma_ratio"] < GROWTH_LIMIT

        def per_robot(v: Array) -> dict[str, float]:
            d = {str(i + 1): float(v[i]) for i in range(n)}
            d["mean"] = float(np.sqrt(np.mean(v**2)))
            return d

        cases[case] = {
            "pos_rmse_m": per_robot(pos),
            "x_rmse_m": per_robot(xr),
            "y_rmse_m": per_robot(yr),
            "heading_rmse_rad": per_robot(hr),
            "bounded": bool(bounded),
            "paper_bounded": PAPER_BOUNDED[case],
            "growth": growth,
            "final_pos_err_m": float(np.sqrt(np.mean(np.sum(err[:, -1, :, :2] ** 2, axis=-1)))),
            "nees_pct_beyond": share.percent,
            "nees_beyond_interval": share.to_dict(),
            "nees_pct_beyond_per_run": [percent_beyond(run_nees, bound) for run_nees in ne],
            "anees": float(np.mean(ne) / 3.0),
            "nees_run_average": run_average_band(ne, 3),
            "used": float(np.mean([r[block][case]["used"] for r in results])),
            "rejected": float(np.mean([r[block][case]["rejected"] for r in results])),
            "frame_nees": frame_nees_summary(
                [r[block][case]["frame_nees"] for r in results], frame_times(results[0]["t"])
            ),
        }
    return cases


def frame_nees_summary(
    series: list[tuple[Array, int] | None], times: Array
) -> dict[str, Any] | None:
    """The runs' NEES along the unobservable directions (:func:`frame_nees` at ``times``, χ²(d)
    each, independent across runs). At the end: their mean against the two-sided 95 % band of
    a mean of ``R`` such values (verdict *over-confident* above it, *conservative* below), and
    the share beyond χ²_d(0.95) with its interval (each run one cluster). Along the run: the
    mean over the runs at each of ``times`` against the same band
    (:func:`relloc.metrics.run_average_band`). ``None`` without such directions."""
    from relloc.metrics import chi2_upper, mean_chi2_band, percent_beyond_interval, run_average_band

    if not series or any(v is None for v in series):
        return None
    table = np.stack([v[0] for v in series if v is not None])  # (R, K)
    dof = {v[1] for v in series if v is not None}.pop()
    final = table[:, -1]
    lo, hi = mean_chi2_band(dof, final.size)
    mean = float(np.mean(final))
    share = percent_beyond_interval(
        final, np.zeros(final.size), chi2_upper(dof, 0.95), runs=np.arange(final.size)
    )
    verdict = "over-confident" if mean > hi else "conservative" if mean < lo else "consistent"
    return {
        "dof": dof,
        "per_run": final.tolist(),
        "mean": mean,
        "band": [lo, hi],
        "verdict": verdict,
        "pct_beyond": share.percent,
        "beyond_interval": share.to_dict(),
        "along_the_run": {
            "t": [float(t) for t in times],
            "mean_over_runs": table.mean(axis=0).tolist(),
            **run_average_band(table, dof),
        },
    }


def headline_aware(plain: dict[str, Any], aware: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Which observability-aware filter is the headline one, and why.

    A filter meets the target when, in every case of :data:`AWARE_CASES`, its NEES share beyond
    χ²₃(0.95) is at most :data:`AWARE_NEES_LIMIT_PCT` and its position RMSE is not above the
    plain EIF's. The headline is the one meeting it with the smaller worst NEES share; if none
    does, the one with the smaller worst NEES share, with ``target_met`` false.
    """

    def worst(block: str) -> float:
        return max(aware[block][c]["nees_pct_beyond"] for c in AWARE_CASES)

    def meets(block: str) -> bool:
        return worst(block) <= AWARE_NEES_LIMIT_PCT and all(
            aware[block][c]["pos_rmse_m"]["mean"] <= plain[c]["pos_rmse_m"]["mean"]
            for c in AWARE_CASES
        )

    met = [b for b in aware if meets(b)]
    block = min(met or list(aware), key=worst)
    return {
        "block": block,
        "filter": FILTER_LABELS[block],
        "target_met": bool(met),
        "meets_target": {b: meets(b) for b in aware},
        "worst_nees_pct_beyond": {b: worst(b) for b in aware},
        "target": (
            f"NEES beyond χ²₃(0.95) ≤ {AWARE_NEES_LIMIT_PCT:g} % in "
            f"{' and '.join(AWARE_CASES)}, position RMSE not above the plain EIF's"
        ),
        "nees_beyond_interval": {c: aware[block][c]["nees_beyond_interval"] for c in AWARE_CASES},
        "nees_pct_beyond_per_run": {
            c: aware[block][c]["nees_pct_beyond_per_run"] for c in AWARE_CASES
        },
        "frame_nees": {c: aware[block][c]["frame_nees"] for c in AWARE_CASES},
    }


def _figures(out: Any, first: dict[str, Any], scenario: Any) -> list[tuple[str, str]]:
    from relloc.plotting.cooperative import plot_case_series, plot_topology
    from relloc.plotting.errors import plot_trajectories
    from relloc.plotting.setup import pyplot

    plt = pyplot()

    figs: list[tuple[str, str]] = []
    n = scenario.n_robots
    prior = first["prior"]
    fig, ax = plt.subplots(figsize=(7, 5))
    plot_topology(
        ax,
        first["truth"][0, :, :2],
        prior.mean.reshape(n, 3)[:, :2],
        np.sqrt(np.diag(prior.cov)).reshape(n, 3)[:, :2],
        scenario.landmarks_xy,
        first["first_edges"]["robots"],
        first["first_edges"]["landmarks"],
    )
    ax.set_title("Initial RPMG (cf. seed 001 Fig. 3)")
    figs.append((save_figure(fig, out, "fig3_topology"), "Initial topology and 3σ circles"))

    fig, ax = plt.subplots(figsize=(7, 5))
    plot_trajectories(ax, {f"robot {i + 1}": first["truth"][:, i, :2] for i in range(n)})
    ax.plot(*scenario.landmarks_xy.T, "s", color="tab:green", ms=8)
    ax.set_title("True trajectories (cf. Fig. 4)")
    figs.append((save_figure(fig, out, "fig4_trajectories"), "True trajectories"))

    robot = 1  # the paper's "second robot"
    paths = {"true": first["truth"][:, robot, :2]}
    for case in CASES:
        paths[CASE_LABELS[case]] = first["cases"][case]["mean"][:, robot, :2]
    fig, ax = plt.subplots(figsize=(7, 5))
    plot_trajectories(ax, paths)
    ax.set_title("Robot 2: true and estimated trajectories (cf. Fig. 5)")
    figs.append((save_figure(fig, out, "fig5_robot2_estimates"), "Robot 2 estimates, run 0"))

    t = first["t"]
    for k, (name, label) in enumerate((("fig6_robot2_error_x", "x"), ("fig7_robot2_error_y", "y"))):
        fig, ax = plt.subplots(figsize=(7, 3.5))
        plot_case_series(
            ax,
            t,
            {CASE_LABELS[c]: first["cases"][c]["errors"][:, robot, k] for c in CASES},
            ylabel=f"error in {label} (m)",
        )
        ax.set_title(f"Robot 2 error in {label} (cf. Fig. {6 + k})")
        figs.append((save_figure(fig, out, name), f"Robot 2 error in {label}, run 0"))
    for k, (name, label) in enumerate(
        (
            ("fig8_robot2_3sigma_x", "x (m)"),
            ("fig9_robot2_3sigma_y", "y (m)"),
            ("fig10_robot2_3sigma_psi", "ψ (rad)"),
        )
    ):
        fig, ax = plt.subplots(figsize=(7, 3.5))
        plot_case_series(
            ax,
            t,
            {CASE_LABELS[c]: 3 * np.sqrt(first["cases"][c]["cov"][:, robot, k, k]) for c in CASES},
            ylabel=f"3σ {label}",
            log=True,
        )
        ax.set_title(f"Robot 2 3σ in {label} (cf. Fig. {8 + k})")
        figs.append((save_figure(fig, out, name), f"Robot 2 3σ bound in {label}, run 0"))
    return figs


def _nees_figure(out: Any, results: list[dict[str, Any]]) -> tuple[str, str]:
    """Run-averaged NEES of robot 2 over time, both filters, the unanchored cases."""
    from relloc.metrics import mean_chi2_band, nees
    from relloc.plotting.cooperative import plot_case_series
    from relloc.plotting.setup import pyplot

    plt = pyplot()
    robot = 1
    series = {}
    for block, label in FILTER_LABELS.items():
        for case in ("no_landmark", "one_landmark"):
            err = np.stack([r[block][case]["errors"][:, robot] for r in results])
            cov = np.stack([r[block][case]["cov"][:, robot] for r in results])
            series[f"{label}, {CASE_LABELS[case]}"] = nees(err, cov).mean(axis=0)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    plot_case_series(ax, results[0]["t"], series, ylabel="NEES, mean over runs", log=True)
    if len(results) >= 2:
        for bound in mean_chi2_band(3, len(results)):
            ax.axhline(bound, color="0.3", ls="--", lw=0.8)
    ax.set_title(f"Robot 2: NEES averaged over {len(results)} runs, with its 95 % band")
    return (
        save_figure(fig, out, "nees_run_average"),
        "Robot 2 NEES averaged over the runs at each instant, plain, FEJ and OC EIF",
    )


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    """Run the Monte Carlo, write summary.json, report.md and the figures."""
    out = prepare_out_dir(args.out_dir)
    runs = args.runs or DEFAULT_RUNS
    scenario = _scenario()
    n = scenario.n_robots
    results = run_monte_carlo(
        run_once,
        runs,
        args.master_seed,
        executor=args.executor,
        description="sharma2013",
        quiet=args.quiet,
    )
    first = results[0]
    first["landmarks_xy"] = scenario.landmarks_xy
    cases = summarise(results, n)
    aware = {block: summarise(results, n, block) for block in AWARE_BLOCKS}
    ranks = observability_ranks(first, n)
    for case in CASES:
        cases[case]["observability_rank"] = ranks[case]
    summary: dict[str, Any] = {
        "experiment": "sharma2013",
        "seed": args.master_seed,
        "runs": runs,
        "scenario": {
            "n_robots": n,
            "landmarks": 2,
            "sensing_range_m": scenario.sensing_range,
            "speed_mps": scenario.speed,
            "ts_s": scenario.dt,
            "duration_s": scenario.duration,
            "initial_sigma": list(scenario.initial_sigma),
            "sigma_v": scenario.sigma_v,
            "sigma_w": scenario.sigma_w,
            "sigma_bearing": scenario.sigma_bearing,
            "gps_sigma": list(scenario.gps_sigma),
            "gps_period_s": scenario.gps_period,
        },
        "rpmg": first["rpmg"],
        "filters": FILTER_LABELS,
        "nees_on": NEES_ON,
        "cases": cases,
        **aware,
        "observability_aware": headline_aware(cases, aware),
        "departures": departures(scenario.duration, runs),
    }
    if args.export is not None:
        summary["export"] = export_run0(args, runs)
    figures = _figures(out, first, scenario)
    figures.append(_nees_figure(out, results))
    write_summary(out, summary)
    write_report(out, _report(summary, figures))
    return summary


def _headline_text(headline: dict[str, Any]) -> str:
    worst = ", ".join(
        f"{FILTER_LABELS[b]} {v:.1f} %" for b, v in headline["worst_nees_pct_beyond"].items()
    )
    verdict = "meets it" if headline["target_met"] else "does not meet it (no filter does)"
    among = "of the filters meeting the target, " if headline["target_met"] else ""
    return (
        f"Headline observability-aware filter: **{headline['filter']}**, {among}the one with "
        f"the smaller worst NEES share ({worst}); target: {headline['target']}; it {verdict}. "
        "The target is judged on the shares themselves; their 95 % intervals (cluster means, "
        "each independent run one cluster) and verdicts: "
        + "; ".join(
            f"{CASE_LABELS[c]} {interval_text(share)}"
            for c, share in headline["nees_beyond_interval"].items()
        )
        + ". A run's own share (median, largest over the runs): "
        + "; ".join(
            f"{CASE_LABELS[c]} {np.median(v):.1f} %, {max(v):.1f} %"
            for c, v in headline["nees_pct_beyond_per_run"].items()
        )
        + ". Along the unobservable directions (the runs' final frame NEES, below): "
        + "; ".join(
            f"{CASE_LABELS[c]} mean {f['mean']:.3g} against {f['band'][0]:.3g}–{f['band'][1]:.3g}, "
            f"{f['verdict']}"
            for c, f in headline["frame_nees"].items()
            if f is not None
        )
        + "."
    )


def _frame_table(summary: dict[str, Any]) -> str:
    """The final frame NEES (:func:`frame_nees_summary`) per unanchored case and filter."""
    rows = []
    for case in AWARE_CASES:
        for block in FILTERS:
            f = summary[block][case]["frame_nees"]
            if f is None:
                continue
            rows.append(
                [
                    CASE_LABELS[case],
                    FILTER_LABELS[block],
                    f["dof"],
                    f["mean"],
                    f"{f['band'][0]:.3g}–{f['band'][1]:.3g}",
                    f["verdict"],
                    f["pct_beyond"],
                    interval_text(f["beyond_interval"]),
                    f["along_the_run"].get("in_band_percent"),
                    run_average_verdict_text(f["along_the_run"]),
                ]
            )
    return markdown_table(
        [
            "case",
            "filter",
            "d",
            "mean over runs",
            "95 % band of the mean",
            "verdict",
            "% beyond χ²_d(.95)",
            "its 95 % interval",
            f"along the run: mean in band (%, every {FRAME_EVERY_S:g} s)",
            "its verdict",
        ],
        rows,
    )


def _report(summary: dict[str, Any], figures: list[tuple[str, str]]) -> str:
    cases = summary["cases"]
    n = summary["scenario"]["n_robots"]
    rows = []
    for case, c in cases.items():
        rank = c["observability_rank"]
        rows.append(
            [
                CASE_LABELS[case],
                c["pos_rmse_m"]["mean"],
                c["heading_rmse_rad"]["mean"],
                c["final_pos_err_m"],
                c["growth"]["error_ratio"],
                c["growth"]["sigma_ratio"],
                c["bounded"],
                c["paper_bounded"],
                rank["rank"],
                rank["paper_rank"],
                c["nees_pct_beyond"],
            ]
        )
    table = markdown_table(
        [
            "case",
            "pos RMSE (m)",
            "heading RMSE (rad)",
            "final pos err (m)",
            "error growth",
            "σ growth",
            "bounded",
            "paper: bounded",
            "obs. rank",
            f"paper rank (of {3 * n})",
            "NEES > χ²₃(.95) (%)",
        ],
        rows,
    )
    per_robot = markdown_table(
        ["case", *[f"robot {i + 1} pos / heading" for i in range(n)]],
        [
            [
                CASE_LABELS[case],
                *[
                    f"{c['pos_rmse_m'][str(i + 1)]:.3g} m / {c['heading_rmse_rad'][str(i + 1)]:.3g}"
                    for i in range(n)
                ],
            ]
            for case, c in cases.items()
        ],
    )
    both = markdown_table(
        [
            "case",
            "filter",
            "pos RMSE (m)",
            "heading RMSE (rad)",
            "final pos err (m)",
            "NEES > χ²₃(.95) (%)",
            "its 95 % interval",
            "ANEES",
            "run-avg NEES in 95 % band (%)",
            "verdict",
            "bounded",
        ],
        [
            [
                CASE_LABELS[case],
                FILTER_LABELS[block],
                c["pos_rmse_m"]["mean"],
                c["heading_rmse_rad"]["mean"],
                c["final_pos_err_m"],
                c["nees_pct_beyond"],
                interval_text(c["nees_beyond_interval"]),
                c["anees"],
                c["nees_run_average"].get("in_band_percent"),
                run_average_verdict_text(c["nees_run_average"]),
                c["bounded"],
            ]
            for case in CASES
            for block in FILTERS
            for c in (summary[block][case],)
        ],
    )
    band = cases["no_landmark"]["nees_run_average"]
    band_text = (
        f"[{band['band'][0]:.2f}, {band['band'][1]:.2f}] for {band['runs']} runs"
        if band.get("band")
        else "not available (one run)"
    )
    borderline = [
        CASE_LABELS[case]
        for case, c in cases.items()
        if any(abs(r - GROWTH_LIMIT) < 0.05 for r in c["growth"].values())
    ]
    note = (
        "Borderline (a growth ratio within 0.05 of the limit): "
        + ", ".join(borderline)
        + ". Without full observability the global error drifts slowly (a random walk of the "
        "unobservable translation/rotation), so its growth over 300 s is modest; the NEES "
        "column shows that the filter does not account for it."
        if borderline
        else ""
    )
    s = summary["scenario"]
    parts = [
        "# Seed 001 (Sharma et al. 2013): bearing-only cooperative localization, simulation",
        f"Seed {summary['seed']}, {summary['runs']} Monte-Carlo runs, {s['duration_s']:g} s each; "
        f"{n} robots at {s['speed_mps']} m/s, R_sensor {s['sensing_range_m']} m, Ts {s['ts_s']} s, "
        f"σ_v {s['sigma_v']}, σ_ω {s['sigma_w']}, σ_η {s['sigma_bearing']}; "
        "centralised EIF, plain, with first-estimates and with observability-constrained "
        "Jacobians. Regenerate: "
        f"`relloc reproduce sharma2013 --out DIR --runs {summary['runs']} "
        f"--seed {summary['seed']}`.",
        "## Accuracy, boundedness and observability (plain EIF)",
        table,
        "Growth = mean over the last quarter / mean over the second quarter of the run (RMS "
        "position error over runs and robots, and mean 1σ position bound); *bounded* when both "
        f"are below {GROWTH_LIMIT}. {note} Observability rank: the nonlinear observability matrix "
        "(Lie derivatives up to order 2, `relloc.observability.analysis`) at the true "
        "mid-run state with a spanning tree of the RPMG observed then.",
        f"RPMG connected during {100 * summary['rpmg']['connected_fraction']:.1f} % of the "
        f"measurement epochs; β(G) = 1 (every robot has a path to both landmarks) during "
        f"{100 * summary['rpmg']['beta_fraction']:.1f} %.",
        "## Plain EIF and observability-aware (FEJ, OC) EIFs",
        both,
        _headline_text(summary["observability_aware"]),
        f"NEES on: {summary['nees_on']}. *NEES > χ²₃(.95)*: share of all (run, instant, robot) "
        "samples beyond the single-sample bound (about 5 % when consistent; each sample's "
        "exceedance probability, no independence needed); its 95 % interval's verdict is "
        "*over-confident* when the interval lies wholly above 5 %, *conservative* wholly "
        "below, *consistent* when it holds 5 % and reaches no higher than 10 % (twice it), "
        "*inconclusive* when it holds 5 % but reaches above 10 % (not rejected, not shown "
        "consistent either). *Run-avg NEES in band*: at each "
        "instant and for each robot, the NEES averaged over the independent runs against the "
        f"two-sided 95 % band of such a mean, {band_text} (about 95 % when consistent; verdict "
        "*over-confident* when the share above is significantly more than 2.5 % — its 95 % "
        "interval by batch means over the instants, widened on blocks shorter than ten "
        "correlation times, lies wholly above —, *conservative* when "
        "the share below is, else *consistent*). The FEJ "
        "EIF evaluates every Jacobian at the first estimate of the state it differentiates "
        "(`relloc.estimators.first_estimates`), so the linearised team keeps the nonlinear "
        "team's unobservable global translation and rotation; the OC EIF linearises at the "
        "latest estimate and changes the Jacobians least (Frobenius norm) so that they keep "
        "that subspace (`relloc.estimators.observability_constrained`; its transition couples "
        "the robots); the plain EIF evaluates the motion Jacobian at the updated estimate and "
        "thereby makes the global rotation appear observable. Both observability-aware EIFs "
        "add each bearing's second-order mean and variance under the prior "
        "(`relloc.estimators.second_order`): at the start the robots are 6–35 m apart with 5 m "
        "errors, a first-order bearing update is wrong over that spread (it stretches the "
        "formation along its weakly observable scale), and an error it leaves along the "
        "unobservable directions is never corrected.",
        "## Along the unobservable directions: the final frame NEES",
        _frame_table(summary),
        "Frame NEES: at the end of each run, the NEES of the team's joint error (all "
        f"{3 * n} states, the filter's joint covariance) along the unobservable directions "
        "only — global translation and rotation with no landmark (d = 3), the rotation about "
        "the landmark with one (d = 1) — by generalised least squares "
        "(`relloc.metrics.projected_nees`): χ²(d) for a consistent filter, one value per "
        "independent run, so the runs' mean has an exact band (verdict *over-confident* above "
        "it, *conservative* below) and the share beyond χ²_d(0.95) should be about 5 %. It "
        "tests the filters exactly where a linearised filter gains spurious information. "
        f"*Along the run*: the same NEES every {FRAME_EVERY_S:g} s, averaged over the runs at "
        "each of those times against the same band (`relloc.metrics.run_average_band`, with "
        "its verdict, as for the run-averaged NEES above).",
        "## Per-robot RMSE, plain EIF (position m / heading rad)",
        per_robot,
        "## How this compares with the paper",
        "The paper shows single-run figures and no numbers; what it claims is qualitative: with no "
        "landmark or one landmark the team is not fully observable (rank 3(n−1) resp. 3n−1) and "
        "the error and 3σ drift, with two landmarks or GPS on one robot they are observable (rank "
        "3n) and bounded. The table checks each claim. Without anchors the EIF's 1σ bound is "
        "smaller than the actual error (NEES far above χ²): the linearised filter gains "
        "spurious information along the unobservable directions (global translation and "
        "rotation), a known inconsistency of EKF/EIF cooperative localization that the paper does "
        "not discuss; the FEJ and OC EIFs above are built to remove it (compare the NEES "
        "columns of the filters).",
        "## Departures from the paper",
        "\n".join(f"- {d}" for d in summary["departures"]),
        "## Figures",
        *[figure_md(f, c) for f, c in figures],
    ]
    return "\n\n".join(parts)
