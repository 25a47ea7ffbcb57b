"""Screenshot of Foxglove Studio showing a tracked athenakin MCAP file with our layout.

Foxglove Studio v1.48, the last open-source release (MPL-2.0), ships its app compiled in the
npm package ``@foxglove/studio-base`` (a UMD bundle, ``assets/index.js``, whose only externals
are React 17 and ReactDOM 17). ``index.html`` + ``main.js`` here mount its ``App`` with the
local-file and remote-file data sources; this script serves them and the MCAP file on
127.0.0.1, opens the page in headless Chromium (Playwright, Debian's /usr/bin/chromium), and
does what a user does:

1. *Open local file* on the start dialog (``--source local``, the default; the browser's file
   picker is answered with the MCAP file), or Foxglove's deep link
   ``?ds=remote-file&ds.url=...`` (``--source remote``: HTTP Range requests, served here);
2. *Layouts* > *Import layout* with docs/foxglove_layout.json (the picker again);
3. checks that Foxglove's *Problems* list of the data source is empty and that the page
   raised no error; closes the sidebar, seeks to ``--at`` of the recording, waits for the
   plots to load, and takes the screenshot.

``--source live`` opens no file: the script starts an ``athenakin.ros.FoxgloveStream`` on a
free port whose tool tip circles, and Foxglove opens it through its deep link
``?ds=foxglove-websocket&ds.url=ws://127.0.0.1:PORT`` (Studio 1.48 offers only the
subprotocol ``foxglove.websocket.v1``; the stream's relay logs what each client offered, and
the script fails unless that name was offered and accepted). Steps 2 and 3 follow, without
the seek::

    python tools/foxglove-shot/shot.py --source live --out docs/figures/foxglove_live.png

``--recording teleop`` shows a replayed teleoperation session instead (docs/teleop.md): with
no ``--mcap``, the script writes an 8 s recorded master here (``geometry_msgs/PoseStamped``
at 1 kHz and a ``sensor_msgs/Joy`` clutch pedal: the pedal held from 3 to 4 s, the master
silent from 5.5 to 5.6 s, a 0.3 m jump of the handle from 6.5 to 7 s), replays it with
``athenakin teleop --master REC.mcap -o session.mcap`` (the simulated MuJoCo arm in the loop)
and opens the session's CRTK topics with docs/foxglove_teleop_layout.json::

    python tools/foxglove-shot/shot.py --recording teleop   # -> docs/figures/foxglove_teleop.png

Nothing is reached outside 127.0.0.1. Run from the repository root (extra ``ros`` and
Playwright in the Python environment; node + npm only for the install)::

    (cd tools/foxglove-shot && npm ci)
    python tools/foxglove-shot/shot.py             # -> docs/figures/foxglove_track.png

With no ``--mcap``, the recording is made here: ``athenakin plan`` of
examples/motion/tip_square.csv at 50 Hz, then ``athenakin track`` of that plan into MCAP.
Exit status 1, with Foxglove's words, if Foxglove reports a problem with the file.
"""

from __future__ import annotations

import argparse
import functools
import http.server
import json
import logging
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync"]
#: The name the imported layout gets in Foxglove (Foxglove names it after the file).
LAYOUT_NAME = "athenakin"
#: Where the server exposes the recording.
MCAP_URL_PATH = "/recording.mcap"
#: Per recording kind: the default layout, the default picture, and a topic whose name in
#: the data-source sidebar says that Foxglove has opened the file.
RECORDINGS = {
    "track": ("docs/foxglove_layout.json", "docs/figures/foxglove_track.png",
              "/robot_description"),
    "teleop": ("docs/foxglove_teleop_layout.json", "docs/figures/foxglove_teleop.png",
               "/athena/teleop/status"),
}


class _Handler(http.server.SimpleHTTPRequestHandler):
    """Static files, plus ``extra`` URL paths mapped to files, with HTTP Range requests."""

    extra: dict[str, str] = {}

    def log_message(self, format, *args):  # noqa: A002  (the base class's signature)
        pass

    def translate_path(self, path):
        clean = path.split("?", 1)[0].split("#", 1)[0]
        if clean in self.extra:
            return self.extra[clean]
        return super().translate_path(path)

    def send_head(self):
        path = self.translate_path(self.path)
        byte_range = self.headers.get("Range")
        if byte_range is None or not os.path.isfile(path):
            return super().send_head()
        size = os.path.getsize(path)
        m = re.fullmatch(r"bytes=(\d*)-(\d*)", byte_range.strip())
        if m is None or m.group(0) == "bytes=-":
            self.send_error(416)
            return None
        if m.group(1) == "":                                   # the last N bytes
            start, end = max(0, size - int(m.group(2))), size - 1
        else:
            start = int(m.group(1))
            end = min(size - 1, int(m.group(2))) if m.group(2) else size - 1
        if start > end:
            self.send_response(416)
            self.send_header("Content-Range", f"bytes */{size}")
            self.end_headers()
            return None
        f = open(path, "rb")  # noqa: SIM115  (closed by the base class after copyfile)
        f.seek(start)
        self.send_response(206)
        self.send_header("Content-Type", self.guess_type(path))
        self.send_header("Content-Range", f"bytes {start}-{end}/{size}")
        self.send_header("Content-Length", str(end - start + 1))
        self.end_headers()
        self._remaining = end - start + 1
        return f

    def copyfile(self, source, outputfile):
        remaining = getattr(self, "_remaining", None)
        if remaining is None:
            super().copyfile(source, outputfile)
            return
        while remaining > 0:
            chunk = source.read(min(remaining, 1 << 16))
            if not chunk:
                break
            outputfile.write(chunk)
            remaining -= len(chunk)
        self._remaining = None

    def end_headers(self):
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("Cache-Control", "no-store")
        super().end_headers()


def serve(root: Path, extra: dict[str, str]) -> tuple[http.server.ThreadingHTTPServer, int]:
    """Serve ``root`` and the ``extra`` URL paths on 127.0.0.1 (a free port) in a thread."""
    handler = type("Handler", (_Handler,), {"extra": dict(extra)})
    httpd = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(handler, directory=str(root)))
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    return httpd, httpd.server_address[1]


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


def write_master(path: Path, *, seconds: float = 8.0, rate_hz: float = 1000.0) -> None:
    """A recorded master handle: ``/master/pose`` (PoseStamped, m) and ``/master/joy`` (Joy).

    The handle draws a slow Lissajous figure (5, 4 and 3 cm); the clutch pedal (button 0) is
    held from 3 to 4 s; no pose arrives from 5.5 to 5.6 s (the watchdog holds the robot);
    the handle jumps by 0.3 m in x from 6.5 to 7 s (the velocity and acceleration limits).
    """
    import math

    from mcap_ros2.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)

    def msgdef(name: str) -> str:
        return store.generate_msgdef(name, ros_version=2)[0]

    with open(path, "wb") as fh:
        w = Writer(fh)
        pose = w.register_msgdef("geometry_msgs/msg/PoseStamped",
                                 msgdef("geometry_msgs/msg/PoseStamped"))
        joy = w.register_msgdef("sensor_msgs/msg/Joy", msgdef("sensor_msgs/msg/Joy"))
        t0 = 1_700_000_000 * 10**9
        for k in range(int(seconds * rate_hz)):
            s = k / rate_hz
            if 5.5 <= s < 5.6:                                  # the master falls silent
                continue
            ns = t0 + round(k * 1e9 / rate_hz)
            head = {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": "master"}
            x = 0.05 * math.sin(2 * math.pi * 0.25 * s) + (0.3 if 6.5 <= s < 7.0 else 0.0)
            y = 0.04 * math.sin(2 * math.pi * 0.5 * s)
            z = 0.03 * (1.0 - math.cos(2 * math.pi * 0.125 * s))
            w.write_message("/master/pose", pose, {"header": head, "pose": {
                "position": {"x": x, "y": y, "z": z},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}, log_time=ns)
            if k % round(rate_hz / 20) == 0:                    # the pedal at 20 Hz
                w.write_message("/master/joy", joy, {"header": head, "axes": [], "buttons": [
                    1 if 3.0 <= s < 4.0 else 0]}, log_time=ns)
        w.finish()


def make_teleop_session(workdir: Path) -> Path:
    """Write a recorded master (:func:`write_master`) and replay it: ``athenakin teleop``."""
    env = dict(os.environ, PYTHONPATH=str(REPO / "src"))
    master = workdir / "master.mcap"
    session = workdir / "teleop_session.mcap"
    write_master(master)
    subprocess.run([sys.executable, "-m", "athenakin", "teleop", "--master", str(master),
                    "-o", str(session)], check=True, env=env)
    return session


def _first_title(layout: dict) -> str:
    """The first panel title of a layout: its text on the page says the layout is loaded."""
    for config in layout.get("configById", {}).values():
        if config.get("title"):
            return str(config["title"])
    raise SystemExit("the layout has no panel with a title (the script waits for one)")


def _file_picker_script(layout_text: str, mcap_name: str) -> str:
    """Replace ``window.showOpenFilePicker``: the layout for .json, the MCAP file otherwise."""
    layout_name = json.dumps(LAYOUT_NAME + ".json")
    return f"""
window.showOpenFilePicker = async (options) => {{
  const accepts = JSON.stringify(options?.types ?? []);
  if (accepts.includes(".json")) {{
    return [{{kind: "file", name: {layout_name}, getFile: async () =>
      new File([{json.dumps(layout_text)}], {layout_name}, {{type: "application/json"}})}}];
  }}
  const blob = await (await fetch({json.dumps(MCAP_URL_PATH)})).blob();
  return [{{kind: "file", name: {json.dumps(mcap_name)}, queryPermission: async () => "granted",
    getFile: async () => new File([blob], {json.dumps(mcap_name)})}}];
}};
"""


class _Records(logging.Handler):
    """Keep the log records (the relay's: which subprotocol each client offered)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


def live_stream(rate: float = 30.0):
    """A FoxgloveStream on a free port of 127.0.0.1 whose tool tip circles (period 4 s)."""
    import numpy as np

    sys.path.insert(0, str(REPO / "src"))
    from athenakin.ros import FoxgloveStream

    q0 = np.array([-0.10, 0.10, 0.45])
    t0 = time.monotonic()

    def state():
        phase = 2 * np.pi * (time.monotonic() - t0) / 4.0
        return q0 + 0.012 * np.array([np.cos(phase), np.sin(phase), 0.5 * np.sin(phase)]), 0

    live = FoxgloveStream(port=0)
    live.follow(state, rate=rate)
    return live


def screenshot(mcap: Path | None, layout: Path, out: Path, *, source: str = "local",
               at: float = 0.45, ready_topic: str = "/robot_description",
               width: int = 1600, height: int = 900, timeout_s: float = 60.0,
               settle_s: float = 20.0) -> None:
    """Open ``mcap`` in Foxglove Studio with ``layout``, seek to ``at``, screenshot to ``out``.

    ``source="live"``: no file; Foxglove opens a Foxglove WebSocket connection to a
    :class:`athenakin.ros.FoxgloveStream` publishing a moving pose (:func:`live_stream`), and
    the screenshot is taken ``settle_s`` after the layout is loaded (no seek).
    ``ready_topic``: a topic of the file (listed in Foxglove's data-source sidebar once it is
    open); the layout is loaded when its first panel title appears.
    Raises SystemExit with Foxglove's words if the page reports an error or the data source
    has problems.
    """
    from playwright.sync_api import sync_playwright

    bundle = HERE / "node_modules/@foxglove/studio-base/assets/index.js"
    if not bundle.is_file():
        raise SystemExit(f"{bundle} is missing: run 'npm ci' in {HERE}")
    layout_text = layout.read_text()
    # A clear error here rather than a snackbar in the page.
    ready_title = _first_title(json.loads(layout_text))
    if (mcap is None) != (source == "live"):
        raise ValueError("screenshot: an MCAP file for sources local and remote, none for live")
    httpd, port = serve(HERE, {MCAP_URL_PATH: str(mcap)} if mcap is not None else {})
    base = f"http://127.0.0.1:{port}"
    url = f"{base}/index.html"
    live = None
    relay_log = _Records()
    if source == "remote":
        url += f"?ds=remote-file&ds.url={base}{MCAP_URL_PATH}"
    elif source == "live":
        live = live_stream()
        logging.getLogger("athenakin.ros.foxglove_relay").addHandler(relay_log)
        logging.getLogger("athenakin.ros.foxglove_relay").setLevel(logging.INFO)
        url += f"?ds=foxglove-websocket&ds.url={live.url}"
    errors: list[str] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS)
            context = browser.new_context(viewport={"width": width, "height": height})
            context.add_init_script(_file_picker_script(layout_text,
                                                        mcap.name if mcap else "none"))
            page = context.new_page()
            page.set_default_timeout(timeout_s * 1000)
            page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
            page.goto(url)
            if source == "local":
                page.get_by_text("Open local file", exact=True).click()
            # The file is open when its topics are listed in the data-source sidebar (open
            # at start). Foxglove then logs a DataCloneError: it cannot keep the picker's
            # stand-in file handle among its recent files (IndexedDB); that is all it costs.
            page.get_by_text(ready_topic, exact=True).first.wait_for()
            # Foxglove's own list of problems with the data source must be empty.
            page.get_by_role("tab", name="Problems").click()
            problems = page.get_by_text("No problems found")
            try:
                problems.wait_for(timeout=5000)
            except Exception:  # noqa: BLE001  (the sidebar's text says what is wrong)
                errors.append("Foxglove's Problems list: "
                              + page.locator("body").inner_text()[:2000])
            # Import the layout: Layouts sidebar > Import layout.
            page.get_by_title("Layouts", exact=True).first.click()
            page.get_by_label("Import layout").click()
            page.get_by_text(LAYOUT_NAME, exact=True).first.wait_for()
            page.get_by_text(ready_title).first.wait_for()
            # Close the sidebar (a second click on its icon), dismiss the 3D panel's tip.
            page.get_by_title("Layouts", exact=True).first.click()
            dismiss = page.get_by_label("Dismiss")
            if dismiss.count():
                dismiss.first.click()
            if live is None:
                # Seek: a click on the playback scrubber at the fraction `at` of the recording.
                scrubber = page.locator('div[style*="height: 32px"]').last
                box = scrubber.bounding_box()
                if box is None:
                    raise SystemExit("Foxglove's playback scrubber was not found")
                page.mouse.click(box["x"] + at * box["width"], box["y"] + box["height"] / 2)
                page.mouse.move(box["x"] + box["width"] / 2, box["y"] - 200)
            else:
                for record in relay_log.records:
                    print(f"FoxgloveStream relay: {record.getMessage()}")
                if not any("offered foxglove.websocket.v1:" in r.getMessage()
                           for r in relay_log.records):
                    errors.append("Foxglove Studio did not connect offering only "
                                  "foxglove.websocket.v1")
            # Let the 3D panel load the URDF and the plots load the file, then the picture.
            time.sleep(settle_s)
            if errors:
                raise SystemExit("Foxglove reported:\n" + "\n".join(errors))
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
            browser.close()
    finally:
        httpd.shutdown()
        if live is not None:
            live.stop()


def main(argv: list[str] | None = None) -> int:
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--recording", choices=tuple(RECORDINGS), default="track",
                        help="what the file is: a tracked motion (default) or a replayed "
                             "teleop session; sets the defaults of --layout and --out")
    parser.add_argument("--mcap", type=Path,
                        help="the MCAP file (default: made here, see --recording)")
    parser.add_argument("--layout", type=Path,
                        help="Foxglove layout (default: docs/foxglove_layout.json, or "
                             "docs/foxglove_teleop_layout.json for --recording teleop)")
    parser.add_argument("--out", type=Path,
                        help="the PNG (default: docs/figures/foxglove_track.png, or "
                             "docs/figures/foxglove_teleop.png for --recording teleop)")
    parser.add_argument("--source", choices=("local", "remote", "live"), default="local",
                        help="Open local file (default), the remote-file deep link, or a "
                             "Foxglove WebSocket connection to a live FoxgloveStream")
    parser.add_argument("--at", type=float, default=0.45,
                        help="where to seek, as a fraction of the recording (0.45)")
    parser.add_argument("--size", type=int, nargs=2, default=(1600, 900),
                        metavar=("WIDTH", "HEIGHT"))
    parser.add_argument("--timeout", type=float, default=60.0, help="per step, s (60)")
    parser.add_argument("--settle", type=float, default=20.0,
                        help="wait after the seek, s (20: the plots load the file in blocks)")
    args = parser.parse_args(argv)
    if not 0.0 <= args.at <= 1.0:
        parser.error(f"--at must lie in [0, 1], got {args.at}")
    if args.source == "live" and args.mcap is not None:
        parser.error("--mcap is for the sources local and remote")
    if args.source == "live" and args.recording != "track":
        parser.error("--source live streams a tracked pose: no --recording teleop")
    layout, out, ready_topic = RECORDINGS[args.recording]
    args.layout = args.layout if args.layout is not None else REPO / layout
    args.out = args.out if args.out is not None else REPO / out
    make = make_teleop_session if args.recording == "teleop" else make_recording
    with tempfile.TemporaryDirectory() as tmp:
        mcap = (None if args.source == "live" else
                args.mcap if args.mcap is not None else make(Path(tmp)))
        screenshot(mcap, args.layout, args.out, source=args.source, at=args.at,
                   ready_topic=ready_topic,
                   width=args.size[0], height=args.size[1], timeout_s=args.timeout,
                   settle_s=args.settle)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
