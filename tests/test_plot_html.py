"""Interactive HTML: the plotly figure, and the page rendered by headless Chromium."""

import re
import shutil
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from matplotlib.colors import to_rgb
from playwright.sync_api import sync_playwright

import athenakin as ak
from athenakin.plot import COLORS, robot_figure, robot_geometry, write_html
from athenakin.plot._html import HTML_DIV_ID, label_boxes, screen_points

SEED = 1313

#: Debian's chromium (scripts/test.sh installs it); Playwright never downloads a browser here.
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync"]
COLOR_TOL = 45


def color_fraction(img, color):
    target = 255 * np.array(to_rgb(color))
    return float(np.mean(np.linalg.norm(img[..., :3].astype(float) - target, axis=-1)
                         < COLOR_TOL))


def test_figure_has_every_solution_behind_a_menu():
    fig = robot_figure()
    menu = fig.layout.updatemenus[0]
    assert len(menu.buttons) == 16
    shown = np.array([b.args[0]["visible"] for b in menu.buttons])       # (16, n_traces)
    assert np.all(shown.sum(axis=0) == 1)              # each trace belongs to one solution
    for k, b in enumerate(menu.buttons):
        assert b.label.startswith(f"slot {k}:")
        idx = np.flatnonzero(shown[k])
        assert np.all(np.diff(idx) == 1) and len(idx) >= 13
        single = robot_figure(slot=k, all_slots=False)
        assert [fig.data[i].name for i in idx] == [t.name for t in single.data]
    np.testing.assert_array_equal([bool(t.visible) for t in fig.data], shown[0])
    names = {t.name for t in fig.data}
    for part in ("instrument", "circle k1", "actuator q3 (radius of k2)",
                 "spherical joint at the RCM (u3, u4, u5)", "base rail (x_b)"):
        assert part in names


def test_figure_traces_hold_the_geometry():
    g = robot_geometry(slot=3)
    fig = robot_figure(slot=3, all_slots=False)
    assert len(fig.layout.updatemenus) == 0
    ins = next(t for t in fig.data if t.name == "instrument")
    np.testing.assert_allclose(np.array([ins.x[:2], ins.y[:2], ins.z[:2]]).T,
                               1e3 * np.stack(g.segments()["instrument"]), atol=1e-12)
    pts = next(t for t in fig.data if t.name == "points (hover: mm)")
    i = list(pts.text).index("RCM")
    np.testing.assert_allclose([pts.x[i], pts.y[i], pts.z[i]], 1e3 * g.points["RCM"],
                               atol=1e-12)


def test_write_html_is_self_contained(tmp_path):
    text = write_html(tmp_path / "robot.html").read_text()
    assert f'id="{HTML_DIV_ID}"' in text
    assert "<script src=" not in text
    assert len(text) > 1_000_000                     # plotly.js is inline
    small = write_html(tmp_path / "cdn.html", include_plotlyjs="cdn").read_text()
    assert len(small) < len(text) - 3_000_000       # plotly.js from the CDN instead


def test_page_renders_in_headless_chromium(tmp_path):
    assert Path(CHROMIUM).exists(), (
        f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium); "
        "scripts/test.sh does it")
    page_path = write_html(tmp_path / "robot.html")
    errors, requests = [], []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1000, "height": 800})
            page.on("pageerror", lambda e: errors.append(f"pageerror: {e}"))
            page.on("console", lambda m: errors.append(f"console: {m.text}")
                    if m.type == "error" else None)
            page.on("request", lambda r: requests.append(r.url))
            page.goto(page_path.as_uri())
            page.wait_for_function(
                f"() => {{ const d = document.getElementById('{HTML_DIV_ID}'); "
                "return d && d._fullLayout && d.querySelector('canvas'); }", timeout=30000)
            page.wait_for_timeout(800)
            shot0 = tmp_path / "robot_slot0.png"
            page.screenshot(path=str(shot0))
            n_visible = page.evaluate(
                f"() => document.getElementById('{HTML_DIV_ID}').data"
                ".filter(t => t.visible === true).length")
            # choose slot 4 in the menu, as a user would
            page.locator(".updatemenu-header-group").first.click()
            page.locator(".updatemenu-dropdown-button").nth(4).click()
            page.wait_for_timeout(800)
            title = page.evaluate(
                f"() => document.getElementById('{HTML_DIV_ID}').layout.title.text")
            shot4 = tmp_path / "robot_slot4.png"
            page.screenshot(path=str(shot4))
        finally:
            browser.close()
    assert errors == []
    assert all(u.startswith("file://") for u in requests), requests   # nothing from the network
    assert n_visible == len(robot_figure(all_slots=False).data)
    assert "slot 4" in title
    img0, img4 = iio.imread(shot0), iio.imread(shot4)
    assert img0.std() > 15
    # the scene is not clipped: its bottom rows and left columns are page background
    scene = img0[:, : int(0.74 * img0.shape[1]), :3]
    assert np.all(scene[-6:] == 255) and np.all(scene[:, :4] == 255)
    for key in ("serial", "parallel", "actuator"):
        assert color_fraction(img0, COLORS[key]) > 2e-4, key
    assert np.mean(np.abs(img0.astype(float) - img4.astype(float))) > 0.5


# --- issue 12, item 13: title, hover read-outs, labels, legend, clipping, --all -------------
def test_page_has_a_title(tmp_path):
    text = write_html(tmp_path / "robot.html", slot=5, include_plotlyjs="cdn").read_text()
    m = re.search(r"<title>(.*?)</title>", text)
    assert m and "slot 5" in m.group(1) and "q = (-100, 100, 450) mm" in m.group(1)


@pytest.mark.parametrize("slot", [0, 9])
def test_hover_shows_names_and_coordinates_in_mm(slot):
    g = robot_geometry(slot=slot)
    fig = robot_figure(slot=slot, all_slots=False)
    for t in fig.data:
        if t.hovertemplate:                        # lines: name and x, y, z of the point
            assert t.name in t.hovertemplate
            for c in "xyz":
                assert f"%{{{c}:.1f}} mm" in t.hovertemplate
        else:
            assert t.hoverinfo == "text"
    pts = next(t for t in fig.data if t.name == "points (hover: mm)")
    for key, (x, y, z, hover) in zip(["A", "B", "M", "D", "C", "O_i", "O_s", "RCM", "tip"],
                                     zip(pts.x, pts.y, pts.z, pts.hovertext, strict=False),
                                     strict=False):
        nums = [float(v) for v in re.findall(r"= (-?\d+\.\d) mm", hover)]
        np.testing.assert_allclose(nums, 1e3 * g.points[key], atol=0.051)
        np.testing.assert_allclose([x, y, z], 1e3 * g.points[key], atol=1e-9)


def _label_boxes_of(fig, trace):
    lo = np.array([fig.layout.scene[a].range[0] for a in ("xaxis", "yaxis", "zaxis")]) / 1e3
    hi = np.array([fig.layout.scene[a].range[1] for a in ("xaxis", "yaxis", "zaxis")]) / 1e3
    pts = np.column_stack([trace.x, trace.y, trace.z]) / 1e3
    keep = [i for i, t in enumerate(trace.text) if t]
    pos = trace.textposition
    pos = [pos] * len(trace.text) if isinstance(pos, str) else list(pos)
    xy = screen_points(pts[keep], lo, hi)
    return label_boxes(xy, [trace.text[i] for i in keep], [pos[i] for i in keep]), xy


def test_point_labels_do_not_overlap_in_the_default_view():
    rng = np.random.default_rng(SEED)
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = rng.uniform(d.stroke_min, d.stroke_max, (40, 3))
    sol = ak.forward_kinematics(q, T, d, errors="flag")
    cases = [(ak.robot.REFERENCE_Q, 0), (ak.robot.REFERENCE_Q, 12)]
    cases += [(q[i], int(np.flatnonzero(sol.valid[i])[0]))
              for i in np.flatnonzero(sol.valid.any(axis=1))[:4]]
    for qi, slot in cases:
        fig = robot_figure(qi, T, d, slot=slot, all_slots=False)
        pts = next(t for t in fig.data if t.name == "points (hover: mm)")
        boxes, xy = _label_boxes_of(fig, pts)
        for i in range(len(boxes)):
            for j in range(i):
                w = min(boxes[i, 2], boxes[j, 2]) - max(boxes[i, 0], boxes[j, 0])
                h = min(boxes[i, 3], boxes[j, 3]) - max(boxes[i, 1], boxes[j, 1])
                assert w <= 0 or h <= 0, (qi, slot, pts.text, i, j)


def test_legend_names_parts_only():
    fig = robot_figure(all_slots=False)
    shown = [t for t in fig.data if t.showlegend is not False]
    assert all(t.mode in ("lines", "markers", "markers+text") for t in shown)
    names = [t.name for t in shown]
    assert len(names) == len(set(names))
    assert "O_b" not in names                     # the base frame is a labelled point


def test_all_solutions_at_once_one_legend_entry_per_slot():
    fig = robot_figure(all_solutions=True)
    entries = [t for t in fig.data if t.showlegend]
    assert [t.name for t in entries] == [
        f"slot {k}: " + t.name.split(": ", 1)[1] for k, t in enumerate(entries)]
    assert len(entries) == 16
    groups = {t.legendgroup for t in fig.data}
    assert groups == {f"slot {k}" for k in range(16)}
    assert all(t.visible is True for t in fig.data)
    menu = fig.layout.updatemenus[0]
    assert menu.buttons[0].label == "all 16 solutions" and len(menu.buttons) == 17
