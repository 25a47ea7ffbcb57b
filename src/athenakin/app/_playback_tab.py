"""The Playback tab of the app (private): a trajectory CSV, a time slider, real-time play.

The trajectory is read by :func:`~athenakin.app.load_playback` and sampled by
:func:`~athenakin.app.playback_q`; the tab moves the app's robot through
``app._apply_q`` under the app's lock, as the other tabs do. A file with bad rows is
reported in the status line and the banner; the app keeps running.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import KinematicsError
from ._page import banner_html
from ._playback import Playback, load_playback, playback_q
from ._setup_tab import _error_text

__all__ = ["PlaybackTab", "PLAY_HZ"]

#: Rate at which *play* moves the time slider, Hz.
PLAY_HZ = 30.0


class PlaybackTab:
    """The Playback tab: load a trajectory, scrub its time, play it in real time.

    Parameters
    ----------
    app : AthenaApp
        The app whose robot the trajectory moves.

    Attributes
    ----------
    playback : Playback or None
        The trajectory loaded.
    path, time, play_button : viser GUI handles
    """

    def __init__(self, app: Any) -> None:
        gui = app.server.gui
        self.app = app
        self.playback: Playback | None = None
        self.path = gui.add_text("trajectory CSV", initial_value="",
                                 hint="written by 'athenakin plan'")
        gui.add_button("load trajectory").on_click(lambda _: self.load(self.path.value))
        self.time = gui.add_slider("time [s]", min=0.0, max=1.0, step=0.001,
                                   initial_value=0.0, disabled=True)
        self.time.on_update(self._on_time)
        self.play_button = gui.add_button("play", disabled=True)
        self.play_button.on_click(lambda _: self.play())

    def _on_time(self, _: object) -> None:
        app = self.app
        with app._lock:
            if app._echo or self.playback is None:
                return
            q, _k = playback_q(self.playback, self.playback.t[0] + self.time.value)
            app._apply_q(q, sync_ik=True)

    def load(self, path: str) -> None:
        """Load a trajectory CSV and show its first sample (a bad file: said in the page).

        Parameters
        ----------
        path : str
            The CSV (``t_s, q1_m, q2_m, q3_m``).
        """
        app = self.app
        try:
            pb = load_playback(path.strip())
        except (OSError, ValueError, KinematicsError) as exc:
            app._set_status(f"trajectory not loaded: {_error_text(exc)}", "error")
            app.errors.append(f"trajectory: {_error_text(exc)}")
            app._banner.content = banner_html(app.setup, app.errors)
            return
        with app._lock:
            self.playback = pb
            with app._echo():
                self.path.value = path
                self.time.max = max(pb.duration, 1e-3)
                self.time.step = float(np.min(np.diff(pb.t))) if len(pb.t) > 1 else 1e-3
                self.time.value = 0.0
                self.time.disabled = False
                self.play_button.disabled = False
        app._apply_q(pb.q[0], sync_ik=True,
                     extra=(f"trajectory {Path(pb.source).name}: {len(pb.t)} samples, "
                            f"{pb.duration:.3f} s", "ok"))

    def play(self) -> None:
        """Play the trajectory in real time from the slider's time (from 0 at its end)."""
        pb = self.playback
        if pb is None:
            return

        def run() -> None:
            t_end = pb.duration
            start = time.perf_counter() - float(self.time.value)
            if self.time.value >= t_end:
                start = time.perf_counter()
            while self.playback is pb:
                t = min(time.perf_counter() - start, t_end)
                self.time.value = float(t)                 # calls _on_time
                if t >= t_end:
                    break
                time.sleep(1 / PLAY_HZ)

        threading.Thread(target=run, daemon=True, name="athenakin-playback").start()

    def stop(self) -> None:
        """Stop playing (the trajectory is dropped)."""
        self.playback = None
