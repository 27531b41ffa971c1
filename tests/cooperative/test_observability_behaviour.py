"""Observability-consistent behaviour on short seeded runs (seed 001 Theorems 2–3).

Without landmarks the global pose of the team is unobservable: the filter keeps the relative
geometry (inter-robot distances) but cannot remove the common translation/rotation error, and
its position uncertainty stays at the initial level. With two landmarks everything is
observable: errors and bounds collapse to the sensing accuracy.
"""

import numpy as np
import pytest

from relloc.estimators.cooperative import CooperativeSettings, OdometryModel, SensorModel
from relloc.metrics import state_errors
from relloc.sim.cooperative import sharma2013_scenario, simulate


@pytest.fixture(scope="module")
def runs(team_run):
    scenario = sharma2013_scenario(duration=40.0)
    sim = simulate(scenario, np.random.default_rng(7))
    rec = sim.recording
    odo = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt)
    out_t = rec.truth[0].t[::20]
    truth = np.stack([g.pose[::20][:, [0, 1, 3]] for g in rec.truth], axis=1)
    results = {}
    for name, anchors in (("none", ()), ("two", (0, 1))):
        settings = CooperativeSettings(
            odometry=odo, sensor=SensorModel(sigma_bearing=scenario.sigma_bearing), anchors=anchors
        )
        run = team_run(rec, sim.prior, settings, out_t)
        results[name] = (run, state_errors(run.mean, truth, angle_indices=(2,)), truth)
    return results


def _pairwise_distances(xy):
    d = xy[..., :, None, :] - xy[..., None, :, :]
    return np.linalg.norm(d, axis=-1)


def test_without_landmarks_global_error_stays_but_geometry_is_kept(runs):
    run, err, truth = runs["none"]
    last = slice(-5, None)
    global_err = np.sqrt(np.mean(np.sum(err[last, :, :2] ** 2, axis=-1)))
    dist_err = _pairwise_distances(run.mean[last, :, :2]) - _pairwise_distances(truth[last, :, :2])
    geometry_err = np.sqrt(np.mean(dist_err**2))
    sigma = np.sqrt(run.cov[-1, :, 0, 0] + run.cov[-1, :, 1, 1])
    assert global_err > 2.0  # initial σ 5 m per robot: the common error cannot be removed
    assert geometry_err < 0.25 * global_err  # inter-robot distances are learned
    assert sigma.min() > 2.0  # the bound stays at the unobservable level


def test_with_two_landmarks_the_error_is_bounded(runs):
    run, err, _ = runs["two"]
    none_run = runs["none"][0]
    last = slice(-5, None)
    global_err = np.sqrt(np.mean(np.sum(err[last, :, :2] ** 2, axis=-1)))
    sigma = np.sqrt(run.cov[last, :, 0, 0] + run.cov[last, :, 1, 1])
    none_sigma = np.sqrt(none_run.cov[last, :, 0, 0] + none_run.cov[last, :, 1, 1])
    assert global_err < 2.0
    assert sigma.max() < 1.5
    assert np.all(sigma < 0.5 * none_sigma)
    assert np.sqrt(np.mean(err[last, :, 2] ** 2)) < 0.05


def test_along_the_unobservable_directions_oc_is_consistent_and_plain_over_confident():
    # Twelve independent 150 s runs with no landmark; each run's final NEES along the global
    # translation and rotation (sharma2013.frame_nees) is chi2(3) for a consistent filter, so
    # the mean of twelve lies in [1.20, 5.88] with probability 0.999. Developed on root 5: OC
    # EIF 2.71, plain EIF 23.8 (spurious information along the rotation). Root 90421 was not
    # used while developing.
    from relloc.experiments import sharma2013
    from relloc.metrics import mean_chi2_band

    lo, hi = mean_chi2_band(3, 12, 0.999)
    frame = {"latest": [], "observability_constrained": []}
    for seq in np.random.SeedSequence(90421).spawn(12):
        scenario = sharma2013_scenario(duration=150.0)
        sim = simulate(scenario, np.random.default_rng(seq))
        out_t = sim.recording.truth[0].t[::50]
        for lin, values in frame.items():
            settings = sharma2013.case_settings(scenario, "no_landmark", lin)
            series, dof = sharma2013.run_case(sim, settings, out_t)["frame_nees"]
            assert dof == 3 and series.size == 5  # at 30, 60, ..., 150 s
            values.append(series[-1])
    assert lo <= np.mean(frame["observability_constrained"]) <= hi
    assert np.mean(frame["latest"]) > hi
