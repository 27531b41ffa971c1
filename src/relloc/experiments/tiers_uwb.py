"""UWB localization of a TurtleBot team on real ROS 2 bags (TIERS layouts).

``relloc reproduce tiers-uwb --out DIR [--bag BAG --map MAP] [--calibrate-on BAG]``

Without ``--bag`` both bags of ``../shared/data/tiers`` run with their shipped mappings
(``relloc/datasets/mappings``); with ``--bag`` only that bag, read through ``--map``. Nothing
about a bag is assumed beyond its mapping: robots, radios, anchors, pairs and windows all follow
from the mapping and the data.

What runs on each bag (:func:`analyse_bag`; the calibration is
:mod:`relloc.calibration.uwb_bag`, the team part :mod:`relloc.experiments.tiers_uwb_team`, the
pairs :mod:`relloc.experiments.tiers_uwb_pairs`):

(c) **Calibration.** The UWB error model (:func:`relloc.calibration.uwb.fit_uwb_noise`: bias per
    link, spread, outliers, correlation) is fitted on readings whose two radios have known
    positions (motion capture ⊕ antenna offset, or surveyed): on the first
    ``CALIBRATION_FRACTION`` of the bag, or on the whole ``--calibrate-on`` bag (links matched by
    radio names; a link it lacks takes the fitted team bias). Everything below is scored on the
    rest of the bag (the whole bag with ``--calibrate-on``), where the held-out range error
    before and after the correction is reported too.
(b) **Team, ranges only** (:class:`~relloc.estimators.uwb_range.RangeTeamFilter`, constant
    velocity prior): every robot with ground truth, started from the classical-MDS positions of
    the first ``INIT_S`` seconds of ranges, scored (1) *aligned*: at each record time after the
    best rigid alignment of all estimated positions onto motion capture (rotation + translation,
    no scale; reflections allowed, since ranges cannot tell a mirror image), and (2) *anchored*:
    the mapping's ``anchors`` (default: the robots whose motion capture moves less than
    ``STANDING_M`` from where they start) are fixed at their motion-capture start and the others
    estimated in the world frame; when every robot stands, each in turn is estimated with the
    others as anchors (leave-one-out).
(a) **Pairs, range + odometry** (:class:`~relloc.estimators.uwb_range.RangePairBank`): every pair
    of robots that both have odometry, are linked by a range and of which at least one moves by
    its odometry (path length > ``MOVING_M``), from an unknown start; the observability verdict
    per pair comes from relloc's own tool (rank of the observability matrix of the range-only
    seed-000 model along the recorded relative states and inputs,
    :class:`~relloc.observability.analysis.InputRankEvaluator`; and the generic input conditions
    of :func:`~relloc.observability.analysis.analyse`).
(d) **Baselines** side by side: raw multilateration (latest raw range per link within
    ``LATEST_S``, least squares, no memory), uncalibrated ranges (the same filters without the
    bias correction) and, for pairs, odometry alone (both odometries integrated from the true
    relative pose at the start of the scored stretch).

summary.json: ``experiment``, ``seed`` (``None``: nothing is drawn at random), ``runs`` (1),
``bags.<name>`` (times in s on the bag's clock, from ``loader.time_origin_unix_s``):
``loader`` (:meth:`relloc.datasets.rosbag.BagRecording.to_dict`: ``bag``, ``mapping``,
``time_origin_unix_s``, ``stamp_offset_s`` (topic → median receive − header stamp, s, and
``bag``: the pooled median), ``stamps_from_receive`` (topic → messages with an unset header
stamp, timed by their receive time),
``unknown_topics``, ``uwb_readings``, ``uwb_readings_not_in_recording`` (reason → count),
``skips``: ``rows_skipped``, ``by_reason``, ``files`` → ``rows_read``, ``rows_kept``,
``skipped``, ``examples``), ``calibration`` (``source`` ``window`` or ``bag`` with that
``bag``'s path, the ``window`` (``start_s``, ``end_s``, ``source``), the ``fit``
(:meth:`relloc.calibration.uwb.UwbNoiseFit.to_dict`, lengths in m: ``bias_m``, ``spread_m``,
``outlier_rate``, ``outlier_threshold_sigma``, ``outlier_excess_mean_m``,
``outlier_positive_fraction``, ``link_bias_std_m``, ``correlation_time_s``,
``lag1_correlation``, ``sample_period_s``, ``link_biases_m`` keyed by radio indices ``"0-1"``
…, ``n_rows``, ``n_links``, ``rows_skipped``, ``calibration_window``; as guler2023's
``uwb_noise_fit`` describes them),
``link_bias_m`` the same biases by radio names ``"n_3-n_4"`` …, ``bias_drift_m`` (how far a
link's bias moves within the window, :func:`relloc.calibration.uwb_bag.bias_drift`),
``range_sigma_m`` the σ of one range the filters use, ``mapping_sigma_replaced_m`` the
mapping's ``uwb.sigma`` it replaces (``None`` without one), ``heldout``: the range error
(reading − true distance) over the scored window, ``rows`` and, where there are any, ``raw``
and ``calibrated`` (``mean_m``, ``std_m``, ``rmse_m``)), ``scored_window_s`` (``[start,
end]``), ``team.aligned`` and ``team.anchored`` (``pos_rmse_m``, m, over ``records``, the
record times at 10 Hz at which every scored robot has an estimate; ``nees_pct_beyond``: share
of the scored robots' 2-DOF NEES values at those times that exceed χ²₂(0.95), with
``nees_beyond_interval`` its 95 % interval by batch means over time (widened on short blocks,
:func:`relloc.metrics.percent_beyond_interval`; :class:`relloc.metrics.BeyondShare`'s keys)
and the verdict — one run, whose records are correlated in time; over-confident,
conservative, consistent or inconclusive, :func:`relloc.metrics.consistency.share_verdict` —,
``converged_after_s`` (s
from the first record until every scored robot's error stays below 0.3 m for good; null if it
never does), ``per_robot`` (anchored only: robot → ``pos_rmse_m``),
``baselines.uncalibrated`` / ``baselines.multilateration`` ``pos_rmse_m`` (the latter at
2 Hz), ``anchors`` (robot names; empty when aligned), ``mode`` (``"aligned"``, ``"anchors"``
or ``"leave-one-out"``), ``mirror_ambiguous`` (exactly two anchors, or two for each robot
of a leave-one-out of three), ``mirror_image_scored`` (the mirror image in their line was the
closer and was scored; in a leave-one-out, for some robot); where no record has every
scored robot's estimate, ``pos_rmse_m`` is null, ``records`` 0 and the NEES and convergence
keys are absent; ``team.anchored`` is
only ``skipped`` with its reason when the bag has fewer than two anchors), ``pairs.<a->b>``
(one per pair of :func:`~relloc.experiments.tiers_uwb_pairs.moving_pairs`, in the owner's body
frame, with keys of their own: ``pos_rmse_m`` of the 3-D relative position, ``nees_pct_beyond``
of the 4-DOF NEES beyond χ²₄(0.95) with ``nees_beyond_interval``, ``converged_after_s``
(position error below 0.3 m on each axis and yaw error below 0.5 rad for good), ``records``,
``ranges_gated`` the ranges the filter's χ² gate rejected, ``baselines.uncalibrated`` and
``baselines.odometry_alone`` ``pos_rmse_m``, ``observability``: ``verdict``,
``full_rank_share`` (share of the ``samples`` instants of the scored stretch at full rank),
``max_rank``, ``state_dim``, ``samples``, ``generic_conditions`` (text)).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from relloc.calibration.uwb_bag import calibrate, corrected, heldout_errors
from relloc.calibration.window import leading_fraction, spanning
from relloc.datasets.bag_mapping import BagMapping, load_mapping
from relloc.datasets.paths import DATA_HINT, shared_data_dir
from relloc.datasets.rosbag import BagRecording, load_bag
from relloc.errors import ConfigError, DataError
from relloc.estimators.uwb_range import RangeTeamSettings
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.tiers_uwb_pairs import CONVERGED_M, CONVERGED_YAW, moving_pairs, pair_case
from relloc.experiments.tiers_uwb_team import standing_robots, team_case
from relloc.pipeline.output import (
    bag_rows_source,
    interval_text,
    markdown_table,
    prepare_out_dir,
    skipped_rows_line,
    write_report,
    write_summary,
)

#: Share of a bag, from its start, the UWB error model is fitted on (when not --calibrate-on).
CALIBRATION_FRACTION = 0.3
SHIPPED = (
    ("cooperative_shortbag", "tiers_cooperative"),
    ("relative_case4_test1", "tiers_relative"),
)


def analyse_bag(bag: BagRecording, calibration_bag: BagRecording | None) -> dict[str, Any]:
    """Everything of the module docstring on one bag."""
    rec = bag.recording
    if rec.truth is None:
        missing = ", ".join(rec.meta.get("robots_without_truth", [])) or "some robots"
        raise DataError(
            f"{bag.path}: tiers-uwb scores against motion capture, and {missing} have none "
            "(no truth topic, or fewer than two usable messages): leave them out of the mapping"
        )
    span0, span1 = rec.span
    if calibration_bag is None:
        window = leading_fraction(span0, span1, CALIBRATION_FRACTION, str(bag.path))
        cal = calibrate(bag, window)
        t0 = window.end_s
        cal_info: dict[str, Any] = {"source": "window", "window": window.to_dict()}
    else:
        window = spanning(calibration_bag.ranges.t, str(calibration_bag.path))
        cal = calibrate(calibration_bag, window)
        t0 = span0
        cal_info = {"source": "bag", "bag": str(calibration_bag.path), "window": window.to_dict()}
    cal_info["fit"] = cal.fit.to_dict()
    cal_info["link_bias_m"] = {f"{a}-{b}": v for (a, b), v in sorted(cal.link_bias.items())}
    cal_info["heldout"] = heldout_errors(bag, cal, t0, span1)
    cal_info["bias_drift_m"] = cal.bias_drift
    cal_info["range_sigma_m"] = cal.range_sigma
    uwb = bag.mapping.uwb
    cal_info["mapping_sigma_replaced_m"] = None if uwb is None else uwb.sigma
    sigma = cal.range_sigma
    fixed = corrected(bag, cal, sigma)
    raw = corrected(bag, None, sigma)
    team_settings = RangeTeamSettings(sigma_range=sigma)
    anchors = standing_robots(rec, bag.mapping)
    team = {
        "aligned": team_case(fixed, raw, t0, span1, anchors, team_settings, anchored=False),
        "anchored": team_case(fixed, raw, t0, span1, anchors, team_settings, anchored=True),
    }
    pairs = {
        f"{rec.robots[i]}->{rec.robots[j]}": pair_case(fixed, raw, i, j, t0, span1, sigma)
        for i, j in moving_pairs(rec)
    }
    return {
        "loader": bag.to_dict(),
        "calibration": cal_info,
        "scored_window_s": [t0, span1],
        "team": team,
        "pairs": pairs,
    }


def _bags(args: ReproduceArgs) -> list[tuple[Path, BagMapping]]:
    if args.bag is not None:
        if args.map is None:
            raise ConfigError("--bag needs --map (the bag's topic mapping TOML)")
        return [(args.bag, load_mapping(args.map))]
    if args.map is not None:
        raise ConfigError("--map needs --bag")
    folder = shared_data_dir() / "tiers"
    if not folder.is_dir():
        raise DataError(
            f"{folder}: the TIERS bags are not there; pass --bag BAG --map MAP or {DATA_HINT}"
        )
    return [(folder / name, load_mapping(mapping)) for name, mapping in SHIPPED]


def _storage(bag: Path) -> set[Path]:
    """The files holding a bag's messages: a bag folder's ``.db3``/``.mcap`` files, or the file
    itself (the same recording named as a folder and as its file is one bag)."""
    if bag.is_dir():
        return {f.resolve() for f in bag.iterdir() if f.suffix in (".db3", ".mcap")}
    return {bag.resolve()}


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    out_dir = prepare_out_dir(args.out_dir)
    summary: dict[str, Any] = {"experiment": "tiers-uwb", "seed": None, "runs": 1, "bags": {}}
    bags = _bags(args)
    for path, mapping in bags:
        calibration_bag = None
        if args.calibrate_on is not None:
            if _storage(args.calibrate_on) & _storage(path):
                raise ConfigError(
                    f"--calibrate-on {args.calibrate_on}: that is the bag being scored; a fit "
                    "must be scored on data it was not fitted on (leave --calibrate-on out to "
                    f"fit on the first {CALIBRATION_FRACTION:.0%} of the bag)"
                )
            calibration_bag = load_bag(args.calibrate_on, mapping)
        summary["bags"][path.name] = analyse_bag(load_bag(path, mapping), calibration_bag)
    write_summary(out_dir, summary)
    write_report(out_dir, report(summary))
    return summary


def _f(x: Any) -> Any:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else x


def report(summary: dict[str, Any]) -> str:
    """report.md: per bag the calibration, the team table and the pair table."""
    lines = ["# tiers-uwb: UWB localization on real ROS 2 bags", ""]
    for name, b in summary["bags"].items():
        cal = b["calibration"]
        fit = cal["fit"]
        w = cal["window"]
        lines += [
            f"## {name}",
            "",
            f"Calibrated on {cal['source']} `{w['source']}` "
            f"[{w['start_s']:.1f}, {w['end_s']:.1f}] s: bias {fit['bias_m']:.3f} m, "
            f"spread {fit['spread_m']:.3f} m, link-bias std "
            f"{fit['link_bias_std_m']:.3f} m, outliers {100 * fit['outlier_rate']:.1f} %, "
            f"correlation time {fit['correlation_time_s']:.2f} s, bias drift "
            f"{cal['bias_drift_m']:.3f} m → σ of one range in the filters "
            f"{cal['range_sigma_m']:.3f} m"
            + (
                f" (it replaces the mapping's stated {cal['mapping_sigma_replaced_m']:g} m). "
                if cal.get("mapping_sigma_replaced_m") is not None
                else ". "
            )
            + f"Scored on [{b['scored_window_s'][0]:.1f}, {b['scored_window_s'][1]:.1f}] s.",
            "",
        ]
        h = cal["heldout"]
        if h.get("rows"):
            lines += [
                f"Held-out range error ({h['rows']} readings): raw mean {h['raw']['mean_m']:.3f} m "
                f"/ RMSE {h['raw']['rmse_m']:.3f} m → calibrated mean "
                f"{h['calibrated']['mean_m']:.3f} m / RMSE {h['calibrated']['rmse_m']:.3f} m.",
                "",
            ]
        rows = []
        for case, t in b["team"].items():
            if "skipped" in t:
                rows.append([f"team {case}", "—", "—", "—", "—", "—", "—", t["skipped"]])
                continue
            bl = t["baselines"]
            rows.append(
                [
                    f"team {case} ({t['mode']})",
                    _f(t["pos_rmse_m"]),
                    _f(t.get("nees_pct_beyond")),
                    interval_text(t.get("nees_beyond_interval")),
                    _f(t.get("converged_after_s")),
                    _f(bl["uncalibrated"]["pos_rmse_m"]),
                    _f(bl["multilateration"]["pos_rmse_m"]),
                    ", ".join(t["anchors"]) or "—",
                ]
            )
        lines += [
            markdown_table(
                [
                    "case",
                    "pos RMSE (m)",
                    "NEES % > χ²₂(.95)",
                    "its 95 % interval",
                    "converged after (s)",
                    "uncalibrated RMSE (m)",
                    "multilateration RMSE (m)",
                    "anchors",
                ],
                rows,
                3,
            ),
            "",
        ]
        if b["pairs"]:
            prow = []
            for label, p in b["pairs"].items():
                prow.append(
                    [
                        label,
                        _f(p["pos_rmse_m"]),
                        _f(p["nees_pct_beyond"]),
                        interval_text(p.get("nees_beyond_interval")),
                        _f(p["converged_after_s"]),
                        _f(p["baselines"]["uncalibrated"]["pos_rmse_m"]),
                        _f(p["baselines"]["odometry_alone"]["pos_rmse_m"]),
                        p["observability"]["verdict"],
                    ]
                )
            lines += [
                markdown_table(
                    [
                        "pair (owner frame)",
                        "pos RMSE (m)",
                        "NEES % > χ²₄(.95)",
                        "its 95 % interval",
                        "converged after (s)",
                        "uncalibrated RMSE (m)",
                        "odometry alone RMSE (m)",
                        "observability",
                    ],
                    prow,
                    3,
                ),
                "",
                "Each pair filter starts from an unknown relative pose, with ranges and both "
                "odometries only; *odometry alone* starts at the true relative pose and "
                "integrates the two odometries, so it is the reference for how much the ranges "
                "must recover, not a competing estimate. *Converged after* is the time from "
                "which the error stays within "
                f"{CONVERGED_M:g} m and {CONVERGED_YAW:g} rad "
                "to the end of the stretch (— : never); a pair the observability column calls "
                "unobservable, or observable at few instants, cannot be expected to.",
                "",
            ]
        else:
            lines += ["No pair with odometry on both robots and one of them moving.", ""]
        skips = b["loader"]["skips"]
        lines += [
            f"Loader: header → bag time offset {b['loader']['stamp_offset_s']['bag']:.3f} s; "
            f"unknown topics: {len(b['loader']['unknown_topics'])}.",
            "",
            skipped_rows_line(
                skips["rows_skipped"],
                skips["by_reason"],
                bag_rows_source(b["loader"]["uwb_readings_not_in_recording"]),
            ),
            "",
        ]
    lines += [
        "RMSE over every record of the scored stretch (10 Hz), start transient included. NEES "
        "shares pool the records of one run, which are correlated in time, so their 95 % "
        "interval is by batch means: the stretch cut into 10 blocks, each a sample, widened "
        "when a block lasts less than ten correlation times of the NEES to hold "
        "Clopper–Pearson's interval for the effective sample size that time leaves "
        "(`relloc.metrics.consistency.percent_beyond_interval`); the verdict says whether it "
        "lies wholly above the 5 % of a consistent filter (over-confident), wholly below "
        "(conservative), holds 5 % and reaches no higher than 10 %, twice it, the share seed "
        "000 calls acceptable (consistent), or holds 5 % but reaches above 10 % "
        "(inconclusive: not rejected, not shown consistent either).",
    ]
    return "\n".join(lines) + "\n"
