"""Screenshots of `athenakin app` for the docs: docs/figures/app_*.png.

Starts the app in this process, opens it in headless Chromium (Debian's chromium via
Playwright) and saves three views: forward mode, all valid slots ghosted, inverse mode.
Not run by the example tests (it needs a browser); run it by hand:

    python examples/_app_screenshots.py
"""

import shutil
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import sync_playwright

from athenakin.app import AthenaApp

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]


def settle(page, seconds=2.5):
    page.wait_for_timeout(int(seconds * 1000))


def main():
    app = AthenaApp(port=0)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            page.goto(app.url)
            page.wait_for_selector("[data-ro=q1]", timeout=60000)
            settle(page)
            close = page.locator(".mantine-Notification-closeButton")
            for i in range(close.count()):            # the software-WebGL notice
                close.nth(i).click()
            app.set_q([-0.12, 0.07, 0.47])
            settle(page)
            page.screenshot(path=str(OUT / "app_forward.png"))
            app.slot = "all"
            app.set_q([-0.12, 0.07, 0.47])
            settle(page)
            page.screenshot(path=str(OUT / "app_all_slots.png"))
            app.slot = 0
            app.set_q([-0.12, 0.07, 0.47])
            page.get_by_role("tab", name="Inverse").click()
            tip = app.view.readouts.tip_e
            app._move_tip(tip + np.array([0.0, 0.03, 0.04]), snap_angles=False)
            app._sync_gui(app.view, sync_ik=True)
            settle(page)
            page.screenshot(path=str(OUT / "app_inverse.png"))
            browser.close()
    finally:
        app.stop()
    for name in ("app_forward", "app_all_slots", "app_inverse"):
        print(f"wrote {OUT / (name + '.png')}")


if __name__ == "__main__":
    t0 = time.monotonic()
    main()
    print(f"{time.monotonic() - t0:.1f} s")
