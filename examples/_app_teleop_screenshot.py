"""Screenshot of the Teleop tab of `athenakin app` for the docs: docs/figures/app_teleop.png.

Starts the app in this process with an environment (a vessel, a sphere of 6 mm 20 mm
beside the tool tip, and a nerve, a capsule under it), opens the page in headless
Chromium (Debian's chromium via Playwright), starts teleoperation in the Teleop tab and
moves the master handle toward the vessel in steps of 2 mm: at scale 0.2 the tip
follows until the safety layer holds it (flags FIXTURE: the target is pushed out of the
vessel's margin, CLEARANCE: the instrument's capsule keeps 5 + 3 mm from it; the purple
segment joins the tip to the target it was kept from). Not run by the example tests (it needs a
browser); run it by hand (``--out DIR`` writes elsewhere):

    python examples/_app_teleop_screenshot.py
"""

import argparse
import shutil
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import sync_playwright

from athenakin.app import AthenaApp
from athenakin.collision import Environment

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]
TIMEOUT_MS = 120_000
#: Handle steps toward the vessel (base x), m, and how many.
STEP_M, STEPS = 0.002, 45


def _wait_state(page, state):
    page.wait_for_function(
        "(w) => { const e = document.querySelector('[data-ro=teleop_state]');"
        " return e && e.textContent.trim() === w; }", arg=state, timeout=TIMEOUT_MS)


def main(out: Path) -> Path:
    app = AthenaApp(port=0, backend="numpy")
    path = out / "app_teleop.png"
    try:
        tip = app.view.readouts.tip_b.copy()
        app.bodies.environment = (
            Environment().sphere(tip + [0.02, 0.0, 0.0], 0.006, name="vessel")
            .capsule(tip + [-0.03, 0.02, -0.02], tip + [0.03, 0.02, -0.02], 0.004,
                     name="nerve"))
        app.set_q(app.q)                        # the clearance read-out with the obstacles
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            page.goto(app.url)
            page.wait_for_selector("[data-ro=q1]", timeout=TIMEOUT_MS)
            close = page.locator(".mantine-Notification-closeButton")
            for i in range(close.count()):            # the software-WebGL notice
                close.nth(i).click()
            page.get_by_role("tab", name="Teleop").click()
            page.get_by_role("button", name="start teleop").click()
            _wait_state(page, "following")
            h0 = np.array(app.teleop.master.handle_b)
            for k in range(1, STEPS + 1):             # a drag toward the vessel
                app.teleop.set_handle(h0 + [k * STEP_M, 0.0, 0.0])
                page.wait_for_timeout(60)
            page.wait_for_function(
                "() => { const e = document.querySelector('[data-flag=FIXTURE]');"
                " return e && e.dataset.on === '1'; }", timeout=TIMEOUT_MS)
            for client in app.server.get_clients().values():   # the tip and the handle
                client.camera.position = tuple(float(x) for x in tip + [0.07, -0.19, 0.08])
                client.camera.look_at = tuple(float(x) for x in tip + [0.05, 0.0, 0.01])
                client.camera.up_direction = (0.0, 0.0, 1.0)
            page.wait_for_timeout(2500)               # WebGL renders the new view
            page.screenshot(path=str(path))
            browser.close()
    finally:
        app.stop()
    print(f"wrote {path}")
    return path


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    t0 = time.monotonic()
    main(ap.parse_args().out)
    print(f"{time.monotonic() - t0:.1f} s")
