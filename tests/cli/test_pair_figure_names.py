"""Per-pair figures are named by observer *and* observed: two observers of one robot get a
figure each, each linked once in ``report.md`` under its own caption."""

from __future__ import annotations

import re
from types import SimpleNamespace

from relloc.cli import main
from relloc.pipeline.team_report import pair_figure_stems

# alpha and bravo both observe drone; alpha also observes bravo
SCENARIO = """
name = "two-observers"
duration_s = 8.0
propagation_rate_hz = 50.0

[arena]
x = [0.0, 12.0]
y = [0.0, 12.0]
z = [-0.5, 4.0]

[[robots]]
name = "alpha"
kind = "ground"
height = 0.0
initial_pose = [2.0, 2.0, 0.7854]
observes = ["drone", "bravo"]
[robots.motion]
type = "velocity"
mean = [0.1, 0.0, 0.0, 0.0]
amplitude = [0.05, 0.0, 0.0, 0.1]
period_s = [20.0, 10.0, 10.0, 12.0]
phase_rad = [0.0, 0.0, 0.0, 0.0]
[robots.odometry]
sigma_v = 0.03
sigma_w = 0.03
[robots.sensor]
sigma_range = 0.05
sigma_azimuth = 0.01
sigma_elevation = 0.01
rate_hz = 5.0
fov_deg = 360.0
elevation_fov_deg = 180.0
min_range = 0.2
max_range = 20.0

[[robots]]
name = "bravo"
kind = "ground"
height = 0.0
observes = ["drone"]
[robots.motion]
type = "waypoints"
points = [[6.0, 3.0], [9.0, 6.0], [6.0, 9.0], [3.0, 6.0]]
speed = 0.3
closed = true
[robots.odometry]
sigma_v = 0.03
sigma_w = 0.03
[robots.sensor]
sigma_range = 0.1
sigma_azimuth = 0.02
sigma_elevation = 0.02
rate_hz = 10.0
fov_deg = 360.0
elevation_fov_deg = 180.0
min_range = 0.2
max_range = 20.0

[[robots]]
name = "drone"
kind = "aerial"
height = 3.0
[robots.motion]
type = "waypoints"
points = [[4.0, 4.0], [8.0, 4.0], [8.0, 8.0], [4.0, 8.0]]
speed = 0.5
closed = true
heading = "tangent"
[robots.odometry]
sigma_v = 0.05
sigma_vz = 0.02
sigma_w = 0.05
"""


def test_two_observers_of_one_robot_get_two_figures_each_linked_under_its_caption(
    tmp_path, capsys, monkeypatch
):
    import relloc.plotting.errors as plotting_errors

    drawn: list[list[str]] = []  # the curves of the pooled RMSE figure
    draw = plotting_errors.plot_robot_errors

    def spy(axes, series):  # type: ignore[no-untyped-def]
        drawn.append(list(series))
        draw(axes, series)

    monkeypatch.setattr(plotting_errors, "plot_robot_errors", spy)
    scenario = tmp_path / "two_observers.toml"
    scenario.write_text(SCENARIO)
    out = tmp_path / "out"
    argv = ["run", str(scenario), "--out", str(out), "--runs", "1", "--executor", "serial"]
    assert main(argv) == 0
    capsys.readouterr()
    pairs = {"alpha": ["bravo", "drone"], "bravo": ["drone"]}
    names = {f"error_bounds_{o}_{s}.png" for o, subs in pairs.items() for s in subs}
    assert names <= {p.name for p in out.glob("error_bounds_*.png")}
    assert len(list(out.glob("error_bounds_*.png"))) == 3
    report = (out / "report.md").read_text()
    links = re.findall(r"!\[([^\]]*)\]\((error_bounds_[^)]*)\)", report)
    assert sorted(name for _, name in links) == sorted(names)  # each linked once
    for caption, name in links:
        observer, observed = name.removeprefix("error_bounds_").removesuffix(".png").split("_")
        assert caption.startswith(f"Error of {observer}->{observed} ")
    assert [sorted(d) for d in drawn] == [["alpha->drone", "bravo", "bravo->drone"]]  # none hidden


def test_pair_figure_stems_are_unique_and_safe_as_file_names():
    def ev(owner: str, subject: str, track: str = "") -> SimpleNamespace:
        return SimpleNamespace(owner=owner, subject=subject, track=track)

    series = [
        ev("alpha", "drone"),
        ev("bravo", "drone"),
        ev("a_b", "c"),
        ev("a", "b_c"),  # the same stem as the one before: numbered
        ev("1", "2", "hyp/0"),
    ]
    stems = pair_figure_stems(series)  # type: ignore[arg-type]
    assert stems == ["alpha_drone", "bravo_drone", "a_b_c", "a_b_c_2", "1_2__hyp_0"]


def test_pooled_figures_name_each_series_so_none_hides_another():
    from relloc.pipeline.team_report import _legend_names

    def ev(owner: str, subject: str) -> SimpleNamespace:
        return SimpleNamespace(owner=owner, subject=subject, label=f"{owner}->{subject}")

    series = [ev("alpha", "drone"), ev("alpha", "bravo"), ev("bravo", "drone")]
    names = _legend_names(series)  # type: ignore[arg-type]
    # a robot one series observes keeps its name; two observers of drone each get the pair
    assert names == ["alpha->drone", "bravo", "bravo->drone"]
