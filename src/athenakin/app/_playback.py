"""A recorded trajectory played back in the app (Playback)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from .._typing import FloatArray
from .._validation import check_instance, check_scalar


@dataclasses.dataclass(frozen=True)
class Playback:
    """A trajectory to play back.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times, s (``0, 1, 2, ...`` when the file has no ``t_s`` column).
    q : ndarray, shape (N, 3)
        Actuators, m (a missing reading repeats the previous one).
    source : str
    """

    t: FloatArray
    q: FloatArray
    source: str

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]``, s."""
        return float(self.t[-1] - self.t[0])


def load_playback(path: str | Path) -> Playback:
    """Read a trajectory CSV (as written by ``athenakin plan``) for playback.

    Parameters
    ----------
    path : str or Path
        CSV with columns ``q1_m, q2_m, q3_m`` and optionally ``t_s``
        (:func:`athenakin.motion.read_q_stream_csv`).

    Returns
    -------
    Playback

    Raises
    ------
    PathFileError
        The file cannot be read, misses a column, has a non-number (the message names
        the line and column), times that do not increase, or no rows.
    """
    from ..motion._errors import PathFileError
    from ..motion._io import read_q_stream_csv

    try:
        q, t = read_q_stream_csv(path)
    except OSError as exc:
        raise PathFileError(f"{path}: cannot read the file ({exc.strerror or exc})") from exc
    if t is None:
        t = np.arange(len(q), dtype=float)
    if not np.all(np.isfinite(t)):
        k = int(np.flatnonzero(~np.isfinite(t))[0])
        raise PathFileError(f"{path}: data row {k + 1}: t_s is missing or not finite")
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise PathFileError(f"{path}: data row {k + 2}: t_s = {t[k + 1]} does not increase "
                            f"(previous {t[k]})")
    q = q.copy()
    if len(q) and not np.all(np.isfinite(q[0])):
        raise PathFileError(f"{path}: data row 1: q is missing or not finite (a playback "
                            f"starts from a full reading)")
    for i in range(1, len(q)):                      # hold the last reading where one is missing
        if not np.all(np.isfinite(q[i])):
            q[i] = q[i - 1]
    return Playback(t=np.asarray(t, dtype=float), q=q, source=str(path))


def playback_q(pb: Playback, t: float) -> tuple[FloatArray, int]:
    """Actuators at time ``t`` of a playback: the last sample at or before ``t``.

    Parameters
    ----------
    pb : Playback
    t : float
        Time, s (before the first sample: the first one).

    Returns
    -------
    q : ndarray, shape (3,)
        Actuators ``(q1, q2, q3)``, m (a copy).
    index : int
        Sample index (clipped to the recording).
    """
    check_instance(pb, "pb", Playback)
    t = check_scalar(t, "t")
    k = int(np.clip(np.searchsorted(pb.t, t, side="right") - 1, 0, len(pb.t) - 1))
    return pb.q[k].copy(), k
