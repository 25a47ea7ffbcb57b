"""`athenakin app` in a real browser: headless Chromium (Debian's) driven by Playwright.

One server (``python -m athenakin.cli app --host 127.0.0.1 --port N``) and one page serve
the whole module, in order: the WebGL canvas renders, the q1 slider moves the robot and
the read-outs show the forward kinematics, the IK sliders drive q, a trajectory plays
back, a bad trajectory is reported in the page while the app keeps running, and SIGINT
stops the server. The numpy backend keeps numba's first compilation out of the budget.
"""

import math
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("viser", reason="needs the 'app' extra (viser)")
imageio = pytest.importorskip("imageio.v3")
playwright = pytest.importorskip("playwright.sync_api")

import athenakin as ak  # noqa: E402
from athenakin.app import tip_from_angles  # noqa: E402
from athenakin.plot import COLORS, robot_geometry  # noqa: E402

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync"]
START_TIMEOUT_S = 60
UPDATE_TIMEOUT_MS = 15000
COLOR_TOL = 45
#: The sliders of the open tab (Mantine keeps visited tabs mounted, hidden).
SLIDERS = "[role=slider] >> visible=true"
TRAJECTORY = ("t_s,q1_m,q2_m,q3_m\n0.0,-0.10,0.10,0.45\n0.5,-0.11,0.09,0.46\n"
              "1.0,-0.12,0.08,0.47\n")
BAD_TRAJECTORY = "t_s,q1_m,q2_m,q3_m\n0.0,-0.10,0.10,0.45\n0.5,-0.11,oops,0.46\n"


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _color_fraction(img, color):
    target = 255 * np.array([int(color[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    return float(np.mean(np.linalg.norm(img[..., :3].astype(float) - target, axis=-1)
                         < COLOR_TOL))


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    assert Path(CHROMIUM).exists(), f"{CHROMIUM} not found: apt-get install chromium"
    d = tmp_path_factory.mktemp("app")
    (d / "traj.csv").write_text(TRAJECTORY)
    (d / "bad.csv").write_text(BAD_TRAJECTORY)
    port = _free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "athenakin.cli", "app", "--host", "127.0.0.1", "--port",
         str(port), "--backend", "numpy", "--trajectory", str(d / "traj.csv")],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url, t0, lines = None, time.monotonic(), []
    while time.monotonic() - t0 < START_TIMEOUT_S:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if "serving ATHENA at " in line:
            url = line.split("serving ATHENA at ")[1].split()[0]
            break
    # the port asked for (viser moves on to the next one only if another process took it)
    assert url is not None and url.startswith("http://127.0.0.1:"), "".join(lines)
    port = int(url.rstrip("/").rsplit(":", 1)[1])
    errors = []
    with playwright.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 900, "height": 640})
        page.on("pageerror", lambda e: errors.append(f"pageerror: {e}"))
        page.on("console", lambda m: errors.append(f"console: {m.text}")
                if m.type == "error" else None)
        page.goto(url)
        page.wait_for_selector("[data-ro=q1]", timeout=START_TIMEOUT_S * 1000)
        page.wait_for_timeout(1000)
        yield {"proc": proc, "page": page, "errors": errors, "dir": d, "port": port}
        browser.close()
    if proc.poll() is None:
        proc.kill()
        proc.wait()


def _drawn_screenshot(page, path=None):
    """A screenshot once the robot's colours are on the canvas (WebGL renders after the
    read-outs arrive; software rendering on a busy machine takes a few seconds)."""
    t0 = time.monotonic()
    while True:
        img = imageio.imread(page.screenshot(path=path))
        fractions = {k: _color_fraction(img, COLORS[k]) for k in ("serial", "parallel",
                                                                  "actuator")}
        if min(fractions.values()) > 2e-4 or time.monotonic() - t0 > UPDATE_TIMEOUT_MS / 1e3:
            return img, fractions
        page.wait_for_timeout(300)


def _ro(page, key):
    return page.inner_text(f"[data-ro={key}]").strip()


def _wait_ro(page, key, want):
    page.wait_for_function(
        "([k, w]) => { const e = document.querySelector(`[data-ro=${k}]`); "
        "return e && e.textContent.trim() === w; }", arg=[key, want], timeout=UPDATE_TIMEOUT_MS)


def _fmt(x, scale=1e3):
    t = f"{x * scale:.2f}"
    return t[1:] if t.startswith("-") and float(t) == 0 else t


def _tab(page, name):
    page.get_by_role("tab", name=name).click()
    page.wait_for_timeout(300)


def _slider_values(page):
    s = page.locator(SLIDERS)
    return [float(s.nth(i).get_attribute("aria-valuenow")) for i in range(s.count())]


def test_canvas_renders_the_robot(app):
    page = app["page"]
    assert page.locator("canvas").count() >= 1
    img, fractions = _drawn_screenshot(page, app["dir"] / "start.png")
    app["start"] = img
    assert img.std() > 15
    for key, f in fractions.items():
        assert f > 2e-4, key
    assert _ro(page, "q1") == "-100.00" and _ro(page, "mode") == "0 / +1"


def test_q1_slider_moves_the_robot_and_reads_out_fk(app):
    page = app["page"]
    sliders = page.locator(SLIDERS)
    assert sliders.count() == 3                                   # q1, q2, q3: q1 first
    assert _slider_values(page) == [-100.0, 100.0, 450.0]
    before = app.get("start")
    if before is None:
        before, _ = _drawn_screenshot(page)
    sliders.nth(0).focus()
    for _ in range(6):                                            # 6 steps of 0.5 mm
        page.keyboard.press("ArrowRight")
    _wait_ro(page, "q1", "-97.00")
    t0 = time.monotonic()                                         # the scene follows
    while time.monotonic() - t0 < UPDATE_TIMEOUT_MS / 1e3:
        after = imageio.imread(page.screenshot())
        if np.mean(np.abs(after.astype(float) - before.astype(float))) > 0.2:
            break
        page.wait_for_timeout(300)
    assert np.mean(np.abs(after.astype(float) - before.astype(float))) > 0.2
    g = robot_geometry([-0.097, 0.10, 0.45], slot=0)
    assert _ro(page, "p") == _fmt(g.p)
    for i in range(5):
        assert _ro(page, f"u{i + 1}") == _fmt(math.degrees(g.u[i]), 1.0)
    for i, a in enumerate("xyz"):
        assert _ro(page, f"tip_b_{a}") == _fmt(g.points["tip"][i])


def test_ik_sliders_drive_q(app):
    page = app["page"]
    _tab(page, "Inverse")
    sliders = page.locator(SLIDERS)
    assert sliders.count() == 3                                    # azimuth, polar, depth
    q_before = _ro(page, "q1"), _ro(page, "q2"), _ro(page, "q3")
    sliders.nth(0).focus()
    for _ in range(8):                                             # 8 steps of 0.1 deg
        page.keyboard.press("ArrowRight")
    page.wait_for_timeout(300)
    az, pol, depth = _slider_values(page)
    tip = tip_from_angles(math.radians(az), math.radians(pol), depth * 1e-3)
    q, res = ak.q_from_tool_tip(ak.default_rcm_frame(), tip)
    assert res.valid
    for i in range(3):
        _wait_ro(page, f"q{i + 1}", _fmt(q[i]))
    assert (_ro(page, "q1"), _ro(page, "q2"), _ro(page, "q3")) != q_before
    assert page.get_attribute("[data-ro=status]", "data-level") in ("ok", "warn")


def test_playback_and_a_bad_trajectory_in_the_page(app):
    page = app["page"]
    _tab(page, "Playback")
    slider = page.locator(SLIDERS).first
    slider.focus()
    page.keyboard.press("End")                                     # the last sample
    for i, v in enumerate((-0.12, 0.08, 0.47)):
        _wait_ro(page, f"q{i + 1}", _fmt(v))
    box = page.locator("input.mantine-TextInput-input >> visible=true").first
    box.fill(str(app["dir"] / "bad.csv"))
    box.press("Enter")
    page.get_by_role("button", name="load trajectory").click()
    page.wait_for_function(
        "() => { const e = document.querySelector('[data-ro=status]'); "
        "return e && e.textContent.includes('line 3'); }", timeout=UPDATE_TIMEOUT_MS)
    status = _ro(page, "status")
    assert "q2_m" in status and page.get_attribute("[data-ro=status]", "data-level") == "error"
    _tab(page, "Forward")                                         # ... and the app keeps going
    page.locator(SLIDERS).nth(2).focus()
    page.keyboard.press("ArrowLeft")
    _wait_ro(page, "q3", "469.50")
    assert app["proc"].poll() is None


def test_no_page_errors(app):
    assert app["errors"] == []


def test_sigint_stops_the_server(app):
    proc = app["proc"]
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=20) == 0
    out = proc.stdout.read()
    assert "athenakin app: stopped" in out and "Traceback" not in out
    with socket.socket() as s, pytest.raises(OSError):
        s.settimeout(2)
        s.connect(("127.0.0.1", app["port"]))
