"""Screenshot of Foxglove Studio showing a tracked athenakin MCAP file with our layout.

Foxglove Studio v1.48, the last open-source release (MPL-2.0), ships its app compiled in the
npm package ``@foxglove/studio-base`` (a UMD bundle, ``assets/index.js``, with React 17 as
its only externals). ``index.html`` + ``main.js`` here mount its ``App`` with the local-file
and remote-file data sources; this script serves them and the MCAP file on 127.0.0.1 (with
HTTP Range requests, which Foxglove's remote MCAP reader uses), opens the page in headless
Chromium (Playwright, Debian's /usr/bin/chromium), opens the file by Foxglove's deep link
``?ds=remote-file&ds.url=...``, imports the layout through *Layouts* > *Import layout*
(the browser's file picker answered with the layout file), seeks to a time and takes the
screenshot. Nothing is reached outside 127.0.0.1.

Run from the repository root (extras ``ros`` and Playwright; node + npm for the install)::

    (cd tools/foxglove-shot && npm ci)
    python tools/foxglove-shot/shot.py             # -> docs/figures/foxglove_track.png

With no ``--mcap``, the recording is made here: ``athenakin plan`` of
examples/motion/tip_square.csv at 50 Hz, then ``athenakin track`` of that plan into MCAP.
The script fails (exit status 1) if Foxglove reports a problem with the file, or if the
layout's panels do not show the topics.
"""

from __future__ import annotations

import argparse
import functools
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
import http.server
import os
import re
import threading


class _Handler(http.server.SimpleHTTPRequestHandler):
    """Static files with HTTP Range requests (Foxglove's remote MCAP reader asks for byte ranges)."""

    extra: dict[str, str] = {}

    def log_message(self, format, *args):  # noqa: A002
        pass

    def translate_path(self, path):
        clean = path.split("?", 1)[0].split("#", 1)[0]
        if clean in self.extra:
            return self.extra[clean]
        return super().translate_path(path)

    def send_head(self):
        path = self.translate_path(self.path)
        rng = self.headers.get("Range")
        if rng is None or not os.path.isfile(path):
            return super().send_head()
        m = re.fullmatch(r"bytes=(\d*)-(\d*)", rng.strip())
        size = os.path.getsize(path)
        if m is None:
            self.send_error(416)
            return None
        if m.group(1) == "":
            start, end = max(0, size - int(m.group(2))), size - 1
        else:
            start = int(m.group(1))
            end = min(size - 1, int(m.group(2))) if m.group(2) else size - 1
        if start > end or start >= size:
            self.send_response(416)
            self.send_header("Content-Range", f"bytes */{size}")
            self.end_headers()
            return None
        f = open(path, "rb")  # noqa: SIM115
        f.seek(start)
        self.send_response(206)
        self.send_header("Content-Type", self.guess_type(path))
        self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.send_header("Content-Length", str(end - start + 1))
        self.send_header("Accept-Ranges", "bytes")
        self.end_headers()
        self._remaining = end - start + 1
        return f

    def copyfile(self, source, outputfile):
        remaining = getattr(self, "_remaining", None)
        if remaining is None:
            return super().copyfile(source, outputfile)
        while remaining > 0:
            chunk = source.read(min(remaining, 1 << 16))
            if not chunk:
                break
            outputfile.write(chunk)
            remaining -= len(chunk)
        self._remaining = None
        return None

    def end_headers(self):
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Cache-Control", "no-store")
        super().end_headers()


def serve(root: str, extra: dict[str, str]):
    handler = type("Handler", (_Handler,), {"extra": dict(extra)})
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(handler, directory=root))
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    return httpd, httpd.server_address[1]


HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync"]
#: The name the imported layout gets in Foxglove (from the file name).
LAYOUT_NAME = "athenakin"


def make_recording(workdir: Path) -> Path:
    """Plan examples/motion/tip_square.csv at 50 Hz and track the plan into an MCAP file."""
    env = dict(os.environ, PYTHONPATH=str(REPO / "src"))
    plan = workdir / "tip_square_plan.csv"
    mcap = workdir / "tip_square_track.mcap"
    subprocess.run([sys.executable, "-m", "athenakin", "plan",
                    str(REPO / "examples/motion/tip_square.csv"), "-o", str(plan),
                    "--rate", "50", "--no-plots"], check=True, env=env)
    subprocess.run([sys.executable, "-m", "athenakin", "track", str(plan), "-o", str(mcap)],
                   check=True, env=env)
    return mcap


def screenshot(mcap: Path, layout: Path, out: Path, *, at: float, width: int, height: int,
               timeout_s: float, settle_s: float) -> None:
    from playwright.sync_api import sync_playwright

    bundle = HERE / "node_modules/@foxglove/studio-base/assets/index.js"
    if not bundle.is_file():
        raise SystemExit(f"{bundle} is missing: run 'npm ci' in {HERE}")
    layout_text = layout.read_text()
    json.loads(layout_text)  # a clear error here rather than a snackbar in the page
    httpd, port = serve(str(HERE), {"/recording.mcap": str(mcap)})
    base = f"http://127.0.0.1:{port}"
    url = f"{base}/index.html?ds=remote-file&ds.url={base}/recording.mcap"
    # Foxglove's "Import layout" calls window.showOpenFilePicker; answer it with the layout.
    picker = (
        "window.showOpenFilePicker = async () => [{kind: 'file', name: %s, getFile: async () =>"
        " new File([%s], %s, {type: 'application/json'})}];"
        % (json.dumps(LAYOUT_NAME + ".json"), json.dumps(layout_text),
           json.dumps(LAYOUT_NAME + ".json")))
    errors: list[str] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS)
            context = browser.new_context(viewport={"width": width, "height": height})
            context.add_init_script(picker)
            page = context.new_page()
            page.set_default_timeout(timeout_s * 1000)
            page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
            page.goto(url)
            # The file is open when its topics are listed in the data-source sidebar.
            page.get_by_text("/robot_description", exact=True).first.wait_for()
            # Import the layout: Layouts sidebar > Import layout.
            page.get_by_title("Layouts").first.click()
            page.get_by_label("Import layout").click()
            page.get_by_text(LAYOUT_NAME, exact=True).first.wait_for()
            page.get_by_text("tool tip (base frame, m)").first.wait_for()
            # Foxglove's own list of problems with the data source must be empty.
            page.get_by_title("Data source").first.click()
            page.get_by_role("tab", name="Problems").click()
            page.get_by_text("No problems found").wait_for()
            # Close the sidebar (a second click on its icon), dismiss the 3D panel's tip.
            page.get_by_title("Data source").first.click()
            dismiss = page.get_by_label("Dismiss")
            if dismiss.count():
                dismiss.first.click()
            # Seek: a click on the playback scrubber at the fraction `at` of the recording.
            track = page.locator('div[style*="height: 32px"]').last
            box = track.bounding_box()
            assert box is not None
            page.mouse.click(box["x"] + at * box["width"], box["y"] + box["height"] / 2)
            page.mouse.move(box["x"] + box["width"] / 2, box["y"] - 200)
            # Let the 3D panel load the URDF and the plots fill, then take the picture.
            time.sleep(settle_s)
            if errors:
                raise SystemExit("Foxglove reported: " + "; ".join(errors))
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
            browser.close()
    finally:
        httpd.shutdown()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mcap", type=Path, help="tracked MCAP (default: made here)")
    parser.add_argument("--layout", type=Path, default=REPO / "docs/foxglove_layout.json")
    parser.add_argument("--out", type=Path, default=REPO / "docs/figures/foxglove_track.png")
    parser.add_argument("--at", type=float, default=0.45,
                        help="where to seek, as a fraction of the recording (0.45)")
    parser.add_argument("--size", type=int, nargs=2, default=(1600, 900),
                        metavar=("WIDTH", "HEIGHT"))
    parser.add_argument("--timeout", type=float, default=60.0, help="per step, s (60)")
    parser.add_argument("--settle", type=float, default=20.0,
                        help="wait after the seek before the screenshot (the plots load the file in blocks), s (20)")
    args = parser.parse_args(argv)
    if not 0.0 <= args.at <= 1.0:
        parser.error(f"--at must lie in [0, 1], got {args.at}")
    with tempfile.TemporaryDirectory() as tmp:
        mcap = args.mcap if args.mcap is not None else make_recording(Path(tmp))
        screenshot(mcap, args.layout, args.out, at=args.at, width=args.size[0],
                   height=args.size[1], timeout_s=args.timeout, settle_s=args.settle)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
