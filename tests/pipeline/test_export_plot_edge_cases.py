"""Degenerate but valid estimates through the ROS export (MCAP / TUM) and the figures: one
record, none, non-finite or singular beliefs, gaps, out-of-range stamps, odd robot and track
names (never a file outside the TUM folder, never a merged topic or overwritten file),
all-NaN and empty data in figures."""

from __future__ import annotations

import dataclasses
import io
import warnings
from pathlib import Path

import numpy as np
import pytest
from export_helpers import T, _series, recording

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError, DataError
from relloc.pipeline.export import ExportRequest, export_estimates

pytest.importorskip("mcap", reason="extra 'ros' (mcap) is not installed")
pytest.importorskip("rosbags", reason="extra 'ros' (rosbags) is not installed")


def _rel(rec: Recording, track: str = "", owner: str = "leader", subject: str = "3"):  # type: ignore[no-untyped-def]
    return _series(rec, np.random.default_rng(1), owner, subject, "relative_pose4", track=track)


def _rows(s: BeliefSeries, idx: np.ndarray) -> BeliefSeries:
    return dataclasses.replace(s, t=s.t[idx], mean=s.mean[idx], cov=s.cov[idx], age=s.age[idx])


def _export(tmp_path: Path, beliefs: list[BeliefSeries], rec: Recording | None = None):  # type: ignore[no-untyped-def]
    request = ExportRequest(mcap=tmp_path / "out.mcap", tum=tmp_path / "tum")
    est = Estimates(estimator="hand", beliefs=tuple(beliefs))
    return export_estimates(request, est, rec or recording(), run="edge")


def _mcap_topics(path: Path) -> dict[str, int]:
    from mcap.reader import make_reader

    counts: dict[str, int] = {}
    with path.open("rb") as f:
        for _, channel, _ in make_reader(f).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


def _files(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


# --- export ------------------------------------------------------------------------------------


def test_single_record_is_written_and_scored(tmp_path: Path) -> None:
    out = _export(tmp_path, [_rows(_rel(recording()), np.arange(1))])
    assert out["series"]["leader->3"]["records"] == 1
    assert np.isfinite(out["series"]["leader->3"]["position_rmse_m"])
    assert _mcap_topics(tmp_path / "out.mcap")["/leader/estimates/r3"] == 1
    lines = (tmp_path / "tum/leader/r3.tum").read_text().splitlines()
    assert len(lines) == 2  # header + one pose


def test_no_track_ever_created_writes_an_empty_but_valid_mcap(tmp_path: Path) -> None:
    out = _export(tmp_path, [])
    assert out["series"] == {} and out["mcap"]["messages"] == 0
    assert out["tum"]["pairs"] == {}
    assert (tmp_path / "tum").is_dir() and not any((tmp_path / "tum").iterdir())  # as named
    assert _mcap_topics(tmp_path / "out.mcap") == {}


def test_all_nan_belief_is_skipped_and_counted(tmp_path: Path) -> None:
    s = _rel(recording())
    out = _export(tmp_path, [dataclasses.replace(s, mean=np.full_like(s.mean, np.nan))])
    assert out["skipped"] == {"non-finite belief": T.size}
    assert out["series"]["leader->3"]["records"] == 0
    assert "/leader/estimates/r3" not in _mcap_topics(tmp_path / "out.mcap")


@pytest.mark.parametrize(
    "scale",
    [0.0, 1e300],
    ids=["zero covariance", "huge rank-one covariance"],
)
def test_singular_covariance_is_exported_and_scored(tmp_path: Path, scale: float) -> None:
    """Was a ModelError (NEES of a non-invertible covariance) from the summary, nothing
    written; the export reports positions only, so the covariance must not matter."""
    s = _rel(recording())
    cov = np.full_like(s.cov, scale)
    out = _export(tmp_path, [dataclasses.replace(s, cov=cov)])
    reference = _export(tmp_path / "ref", [s])
    got, want = out["series"]["leader->3"], reference["series"]["leader->3"]
    assert got["position_rmse_m"] == pytest.approx(want["position_rmse_m"], rel=1e-12)
    assert got["steady_position_rmse_m"] == pytest.approx(want["steady_position_rmse_m"])
    assert _mcap_topics(tmp_path / "out.mcap")["/leader/estimates/r3"] == T.size


def test_track_gap_keeps_every_record(tmp_path: Path) -> None:
    idx = np.r_[0:5, 12 : T.size]
    out = _export(tmp_path, [_rows(_rel(recording()), idx)])
    assert out["series"]["leader->3"]["records"] == idx.size
    assert _mcap_topics(tmp_path / "out.mcap")["/leader/estimates/r3"] == idx.size


@pytest.mark.parametrize("yaw", [float("nan"), "0.3"])
def test_a_common_frame_yaw_that_is_not_a_number_fails_cleanly(tmp_path: Path, yaw) -> None:  # type: ignore[no-untyped-def]
    """Before: ``float`` read the string "0.3" as a number, and a NaN wrote NaN quaternions on
    /tf."""
    rec = recording()
    rec = dataclasses.replace(rec, meta={**rec.meta, "common_frame_yaw": yaw})
    with pytest.raises(DataError, match=r"recording\.meta: common_frame_yaw"):
        _export(tmp_path, [_rel(rec)], rec)


@pytest.mark.parametrize("offset", [-10.0, 2.0**32, 2.0**31 - 3.0])
def test_stamps_outside_ros_time_fail_cleanly_and_write_nothing(
    tmp_path: Path, offset: float
) -> None:
    s = dataclasses.replace(_rel(recording()), t=T + offset)
    with pytest.raises(DataError, match=r"cannot be a ROS stamp"):
        _export(tmp_path, [s])
    assert _files(tmp_path) == []


def test_robot_names_never_leave_the_tum_folder_and_make_valid_topics(tmp_path: Path) -> None:
    """A recording accepts any robot name; names become ROS tokens (``..`` → ``__``)."""
    base = recording()
    rec = dataclasses.replace(base, robots=("a/b", "..", "../x"))
    s1 = _rel(rec, owner="a/b", subject="../x")
    s2 = _rel(rec, owner="..", subject="a/b", track="../../evil")
    out = _export(tmp_path / "out", [s1, s2], rec)
    root = (tmp_path / "out").resolve()
    for pair in out["tum"]["pairs"].values():
        assert Path(pair["estimate"]).resolve().is_relative_to(root / "tum")
    assert _files(tmp_path) == sorted(
        f"out/{f}"
        for f in (
            "out.mcap",
            "tum/__/a_b________evil.tum",
            "tum/__/a_b________evil.truth.tum",
            "tum/a_b/___x.tum",
            "tum/a_b/___x.truth.tum",
        )
    )
    for topic in _mcap_topics(tmp_path / "out/out.mcap"):
        assert topic.startswith("/") and not topic.endswith("/") and "//" not in topic
        assert all(part and not part[0].isdigit() for part in topic[1:].split("/"))
        assert set(topic) <= set("/_abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789")


def test_robot_names_that_become_one_token_are_refused(tmp_path: Path) -> None:
    rec = dataclasses.replace(recording(), robots=(" ", "é", "x"))
    with pytest.raises(ConfigError, match="both become '_'"):
        _export(tmp_path, [_rel(rec, owner=" ", subject="x")], rec)


def test_track_named_only_slashes_gets_no_trailing_slash(tmp_path: Path) -> None:
    """Was the topic ``/leader/estimates/r3/`` (invalid: a ROS name never ends in ``/``)."""
    out = _export(tmp_path, [_rel(recording(), track="/")])
    assert out["series"]["leader->3#/"]["topic"] == "/leader/estimates/r3"
    assert "/leader/estimates/r3" in _mcap_topics(tmp_path / "out.mcap")


@pytest.mark.parametrize(
    ("a", "b", "what"),
    [("a b", "a_b", "topic"), ("a/b", "a//b", "topic"), ("a/b", "a_b", "TUM file")],
)
def test_tracks_sharing_a_topic_or_file_are_refused_before_writing(
    tmp_path: Path, a: str, b: str, what: str
) -> None:
    """Were merged into one MCAP channel (topic) or one TUM file silently overwriting the
    other (``a/b`` and ``a_b`` have distinct topics but one file name)."""
    rec = recording()
    with pytest.raises(ConfigError, match=f"both become the {what}"):
        _export(tmp_path, [_rel(rec, track=a), _rel(rec, track=b)], rec)
    assert _files(tmp_path) == []


# --- figures -----------------------------------------------------------------------------------


def _draw(draw, n_axes: int = 1) -> list[str]:  # type: ignore[no-untyped-def]
    """Draw into fresh axes and render to PNG; the warnings raised."""
    from relloc.plotting.setup import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(n_axes, 1, squeeze=False)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            draw(list(axes[:, 0]))
            fig.savefig(io.BytesIO(), format="png")
        return [str(w.message) for w in caught]
    finally:
        plt.close(fig)


EMPTY = np.zeros(0)
NAN = np.full(5, np.nan)
T5 = np.arange(5.0)


@pytest.mark.parametrize(("t", "v"), [(EMPTY, EMPTY), (T5, NAN)], ids=["empty", "all-NaN"])
def test_team_report_figures_draw_empty_and_nan_data_silently(t, v) -> None:  # type: ignore[no-untyped-def]
    from relloc.plotting.consistency import plot_chi2_series, plot_conditioning
    from relloc.plotting.errors import plot_pose_errors_with_bounds, plot_robot_errors
    from relloc.plotting.team import plot_convergence, plot_team_paths, steady_limits

    four = np.tile(v[:, None], 4)
    assert _draw(lambda ax: plot_pose_errors_with_bounds(ax, t, four, four), 4) == []
    assert _draw(lambda ax: plot_robot_errors(ax, {"x": (t, four)}), 4) == []
    assert _draw(lambda ax: plot_chi2_series(ax[0], t, v, 4)) == []
    assert _draw(lambda ax: plot_chi2_series(ax[0], t, v, 4, n_runs=5, normalise=True)) == []
    assert _draw(lambda ax: plot_conditioning(ax[0], {"P": (t, v)})) == []
    assert _draw(lambda ax: steady_limits(ax[0], t, v, 0.0)) == []
    assert _draw(lambda ax: plot_convergence(ax[0], {"p": [None, None], "q": []})) == []
    paths = {"r": np.zeros((5, 4))}
    estimates = {"p": (t, np.tile(v[:, None], 3), "r")}
    assert _draw(lambda ax: plot_team_paths(ax[0], ax[0], T5, paths, estimates)) == []


def test_empty_true_path_draws_without_start_marker() -> None:
    """Was an IndexError (the start marker at ``p[0]``) in both path figures."""
    from relloc.plotting.errors import plot_trajectories
    from relloc.plotting.team import plot_team_paths

    empty = {"r": np.zeros((0, 4))}
    assert _draw(lambda ax: plot_trajectories(ax[0], empty)) == []
    views = {"r": (90.0, 2.0)}
    assert _draw(lambda ax: plot_team_paths(ax[0], ax[0], EMPTY, empty, {}, views=views)) == []


@pytest.mark.parametrize(
    ("values", "reference"),
    [([None, None], None), ([None, None], 0.0), ([0.0, None], None)],
)
def test_grouped_bars_without_a_positive_value_stay_linear(values, reference) -> None:  # type: ignore[no-untyped-def]
    """Was ``ValueError: Data cannot be log-scaled`` while saving (all bars missing)."""
    from relloc.plotting.cooperative import plot_grouped_bars

    scales: list[str] = []

    def draw(ax):  # type: ignore[no-untyped-def]
        plot_grouped_bars(ax[0], ["a", "b"], {"s": values}, ylabel="m", reference=reference)
        scales.append(ax[0].get_yscale())

    assert _draw(draw) == []
    assert scales == ["linear"]


def test_grouped_bars_with_a_positive_value_keep_the_log_axis() -> None:
    from relloc.plotting.cooperative import plot_grouped_bars

    scales: list[str] = []

    def draw(ax):  # type: ignore[no-untyped-def]
        plot_grouped_bars(ax[0], ["a", "b"], {"s": [0.2, None]}, ylabel="m")
        scales.append(ax[0].get_yscale())

    _draw(draw)
    assert scales == ["log"]
