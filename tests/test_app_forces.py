"""The actuator forces in the live app (issue 21 item 6): athenakin.app._forces.

The layer's numbers against ``ak.dynamics.actuator_forces`` / ``statics`` of the drawn
slot, the tip-force part against a central finite difference of the drawn tool tip, the
handle's drag against the force it sets, the read-out's limits, bad options as named
errors, and (slow) the read-out in headless Chromium.
"""

import asyncio
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import athenakin as ak
from athenakin.app import app_setup, forward_view
from athenakin.app._forces import (
    FORCE_SCALE_M_PER_N,
    MAX_TIP_FORCE_N,
    check_f_max,
    check_masses,
    check_tip_force,
    forces_html,
    forces_view,
    handle_from_tip_force,
    tip_force_from_handle,
)
from athenakin.errors import InvalidInputError
from athenakin.plot import robot_geometry

ATOL_SAME_N = 1e-12     # the same computation: equal to rounding
ATOL_SPLIT_N = 1e-9     # forces + J^T f against a second call without the tip force
ATOL_FD_N = 1e-5        # against a central finite difference of the tip (h = 1e-6 m)
FD_STEP_M = 1e-6
Q_SAMPLES = ([-0.10, 0.10, 0.45], [-0.12, 0.07, 0.47], [-0.08, 0.13, 0.43])


@pytest.fixture(scope="module")
def setup():
    return app_setup(backend="numpy")


def _handle_event(layer, phase):
    """One event of a force-handle drag as viser delivers it (on an event loop), its move
    done."""
    asyncio.run(layer._on_handle(SimpleNamespace(phase=phase)))
    layer._moves.drain()


def _geometry(setup, q, slot):
    v = forward_view(setup, q, slot=slot)
    assert v.geometry is not None
    return v.geometry


def _masses_file(tmp_path, masses=None):
    m = masses if masses is not None else ak.dynamics.MassModel.slender_rods(
        {"link_a": 0.5, "link_b": 0.4, "carrier": 0.7, "instrument": 0.35})
    p = tmp_path / "masses.toml"
    p.write_text(m.to_toml())
    return p, m


@pytest.mark.parametrize("q", Q_SAMPLES)
@pytest.mark.parametrize("slot", [0, 5, 10, 15, "all"])
def test_forces_equal_actuator_forces_of_the_drawn_slot(setup, q, slot):
    g = _geometry(setup, q, slot)
    rng = np.random.default_rng(21 + g.slot)
    f_tip = rng.uniform(-20.0, 20.0, 3)
    for tip in (None, f_tip):
        fv = forces_view(g, tip_force=tip)
        want = ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, slot=g.slot, tip_force=tip)
        np.testing.assert_allclose(fv.forces, want, rtol=0, atol=ATOL_SAME_N)
        st = ak.dynamics.statics(g.q, g.T_b_e, g.design, slot=g.slot, tip_force=tip)
        np.testing.assert_allclose(fv.rcm_force, st.rcm_force, rtol=0, atol=ATOL_SAME_N)
        np.testing.assert_allclose(fv.rcm_moment, st.rcm_moment, rtol=0, atol=ATOL_SAME_N)
        gravity = ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, slot=g.slot)
        np.testing.assert_allclose(fv.gravity_forces, gravity, rtol=0, atol=ATOL_SPLIT_N)
        assert fv.slot == g.slot and not fv.exceeded and fv.f_max is None


def test_forces_with_a_masses_file_equal_actuator_forces(setup, tmp_path):
    path, m = _masses_file(tmp_path)
    g = _geometry(setup, Q_SAMPLES[1], 3)
    f_tip = np.array([3.0, -4.0, 5.0])
    fv = forces_view(g, masses=path, tip_force=f_tip)
    want = ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, masses=m, slot=3,
                                       tip_force=f_tip)
    np.testing.assert_allclose(fv.forces, want, rtol=0, atol=ATOL_SAME_N)
    reference = forces_view(g, tip_force=f_tip).forces
    assert np.max(np.abs(fv.forces - reference)) > 0.1       # the file's model is used


@pytest.mark.parametrize("slot", [0, 9])
def test_tip_force_part_is_minus_jt_f_by_finite_differences(setup, slot):
    """Virtual work: the tip force adds ``-J^T f`` with ``J = d tip / d q`` of the drawn tip."""
    g = _geometry(setup, Q_SAMPLES[0], slot)
    J = np.empty((3, 3))
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = FD_STEP_M
        up = robot_geometry(g.q + dq, g.T_b_e, g.design, slot=slot).points["tip"]
        down = robot_geometry(g.q - dq, g.T_b_e, g.design, slot=slot).points["tip"]
        J[:, j] = (up - down) / (2 * FD_STEP_M)
    f_tip = np.random.default_rng(7).uniform(-30.0, 30.0, 3)
    fv = forces_view(g, tip_force=f_tip)
    np.testing.assert_allclose(fv.forces - fv.gravity_forces, -J.T @ f_tip, rtol=0,
                               atol=ATOL_FD_N)


def test_handle_and_tip_force_round_trip():
    rng = np.random.default_rng(3)
    tip = rng.uniform(-0.3, 0.3, 3)
    for f in rng.uniform(-100.0, 100.0, (20, 3)):
        h = handle_from_tip_force(f, tip)
        np.testing.assert_allclose(h - tip, FORCE_SCALE_M_PER_N * f, rtol=0, atol=1e-15)
        np.testing.assert_allclose(tip_force_from_handle(h, tip), f, rtol=0, atol=1e-9)


def test_handle_dragged_along_x_sets_a_force_along_x():
    tip = np.array([0.1, -0.2, 0.05])
    f = tip_force_from_handle(tip + [0.02, 0.0, 0.0], tip)
    np.testing.assert_allclose(f, [0.02 / FORCE_SCALE_M_PER_N, 0.0, 0.0], rtol=0, atol=1e-9)
    far = tip_force_from_handle(tip + [0.0, 0.0, -10.0], tip)       # cut, same direction
    np.testing.assert_allclose(far, [0.0, 0.0, -MAX_TIP_FORCE_N], rtol=0, atol=1e-9)


def test_readout_flags_the_actuators_over_their_limits(setup):
    g = _geometry(setup, Q_SAMPLES[0], 0)
    free = forces_view(g)
    a = np.abs(free.forces)
    lim = np.where(a == a.max(), 0.5 * a, 2.0 * a + 1.0)            # only the largest over
    fv = forces_view(g, f_max=lim)
    np.testing.assert_array_equal(fv.over, a == a.max())
    text = forces_html(fv)
    k = int(np.argmax(a)) + 1
    assert f'data-force="f{k}" data-force-n="{float(fv.forces[k - 1])!r}" data-over="1"' in text
    assert text.count('data-over="1"') == 1
    assert 'data-level="error"' in text and f"f{k} (" in text
    ok = forces_html(forces_view(g, f_max=2.0 * a.max() + 1.0))
    assert "data-over" not in ok and "within the limits" in ok
    assert "no force limits" in forces_html(free)


@pytest.mark.parametrize("f_max", [-5.0, 0.0, np.nan, np.inf, [1.0, 2.0], [1.0, -2.0, 3.0],
                                   "10", [[1.0, 2.0, 3.0]], True])
def test_bad_force_limits_are_named(f_max):
    with pytest.raises(InvalidInputError, match="f_max"):
        check_f_max(f_max)


def test_force_limits_broadcast():
    np.testing.assert_array_equal(check_f_max(40), [40.0, 40.0, 40.0])
    np.testing.assert_array_equal(check_f_max([10, 20, 30]), [10.0, 20.0, 30.0])
    assert check_f_max(None) is None


def test_bad_masses_files_are_named(tmp_path):
    with pytest.raises(InvalidInputError, match="masses: cannot read .*nowhere.toml"):
        check_masses(tmp_path / "nowhere.toml")
    (tmp_path / "none.toml").write_text("[design]\nname = 'x'\n")
    with pytest.raises(InvalidInputError, match=r"masses: .*none.toml: expected a \[masses\]"):
        check_masses(tmp_path / "none.toml")
    (tmp_path / "neg.toml").write_text("[masses.link_a]\nmass = -1.0\n")
    with pytest.raises(InvalidInputError, match="masses: .*link_a"):
        check_masses(tmp_path / "neg.toml")
    (tmp_path / "bad.toml").write_text("[masses\n")
    with pytest.raises(InvalidInputError, match="masses: .*bad.toml"):
        check_masses(tmp_path / "bad.toml")
    with pytest.raises(TypeError, match="masses"):
        check_masses(3.0)


@pytest.mark.parametrize("f", [[np.nan, 0, 0], [1.0, 2.0], [[1.0, 2.0, 3.0]],
                               [MAX_TIP_FORCE_N, 1.0, 0.0]])
def test_bad_tip_forces_are_named(f):
    with pytest.raises(InvalidInputError, match="tip_force"):
        check_tip_force(f)


# ---------------------------------------------------------------------- the viser layer
@pytest.fixture
def app(tmp_path):
    pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
    from athenakin.app import AthenaApp

    path, _ = _masses_file(tmp_path)
    a = AthenaApp(port=0, backend="numpy", masses=path, f_max=[30.0, 30.0, 4.0])
    yield a
    a.stop()


def test_app_layer_shows_the_forces_of_the_drawn_slot_and_follows_a_drag(app, tmp_path):
    m = ak.dynamics.MassModel.from_toml(tmp_path / "masses.toml")
    layer = app.forces

    def expected(tip):
        g = app.view.geometry
        return ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, masses=m, slot=g.slot,
                                           tip_force=tip)

    np.testing.assert_allclose(layer.view.forces, expected(None), rtol=0, atol=ATOL_SAME_N)
    assert 'data-force="f1"' in layer.readout.content
    # drag: the tip handle gives way to the force handle, which is dragged 20 mm along -z
    assert app.tip_handle.visible and not layer.handle.visible
    layer.drag_checkbox.value = True
    layer._show_handle()                                    # what the checkbox's event runs
    assert layer.handle.visible and not app.tip_handle.visible
    tip = app.view.geometry.points["tip"]
    np.testing.assert_allclose(layer.handle.position, tip, rtol=0, atol=1e-6)
    _handle_event(layer, "start")
    layer.handle.position = tuple(tip + [0.0, 0.0, -0.02])
    _handle_event(layer, "update")
    _handle_event(layer, "end")
    want_tip = np.array([0.0, 0.0, -0.02 / FORCE_SCALE_M_PER_N])
    np.testing.assert_allclose(layer.tip_force, want_tip, rtol=0, atol=1e-4)
    np.testing.assert_allclose(layer.force_input.value, want_tip, rtol=0, atol=1e-3)
    np.testing.assert_allclose(layer.view.forces, expected(layer.tip_force), rtol=0,
                               atol=ATOL_SAME_N)
    # the robot moves: the force stays (base frame), the handle follows the tip
    app.set_q(app.q + [0.002, 0.0, 0.0])
    tip2 = app.view.geometry.points["tip"]
    assert np.linalg.norm(tip2 - tip) > 1e-4
    np.testing.assert_allclose(layer.handle.position,
                               tip2 + FORCE_SCALE_M_PER_N * layer.tip_force, rtol=0, atol=1e-6)
    np.testing.assert_allclose(layer.view.forces, expected(layer.tip_force), rtol=0,
                               atol=ATOL_SAME_N)
    # the limit of 4 N on q3 is flagged in the read-out
    over = np.abs(layer.view.forces) > [30.0, 30.0, 4.0]
    np.testing.assert_array_equal(layer.view.over, over)
    assert layer.readout.content.count('data-over="1"') == int(over.sum())
    # numeric input, a bad value (kept out), reset, and the tip handle back
    layer.set_tip_force([1.0, 2.0, 3.0])
    np.testing.assert_allclose(layer.view.forces, expected([1.0, 2.0, 3.0]), rtol=0,
                               atol=ATOL_SAME_N)
    layer.set_tip_force([1e4, 0.0, 0.0])
    assert "tip_force" in layer.readout.content and "at most" in layer.readout.content
    np.testing.assert_array_equal(layer.tip_force, [1.0, 2.0, 3.0])
    layer.set_tip_force(np.zeros(3))
    np.testing.assert_allclose(layer.view.forces, expected(None), rtol=0, atol=ATOL_SAME_N)
    layer.drag_checkbox.value = False
    layer._show_handle()
    assert app.tip_handle.visible and not layer.handle.visible
    layer.checkbox.value = False
    assert layer.update(app.view.geometry) is None and layer.readout.content == ""


def test_force_handle_dragged_too_far_sets_the_largest_force_and_snaps_to_it(app):
    layer = app.forces
    layer.drag_checkbox.value = True
    layer._show_handle()
    tip = app.view.geometry.points["tip"]
    _handle_event(layer, "start")
    layer.handle.position = tuple(tip + [10.0, 0.0, 0.0])               # 2000 N: too far
    _handle_event(layer, "end")                       # the end first ...
    _handle_event(layer, "update")                    # ... then the update
    np.testing.assert_allclose(layer.tip_force, [MAX_TIP_FORCE_N, 0.0, 0.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(layer.handle.position,
                               tip + [FORCE_SCALE_M_PER_N * MAX_TIP_FORCE_N, 0.0, 0.0],
                               rtol=0, atol=1e-6)


def test_app_default_masses_follow_a_new_design(tmp_path):
    """Without --masses the forces are those of the reference model of the design drawn,
    also after the Set-up tab loads another design."""
    pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
    import dataclasses

    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        g = app.view.geometry
        np.testing.assert_allclose(app.forces.view.forces,
                                   ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, slot=0),
                                   rtol=0, atol=ATOL_SAME_N)
        d2 = dataclasses.replace(ak.Design.default(), l4=0.17)
        (tmp_path / "d2.toml").write_text(d2.to_toml())
        app.setup_tab.design_path.value = str(tmp_path / "d2.toml")
        app.setup_tab.apply()
        g2 = app.view.geometry
        assert g2.design.l4 == pytest.approx(0.17, abs=0)
        want = ak.dynamics.actuator_forces(g2.q, g2.T_b_e, g2.design, slot=g2.slot)
        np.testing.assert_allclose(app.forces.view.forces, want, rtol=0, atol=ATOL_SAME_N)
        before = ak.dynamics.actuator_forces(g2.q, g2.T_b_e, g2.design, slot=g2.slot,
                                             masses=ak.dynamics.MassModel.reference())
        assert np.max(np.abs(want - before)) > 1e-6        # the model did change with l4
    finally:
        app.stop()


def test_app_refuses_bad_force_options_before_serving(tmp_path):
    pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
    from athenakin.app import AthenaApp

    with pytest.raises(InvalidInputError, match="f_max"):
        AthenaApp(port=0, backend="numpy", f_max=-3.0)
    with pytest.raises(InvalidInputError, match="masses"):
        AthenaApp(port=0, backend="numpy", masses=tmp_path / "nowhere.toml")


@pytest.mark.parametrize("argv, match", [
    (["--f-max", "-5"], "--f-max: f_max: expected positive"),
    (["--f-max", "5", "6"], "--f-max: expected 1 or 3"),
    (["--masses", "NOWHERE.toml"], "--masses: masses: cannot read"),
])
def test_cli_names_bad_force_options(argv, match, capsys):
    pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
    from athenakin.cli import main

    assert main(["app", "--port", "0", *argv]) == 1
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1


# ---------------------------------------------------------------------- the browser
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


@pytest.mark.slow
def test_force_readout_appears_in_the_browser(setup):
    pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
    playwright = pytest.importorskip("playwright.sync_api")
    assert Path(CHROMIUM).exists(), f"{CHROMIUM} not found: apt-get install chromium"
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen(
        [sys.executable, "-m", "athenakin.cli", "app", "--host", "127.0.0.1", "--port",
         str(port), "--backend", "numpy", "--f-max", "1.0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        url, t0, lines = None, time.monotonic(), []
        while time.monotonic() - t0 < 60 and url is None:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            if "serving ATHENA at " in line:
                url = line.split("serving ATHENA at ")[1].split()[0]
        assert url is not None, "".join(lines)
        g = _geometry(setup, setup.q_home, 0)
        want = ak.dynamics.actuator_forces(g.q, g.T_b_e, g.design, slot=0)
        with playwright.sync_playwright() as pw:
            b = pw.chromium.launch(executable_path=CHROMIUM, args=[
                "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"])
            try:
                page = b.new_page(viewport={"width": 900, "height": 640})
                page.goto(url)
                page.wait_for_selector("[data-force=f1]", state="attached", timeout=60000)
                for i in range(3):
                    cell = page.locator(f"[data-force=f{i + 1}]")
                    assert float(cell.get_attribute("data-force-n")) == pytest.approx(
                        want[i], abs=1e-9)
                    assert cell.inner_text().strip() == f"{want[i]:+.2f}"
                status = page.locator("[data-force=status]")
                assert status.get_attribute("data-level") == (
                    "error" if np.any(np.abs(want) > 1.0) else "ok")
            finally:
                b.close()
    finally:
        proc.kill()
        proc.wait()
