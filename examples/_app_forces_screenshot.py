"""Screenshot of the actuator forces in `athenakin app` for the docs: docs/figures/app_forces.png.

Starts the app in this process with force limits of 25 N, sets a tip force of 20 N, shows the
tip-force handle and opens the page in headless Chromium (Debian's chromium via
Playwright), scrolled to the folder *Actuator forces*. Not run by the example tests (it
needs a browser); run it by hand (``--out DIR`` writes elsewhere):

    python examples/_app_forces_screenshot.py
"""

import argparse
import shutil
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

from athenakin.app import AthenaApp

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]
Q = [-0.12, 0.07, 0.47]
TIP_FORCE_N = [0.0, 12.0, -16.0]
F_MAX_N = 25.0


def main(out: Path) -> Path:
    app = AthenaApp(port=0, f_max=F_MAX_N)
    path = out / "app_forces.png"
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            page.goto(app.url)
            page.wait_for_selector("[data-force=f1]", state="attached", timeout=60000)
            page.wait_for_timeout(2500)
            close = page.locator(".mantine-Notification-closeButton")
            for i in range(close.count()):            # the software-WebGL notice
                close.nth(i).click()
            app.set_q(Q)
            app.forces.set_tip_force(TIP_FORCE_N)
            app.forces.drag_checkbox.value = True
            app.forces._show_handle()
            tip = app.view.geometry.points["tip"]
            for client in app.server.get_clients().values():   # closer, onto the tool tip
                client.camera.look_at = tuple(float(x) for x in tip + [-0.02, 0.06, 0.02])
                client.camera.position = tuple(float(x) for x in tip + [0.2, -0.24, 0.12])
                client.camera.up_direction = (0.0, 0.0, 1.0)
            page.wait_for_timeout(1500)
            page.locator("[data-force=panel]").scroll_into_view_if_needed()
            page.wait_for_timeout(1500)
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
