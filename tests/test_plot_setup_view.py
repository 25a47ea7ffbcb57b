"""The HTML view of a planned set-up: its traces by name, the coverage map against
evaluate_setup, the robot where the coverage check put it, the page and the command."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("trimesh")
pytest.importorskip("coal")
pytest.importorskip("plotly")

from athenakin.design import Design  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.plot import robot_figure, setup_figure, target_coverage, write_setup_html  # noqa: E402
from athenakin.plot._setup_view import SETUP_HTML_DIV_ID  # noqa: E402
from athenakin.synthesis import (  # noqa: E402
    Patient,
    covered_samples,
    evaluate_setup,
    phantom,
    reference_decision,
    setup_from_decision,
)

D = Design.default()
#: Tolerance of positions drawn (mm) against those computed (m): rounding of the 1e3 scale.
MM_TOL = 1e-9


@pytest.fixture(scope="module")
def patient() -> Patient:
    return phantom(resolution=16)


@pytest.fixture(scope="module")
def setup(patient):
    # a hand-built set-up that covers part of the target, not all of it
    return setup_from_decision(patient, reference_decision(patient, D, yaw=np.radians(270),
                                                           roll=0.4))


@pytest.fixture(scope="module")
def fig(patient, setup):
    return setup_figure(patient, setup, D, targets=3)


def _by_name(fig, name):
    return next(t for t in fig.data if t.name == name)


def _faces(trace) -> np.ndarray:
    return np.stack([trace.i, trace.j, trace.k], axis=-1).reshape(-1, 3)


def test_the_figure_has_the_documented_traces(fig, patient):
    names = [t.name for t in fig.data]
    n = len(patient.target.faces)
    cov = next(t for t in names if t.startswith("target: covered"))
    k = int(re.match(r"target: covered \((\d+) of (\d+)\)", cov).group(1))
    for name in ("skin", "table", "forbidden: aorta", "forbidden: portal_vein", cov,
                 f"target: not covered ({n - k} of {n})", "instrument's nominal axis",
                 "port (RCM)"):
        assert names.count(name) == 1, name
    robot = [t.name for t in robot_figure(all_slots=False, show_frames=False).data]
    groups = sorted({t.legendgroup for t in fig.data if t.legendgroup})
    assert groups == ["target 1", "target 2", "target 3"]
    for g in groups:
        assert sorted(t.name for t in fig.data if t.legendgroup == g) == sorted(robot)
    assert fig.data[names.index("skin")].opacity < 0.5           # the skin lets one see in


def test_the_menu_shows_the_patient_and_one_robot(fig):
    menu = fig.layout.updatemenus[0]
    assert len(menu.buttons) == 3
    shown = np.array([b.args[0]["visible"] for b in menu.buttons])
    fixed = np.array([not t.legendgroup for t in fig.data])
    assert np.all(shown[:, fixed])                                # the patient always
    assert np.all(shown[:, ~fixed].sum(axis=0) == 1)              # each robot trace once
    for k, b in enumerate(menu.buttons):
        groups = {fig.data[i].legendgroup for i in np.flatnonzero(shown[k] & ~fixed)}
        assert groups == {f"target {k + 1}"} and b.label.startswith(f"target {k + 1}:")
    np.testing.assert_array_equal([t.visible is not False for t in fig.data], shown[0])


def test_the_coverage_colours_are_evaluate_setups_flags(fig, patient, setup):
    tm = patient.target
    centroids = tm.vertices[tm.faces].mean(axis=1)
    covered, _, _ = covered_samples(patient, setup, D, points=centroids)
    share = evaluate_setup(patient, setup, D, points=centroids)["coverage"]
    assert 0 < covered.sum() < covered.size                       # both colours drawn
    assert covered.sum() / covered.size == share
    yes = next(t for t in fig.data if t.name.startswith("target: covered"))
    no = next(t for t in fig.data if t.name.startswith("target: not covered"))
    np.testing.assert_array_equal(_faces(yes), tm.faces[covered])
    np.testing.assert_array_equal(_faces(no), tm.faces[~covered])
    assert yes.color != no.color
    for t in (yes, no):
        np.testing.assert_allclose(np.stack([t.x, t.y, t.z], -1), 1e3 * tm.vertices,
                                   rtol=0, atol=MM_TOL)
    points, flags, _, _ = target_coverage(patient, setup, D)
    np.testing.assert_array_equal(points, centroids)
    np.testing.assert_array_equal(flags, covered)


def test_each_robot_reaches_its_covered_target_through_the_port(fig, patient, setup):
    points, covered, _, _ = target_coverage(patient, setup, D)
    drawn = []
    for g in ("target 1", "target 2", "target 3"):
        pts = next(t for t in fig.data if t.legendgroup == g and t.name == "points (hover: mm)")
        xyz = np.stack([pts.x, pts.y, pts.z], -1) * 1e-3
        tip, rcm = xyz[list(pts.text).index("tip")], xyz[list(pts.text).index("RCM")]
        np.testing.assert_allclose(rcm, setup.port, rtol=0, atol=1e-9)
        d = np.linalg.norm(points - tip, axis=-1)
        i = int(np.argmin(d))
        assert d[i] < 1e-9 and covered[i]          # the tip on a covered face's centroid
        drawn.append(i)
    assert len(set(drawn)) == 3
    ax = _by_name(fig, "instrument's nominal axis")
    end = np.array([ax.x[-1], ax.y[-1], ax.z[-1]]) * 1e-3
    np.testing.assert_allclose(end, patient.target_centroid, rtol=0, atol=1e-12)


def test_a_point_cloud_target_is_drawn_as_coloured_points(patient, setup):
    pts = patient.target_samples(60, seed=3)
    cloud = Patient(skin=patient.skin, target_points=pts, forbidden=patient.forbidden,
                    table=patient.table, name="cloud")
    f = setup_figure(cloud, setup, D, targets=1)
    covered, _, _ = covered_samples(cloud, setup, D, points=pts)
    yes = next(t for t in f.data if t.name.startswith("target: covered"))
    np.testing.assert_allclose(np.stack([yes.x, yes.y, yes.z], -1), 1e3 * pts[covered],
                               rtol=0, atol=MM_TOL)
    assert yes.type == "scatter3d" and "60 points" in f.layout.title.text
    assert len(f.layout.updatemenus) == 0                          # one robot: no menu


def test_the_page_is_written_and_self_contained(tmp_path, patient, setup):
    path = write_setup_html(tmp_path / "setup.html", patient, setup, D, targets=2)
    text = path.read_text()
    assert f'id="{SETUP_HTML_DIV_ID}"' in text
    assert re.search(r"<title>set-up for phantom: .* covered", text)
    assert not re.search(r"<script[^>]+src=\"https?:", text)      # plotly.js inline
    assert len(text) > 3_000_000
    small = write_setup_html(tmp_path / "cdn.html", patient, setup, D, targets=2,
                             include_plotlyjs="cdn").read_text()
    assert len(small) < len(text) - 3_000_000


def test_the_page_renders_offline_in_headless_chromium(tmp_path, patient, setup):
    playwright = pytest.importorskip("playwright.sync_api")
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    if not Path(chromium).exists():
        pytest.skip("needs Debian's chromium (scripts/test.sh installs it)")
    page_path = write_setup_html(tmp_path / "setup.html", patient, setup, D, targets=2)
    errors, requests = [], []
    with playwright.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=[
            "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
            "--disable-background-networking"])
        try:
            page = browser.new_page(viewport={"width": 1000, "height": 800})
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.on("request", lambda r: requests.append(r.url))
            page.goto(page_path.as_uri())
            page.wait_for_function(
                f"() => {{ const d = document.getElementById('{SETUP_HTML_DIV_ID}'); "
                "return d && d._fullLayout && d.querySelector('canvas'); }", timeout=30000)
            page.locator(".updatemenu-header-group").first.click()
            page.locator(".updatemenu-dropdown-button").nth(1).click()
            page.wait_for_timeout(300)
            groups = page.evaluate(
                f"() => [...new Set(document.getElementById('{SETUP_HTML_DIV_ID}').data"
                ".filter(t => t.visible !== false && t.legendgroup).map(t => t.legendgroup))]")
        finally:
            browser.close()
    assert errors == []
    assert all(u.startswith("file://") for u in requests), requests
    assert groups == ["target 2"]


def test_bad_input_is_refused_by_name(tmp_path, patient, setup):
    with pytest.raises(TypeError, match="patient: expected Patient"):
        setup_figure("patient.toml", setup)
    with pytest.raises(TypeError, match="setup: expected Setup"):
        setup_figure(patient, setup.T_b_e)
    for bad in (0, 13):
        with pytest.raises(InvalidInputError, match="targets"):
            setup_figure(patient, setup, targets=bad)
    with pytest.raises(TypeError, match="show_frames"):
        setup_figure(patient, setup, show_frames="yes")
    with pytest.raises(InvalidInputError, match="include_plotlyjs"):
        write_setup_html(tmp_path / "a.html", patient, setup, include_plotlyjs="inline")
    with pytest.raises(InvalidInputError, match="is a folder"):
        write_setup_html(tmp_path, patient, setup)
    assert not (tmp_path / "a.html").exists()


def test_the_setup_view_command(tmp_path, patient, setup, capsys):
    from athenakin.cli import main
    from athenakin.synthesis import write_patient

    p = write_patient(patient, tmp_path / "p")
    s = setup.write(tmp_path / "setup.toml", design=D)
    out = tmp_path / "view.html"
    args = ["setup", "view", str(p), str(s), "-o", str(out), "--targets", "2", "--cdn"]
    assert main(args) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    text = out.read_text()
    assert text.count('"legendgroup":"target 2"') > 0 and "target 3" not in text
    assert main(args) == 1 and "exists" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0
    capsys.readouterr()
    assert main(["setup", "view", str(p), str(s), "-o", str(tmp_path / "v.png")]) == 1
    assert ".html" in capsys.readouterr().err
    assert main(["setup", "view", str(p), str(p), "-o", str(tmp_path / "w.html")]) == 1
    assert "T_b_e" in capsys.readouterr().err and not (tmp_path / "w.html").exists()
