"""Pictures that tell the truth (issue 27): with a task, sections go through the task and the task path is drawn at
its own height; the robot is drawn at a reachable task pose (or a reachable pose, said so); legends sit outside
the axes; report.html has a unit on every axis and a hypervolume normalised to [0, 1].

The task: seed 000's Table-4 group-1 design (SMALL) with a task box x, y in [-0.2, 0.2] m, z in [0.3, 0.5] m and a
path at z = 0.4 m whose y runs from 0 to 0.1 m. The workspace centroid lies at z = 0.2 m (the base height; the
workspace is symmetric about it), so centroid sections miss the path's height.
"""

import base64
import copy
import json
import re

import numpy as np
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from scalesynth import workspace_view as wv
from scalesynth.cli import app
from scalesynth.config import config_from_dict
from scalesynth.optimize import run

from conftest import SMALL

runner = CliRunner()
BOX = {"x": [-0.2, 0.2], "y": [-0.2, 0.2], "z": [0.3, 0.5]}
PATH = [[-0.1, 0.0, 0.4], [0.1, 0.0, 0.4], [0.1, 0.1, 0.4]]
PATH_Z = 0.4  # every point of PATH
BOX_CENTRE_Y = 0.0  # PATH's y is not level (0 to 0.1): the xz section goes through the box centre


def task_dict(**extra):
    d = copy.deepcopy(SMALL)
    d["task"] = {"box": copy.deepcopy(BOX), "path": copy.deepcopy(PATH), **extra}
    return d


@pytest.fixture(scope="module")
def task_cfg():
    return config_from_dict(task_dict())


@pytest.fixture(scope="module")
def task_yaml(tmp_path_factory):
    path = tmp_path_factory.mktemp("pictures") / "task.yaml"
    path.write_text(yaml.safe_dump(task_dict()))
    return path


# ----- sections through the task -------------------------------------------------------------------------------------
def test_report_sections_go_through_the_task_path_height(task_cfg):
    design = task_cfg.resolved_design()
    centroid = wv.centroid(wv.sample_fields(task_cfg, design, 24))
    assert abs(centroid[2] - PATH_Z) > 0.1  # the case of the issue: the centroid plane is not the path's
    xz, xy = wv.section_panels(task_cfg, design)
    assert float(xy["title"].split(" = ")[1].split(" ")[0]) == PATH_Z  # the xy section's title states its height
    assert (xz["normal"], xy["normal"]) == (1, 2)
    assert xy["position"] == PATH_Z and xy["source"] == "task path"
    assert xz["position"] == BOX_CENTRE_Y and xz["source"] == "task box centre"
    # the path is drawn in its true coordinates, and its legend says where it lies along each plane's normal
    np.testing.assert_array_equal(xy["path"], np.array(PATH)[:, [0, 1]])
    np.testing.assert_array_equal(xz["path"], np.array(PATH)[:, [0, 2]])
    assert xy["path_label"] == "task path at z = 0.4 m"
    assert xz["path_label"] == "task path, y 0 to 0.1 m (projected)"
    assert xy["box"] == (-0.2, 0.2, -0.2, 0.2) and xz["box"] == (-0.2, 0.2, 0.3, 0.5)
    # the drawn cells are the kernel's at z = 0.4, each point evaluated on its own
    x0, x1, y0, y1 = xy["extent"]
    nx, ny = xy["values"].shape
    for i, j in ((nx // 2, ny // 2), (nx // 3, ny // 2), (nx // 2, 2 * ny // 3), (0, 0)):
        x, y = x0 + (i + 0.5) * (x1 - x0) / nx, y0 + (j + 0.5) * (y1 - y0) / ny
        assert (xy["values"][i, j] >= 0) == wv.reachable_points(task_cfg, design, np.array([[x, y, PATH_Z]]))[0]


def test_show_sections_and_robot_go_to_the_task(task_yaml, task_cfg, tmp_path):
    res = runner.invoke(app, ["show", str(task_yaml), "--resolution", "12", "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    by_normal = {s["normal"]: s for s in info["sections"]}
    assert by_normal["z"]["value"] == PATH_Z and by_normal["z"]["source"] == "task path"
    assert by_normal["z"]["path"] == "task path at z = 0.4 m"
    assert by_normal["y"]["value"] == BOX_CENTRE_Y and by_normal["y"]["source"] == "task box centre"
    assert by_normal["x"]["value"] == 0.0 and by_normal["x"]["source"] == "task box centre"  # PATH's x: -0.1..0.1
    robot = info["robot"]
    pose = np.array(robot["pose"])
    lo, hi = np.array([BOX[a] for a in "xyz"]).T
    assert np.all(lo <= pose) and np.all(pose <= hi), pose  # a point of the task
    assert robot["pose_source"].startswith("task")
    assert wv.reachable_points(task_cfg, task_cfg.resolved_design(), pose[None])[0]
    assert task_cfg.mech.inverse_kinematics(task_cfg.resolved_design(), task_cfg.resolved_options(), pose)
    assert "segments" in robot
    # the platform's centre is the pose: the drawn robot stands where the caption says
    platform = next(s for s in robot["segments"] if s["name"] == "platform")
    np.testing.assert_allclose(0.5 * (np.array(platform["a"]) + np.array(platform["b"])), pose, atol=1e-9)
    caption = wv.robot_caption(task_cfg, robot)
    assert robot["pose_source"] in caption and caption.startswith("robot at x=")


def test_show_section_through_a_task_that_misses_the_workspace(tmp_path):
    """A task far above the workspace: its section is drawn where the task is (empty, and said so), and the robot
    is drawn at a reachable pose (the node nearest the task box centre), never at the unreachable task."""
    d = task_dict()
    d["task"] = {"box": {"x": [-0.1, 0.1], "y": [-0.1, 0.1], "z": [9.0, 9.5]}}
    cfg = config_from_dict(d)
    path = tmp_path / "far.yaml"
    path.write_text(yaml.safe_dump(d))
    res = runner.invoke(app, ["show", str(path), "--resolution", "12", "--out", str(tmp_path / "o"), "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    z = next(s for s in info["sections"] if s["normal"] == "z")
    assert z["value"] == 9.25 and z["cells"] == 0 and z["source"] == "task box centre"
    robot = info["robot"]
    assert robot["pose_source"].startswith("no point of the task is reachable")
    assert wv.reachable_points(cfg, cfg.resolved_design(), np.array(robot["pose"])[None])[0]
    assert "segments" in robot


def test_robot_without_a_task_is_at_a_reachable_pose_and_says_so(tmp_path):
    cfg = config_from_dict(copy.deepcopy(SMALL))
    fg = wv.sample_fields(cfg, cfg.resolved_design(), 12)
    pose, source = wv.robot_pose(cfg, cfg.resolved_design(), fg)
    assert source == "the reachable grid node nearest the workspace centroid"
    assert wv.reachable_points(cfg, cfg.resolved_design(), pose[None])[0]
    empty = config_from_dict({**copy.deepcopy(SMALL), "grid": {"resolution": 12, "region": {"z": [50.0, 60.0]}}})
    fg = wv.sample_fields(empty, empty.resolved_design(), 6)
    assert not fg.reachable.any()
    assert wv.robot_pose(empty, empty.resolved_design(), fg)[0] is None  # no pose, rather than an unreachable one


# ----- legends outside what is drawn ----------------------------------------------------------------------------------
def _legend_clear_of_axes(fig, ax):
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend() or fig.legends[0]
    box, area = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
    assert not box.overlaps(area), (box, area)
    assert fig.bbox.contains(box.x0, box.y0) and fig.bbox.contains(box.x1, box.y1)  # not cut off


def test_legends_do_not_cover_the_sections_or_the_robot(task_cfg):
    from scalesynth import plotting

    panels = wv.section_panels(task_cfg, task_cfg.resolved_design())
    fig = plotting.sections_figure(panels, task_cfg.dexterity.band_edges, "t")
    for ax in fig.axes[:len(panels)]:  # the sections (the colour bars follow)
        _legend_clear_of_axes(fig, ax)
        assert not ax.get_legend().get_window_extent().overlaps(ax.title.get_window_extent())
    plotting.close(fig)
    design = task_cfg.resolved_design()
    robot = wv.robot(task_cfg, design, [0.0, 0.0, PATH_Z])
    for planar in (False, True):
        fig = plotting.robot_figure(robot["segments"], "m", "t", planar, np.array(PATH), "task path")
        _legend_clear_of_axes(fig, fig.axes[0])
        plotting.close(fig)


# ----- report.html: units on every axis, a normalised hypervolume -----------------------------------------------------
@pytest.fixture(scope="module")
def task_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("pictures") / "run"
    run(config_from_dict(task_dict()), out, plots=True)
    return out


def plotly_figures(html: str) -> list[tuple[list, dict]]:
    """(data, layout) of every Plotly.newPlot call of a page, parsed as JSON."""
    decoder = json.JSONDecoder()
    figures = []
    for m in re.finditer(r"Plotly\.newPlot\(\s*", html):
        pos = m.end()
        args = []
        for _ in range(3):  # div id, data, layout
            value, pos = decoder.raw_decode(html, pos)
            args.append(value)
            pos = re.compile(r"\s*,\s*").match(html, pos).end()
        figures.append((args[1], args[2]))
    return figures


def numbers(value) -> np.ndarray:
    """A plotly JSON array: a list, or plotly's typed-array encoding {"dtype", "bdata": base64}."""
    if isinstance(value, dict):
        return np.frombuffer(base64.b64decode(value["bdata"]), dtype=value["dtype"]).astype(float)
    return np.array(value, dtype=float)


def axis_titles(data: list, layout: dict) -> list[str]:
    """Every axis title of a figure: x/y axes, 3-D scene axes, parallel-coordinate axes and colour bars."""
    def text(title):
        return title.get("text") if isinstance(title, dict) else title

    titles = []
    for key, axis in layout.items():
        if re.fullmatch(r"[xy]axis\d*", key):
            titles.append(text(axis.get("title")))
        if re.fullmatch(r"scene\d*", key):
            titles += [text(axis[k].get("title")) for k in ("xaxis", "yaxis", "zaxis")]
    for trace in data:
        titles += [d["label"] for d in trace.get("dimensions", [])]
        for holder in (trace, trace.get("marker", {}), trace.get("line", {})):
            if holder.get("showscale", trace.get("type") == "heatmap") and "colorbar" in holder:
                titles.append(text(holder["colorbar"].get("title")))
    return titles


def test_every_axis_of_report_html_has_a_unit(task_run):
    figures = plotly_figures((task_run / "report.html").read_text(encoding="utf-8"))
    assert len(figures) >= 4  # front, parallel coordinates, hypervolume, featured workspaces
    titles = [t for data, layout in figures for t in axis_titles(data, layout)]
    assert len(titles) >= 20
    missing = [t for t in titles if not (isinstance(t, str) and re.search(r"\[[^\]]+\]$", t))]
    assert missing == []
    assert {"m [m]", "n [m]", "l1 [m]", "l2 [m]", "c [m]", "V [m³]", "GCI [-]"} <= set(titles)


def test_report_hypervolume_is_normalised_by_the_reference_box(task_run):
    figures = plotly_figures((task_run / "report.html").read_text(encoding="utf-8"))
    (data, layout), = [f for f in figures if f[1].get("title", {}).get("text") == "hypervolume per generation"]
    y = numbers(data[0]["y"])
    assert layout["yaxis"]["title"]["text"] == "hypervolume / reference-box volume [-]"
    history = pd.read_csv(task_run / "history.csv")
    manifest = json.loads((task_run / "manifest.json").read_text())
    # SMALL maximises volume and GCI: reference point (0, 0); the box reaches the best volume and GCI of the run
    assert manifest["hv_reference"] == [0.0, 0.0]
    box = history["best_volume_m3"].max() * history["best_gci"].max()
    raw = history["hypervolume"].to_numpy()
    assert raw[-1] > 1.0  # in m³: the raw number is no share
    assert np.all(raw / box <= 1.0 + 1e-12)  # the box holds every counted point (nothing clipped but rounding)
    np.testing.assert_allclose(y, raw / box, rtol=1e-10)  # history.csv keeps 12 significant digits
    assert np.all((0.0 <= y) & (y <= 1.0)) and y[-1] > 0.5
    report = (task_run / "report.md").read_text()
    assert f"({y[-1]:.4g} of the reference box)" in report
