"""The tremor filter: a named causal filter for the master's position (private).

Physiological tremor lies at 8-12 Hz; a surgeon's intended motion below about 2 Hz.
The issue asks for >= 20 dB at 8-12 Hz *and* <= 10 ms delay below 1 Hz. A plain
low-pass cannot do both: a critically damped second-order low-pass with 20 dB at
8 Hz (corner 2.7 Hz) delays slow motion by ``2 / omega_c = 119 ms``. Bode's
gain-phase relation bounds every minimum-phase filter: the delay at DC is
``(2 / pi) * integral of -ln|H(j w)| / w^2 dw``, about 9.7 ms for a brick wall of
exactly 20 dB over 8-12 Hz and no other change of gain. A realisable stop band has
skirts, which cost more delay; the only way under 10 ms is a little gain above 1
where it costs least, between the motion band and the tremor band.

:data:`TREMOR_NOTCH` is such a filter: three notches (zeros on the imaginary
axis at 8.18, 9.86, 11.80 Hz) and one low-frequency shelf biquad that lends phase
lead, each normalised to unit gain at DC. Its parameters were found by a global
search (scipy ``differential_evolution``) minimising the largest gain subject to
>= 21 dB over 8-12 Hz and a delay <= 7.5 ms at 0.05 and 0.5 Hz. Digital, at
1 kHz (bilinear transform), measured by ``tests/test_teleop.py``: >= 21 dB at
8-12 Hz, 7.5 ms phase delay at 0.5 Hz, largest gain +1.2 dB at 3.5 Hz, gain
within 3 % of 1 below 1 Hz.

A notch passes what lies above the tremor band (sensor noise, a handle's vibration;
``"notch8-12"`` keeps +1.1 dB there). Attenuation above the band costs delay too, the
more the lower it starts (``(2 / pi) * 1.38 / (2 pi 15 Hz) = 9.3 ms`` for 12 dB from
15 Hz up), so a roll-off needs more gain between the bands to stay under 10 ms:
:data:`TREMOR_NOTCH_LOWPASS` (``"notch8-12-lp15"``) is seven biquads found by
``scripts/design_tremor_filter.py --design`` (scipy ``SLSQP``, minimising the largest
gain subject to >= 21.6 dB over 8-12 Hz, >= 12.1 dB from 15 Hz and >= 20.1 dB from 30 Hz
up, phase and group delay in [0, 8.5] ms and gain within 2.5 % of 1 from 0.01 to 1 Hz,
every pole damped at least 0.15). Digital at 1 kHz (the script's table): >= 21.6 dB at
8-12 Hz, >= 12.1 dB above 15 Hz, >= 20.1 dB above 30 Hz, phase delay 7.6-8.4 ms and
group delay 0-8.4 ms below 1 Hz, largest gain +2.7 dB at 5.9 Hz (the price of the
roll-off; ``"notch8-12"`` stays the default). ``"none"`` passes the position through.

Each biquad runs in transposed direct form II on plain floats, three axes, no
allocation; :meth:`TremorFilter.reset` sets the state to the steady state of a
constant input (no transient on start, on a jump or on a clutch).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["TREMOR_FILTERS", "TREMOR_NOTCH", "TREMOR_NOTCH_LOWPASS", "TremorFilter",
           "filter_response"]

#: The analog prototype of ``"notch8-12"``: biquads ``(f_zero Hz, zeta_zero, f_pole Hz,
#: zeta_pole)``, each ``(s^2 + 2 zz wz s + wz^2) / (s^2 + 2 zp wp s + wp^2) * wp^2 / wz^2``.
TREMOR_NOTCH: tuple[tuple[float, float, float, float], ...] = (
    (8.1751, 0.0305, 7.4055, 0.2048),
    (9.8575, 0.0370, 10.9606, 0.3152),
    (11.7958, 0.0124, 12.7320, 0.2118),
    (5.8326, 1.2633, 5.6408, 0.9820),
)

#: The analog prototype of ``"notch8-12-lp15"``, biquads as in :data:`TREMOR_NOTCH`: the
#: tremor band and a roll-off above it (>= 12 dB from 15 Hz, >= 20 dB from 30 Hz).
TREMOR_NOTCH_LOWPASS: tuple[tuple[float, float, float, float], ...] = (
    (8.1504, 0.0125, 1.4925, 0.15),
    (9.3622, 0.0773, 7.5142, 0.15),
    (11.6395, 0.0522, 7.5502, 0.1587),
    (1.4502, 0.1513, 2.1388, 0.6811),
    (1.9487, 0.7668, 11.9494, 0.15),
    (30.3844, 0.1087, 27.4978, 0.15),
    (62.7047, 0.9387, 25.2695, 2.0),
)

#: Filters by name: the analog biquads of each (empty: no filtering).
TREMOR_FILTERS: dict[str, tuple[tuple[float, float, float, float], ...]] = {
    "notch8-12": TREMOR_NOTCH,
    "notch8-12-lp15": TREMOR_NOTCH_LOWPASS,
    "none": (),
}

#: Frequency at which the bilinear transform is pre-warped (the tremor band's centre), Hz.
PREWARP_HZ = 10.0
#: Least rate for a filter with a stop band at 12 Hz (Nyquist well above it), Hz: the
#: least that :func:`filter_response` takes.
MIN_FILTER_RATE = 100.0
#: Least rate (Hz) at which each filter keeps its band, >= 20 dB over 8-12 Hz (the
#: bilinear transform warps the band as the rate falls: ``"notch8-12"`` 20.9 dB at
#: 150 Hz, 19.6 dB at 100 Hz; ``"notch8-12-lp15"`` 20.4 dB at 200 Hz, 19.5 dB at 150 Hz;
#: tests/test_teleop_loop.py): :class:`TremorFilter`, and so the teleoperation loop,
#: refuses a lower rate.
BAND_RATES: dict[str, float] = {"notch8-12": 150.0, "notch8-12-lp15": 200.0, "none": 0.0}
#: Least attenuation over the tremor band that :data:`BAND_RATES` keeps, dB.
BAND_DB = 20.0
#: Highest cycle rate (Hz) of the teleoperation loop and the simulated arm: 100 kHz, far
#: above any servo (the dVRK's arms run at 1.5 kHz); a higher one is a typing error (its
#: cycle of under 10 µs would make every difference quotient rounding noise).
MAX_RATE = 100_000.0


def check_rate(rate: object, name: str = "rate") -> float:
    """A cycle rate (Hz) in ``(0, MAX_RATE]``, as a float; else a named error.

    Raises
    ------
    TypeError, InvalidInputError
        Not a real number, not finite, not positive, or above :data:`MAX_RATE`.
    """
    from .._validation import check_scalar
    from ..errors import InvalidInputError

    r = check_scalar(rate, name, positive=True)
    if r > MAX_RATE:
        raise InvalidInputError(f"{name}: expected a cycle rate of at most {MAX_RATE:g} Hz, "
                                f"got {r:g}")
    return r


def _check_name(name: object) -> str:
    """A key of :data:`TREMOR_FILTERS`, else a named error."""
    from .._validation import check_choice

    return check_choice(name, "name", tuple(TREMOR_FILTERS))


def _check_filter_rate(name: str, rate: object) -> float:
    """The sample rate of filter ``name``, checked.

    :func:`check_rate`, and at least :data:`MIN_FILTER_RATE` for a filter with a stop band
    (the tremor band below Nyquist).
    """
    r = check_rate(rate)
    if TREMOR_FILTERS[name] and r < MIN_FILTER_RATE:
        from ..errors import InvalidInputError

        raise InvalidInputError(f"rate: the tremor filter {name!r} needs rate >= "
                                f"{MIN_FILTER_RATE:g} Hz, got {r:g}")
    return r


def _check_band_rate(name: str, rate: object) -> float:
    """The rate of a running filter ``name``: at least :data:`BAND_RATES` ``[name]``."""
    r = _check_filter_rate(name, rate)
    least = BAND_RATES[name]
    if r < least:
        from ..errors import InvalidInputError

        raise InvalidInputError(f"rate: the tremor filter {name!r} keeps >= {BAND_DB:g} dB "
                                f"over 8-12 Hz only at rate >= {least:g} Hz, got {r:g}; raise "
                                f"the rate or choose filter='none'")
    return r


def _digital(name: str, rate: float) -> tuple[tuple[float, float, float, float, float], ...]:
    """``(b0, b1, b2, a1, a2)`` per biquad (``a0 = 1``) of filter ``name`` at ``rate`` Hz."""
    if not TREMOR_FILTERS[name]:        # "none": no biquad, any rate
        return ()
    wc = 2.0 * math.pi * PREWARP_HZ
    K = wc / math.tan(wc / (2.0 * rate))
    out = []
    for fz, zz, fp, zp in TREMOR_FILTERS[name]:
        wz, wp = 2.0 * math.pi * fz, 2.0 * math.pi * fp
        g = wp * wp / (wz * wz)
        # analog (B2 s^2 + B1 s + B0) / (s^2 + A1 s + A0), s = K (1 - z^-1) / (1 + z^-1)
        B2, B1, B0 = g, g * 2.0 * zz * wz, g * wz * wz
        A1, A0 = 2.0 * zp * wp, wp * wp
        KK = K * K
        a0 = KK + A1 * K + A0
        b0 = (B2 * KK + B1 * K + B0) / a0
        b1 = (2.0 * B0 - 2.0 * B2 * KK) / a0
        b2 = (B2 * KK - B1 * K + B0) / a0
        a1 = (2.0 * A0 - 2.0 * KK) / a0
        a2 = (KK - A1 * K + A0) / a0
        out.append((b0, b1, b2, a1, a2))
    return tuple(out)


def filter_response(name: str, rate: float, f_hz: ArrayLike) -> NDArray[np.complex128]:
    """Frequency response of the digital filter ``name`` at ``rate`` Hz.

    Parameters
    ----------
    name : str
        A key of :data:`TREMOR_FILTERS`.
    rate : float
        Sample rate, Hz.
    f_hz : array-like, shape (...)
        Frequencies, Hz (below ``rate / 2``).

    Returns
    -------
    ndarray of complex, shape (...)
        ``H(exp(j 2 pi f / rate))``; gain ``abs``, phase delay ``-angle / (2 pi f)`` (s).
    """
    name = _check_name(name)
    rate = _check_filter_rate(name, rate)
    from .._validation import check_array

    f = check_array(f_hz, "f_hz", ())
    if np.any((f < 0) | (f >= 0.5 * rate)):
        from ..errors import InvalidInputError

        raise InvalidInputError(f"f_hz: expected frequencies in [0, rate / 2) = [0, "
                                f"{0.5 * rate:g}) Hz")
    z1 = np.exp(-2j * np.pi * f / rate)   # z^-1
    h = np.ones_like(z1)
    for b0, b1, b2, a1, a2 in _digital(name, rate):
        h = h * (b0 + b1 * z1 + b2 * z1 * z1) / (1.0 + a1 * z1 + a2 * z1 * z1)
    return h


class TremorFilter:
    """A named causal filter of a 3-vector stream (one sample per cycle), no allocation.

    Parameters
    ----------
    name : str
        A key of :data:`TREMOR_FILTERS` (``"notch8-12"``, ``"notch8-12-lp15"`` or
        ``"none"``).
    rate : float
        Sample rate, Hz, at least :data:`BAND_RATES` ``[name]`` (the rate at which the
        filter keeps >= 20 dB over 8-12 Hz; any rate for ``"none"``).

    Raises
    ------
    InvalidInputError
        An unknown ``name``; a ``rate`` below the filter's band rate.
    """

    def __init__(self, name: str, rate: float) -> None:
        self.name = _check_name(name)
        self.rate = _check_band_rate(self.name, rate)
        self._c = _digital(name, rate)
        # two states per biquad and axis, flat: axis-major, then biquad (s1, s2)
        self._s = [0.0] * (6 * len(self._c))

    def reset(self, x: float, y: float, z: float) -> None:
        """Set the state to the steady state of the constant input ``(x, y, z)``.

        Parameters
        ----------
        x, y, z : float
            The constant input (master position, m) whose steady state the filter takes.
        """
        s = self._s
        i = 0
        for v in (x, y, z):
            for _b0, b1, b2, a1, a2 in self._c:
                # unit DC gain: output v for input v; s2 = b2 v - a2 v, s1 = s2 + b1 v - a1 v
                s[i + 1] = (b2 - a2) * v
                s[i] = s[i + 1] + (b1 - a1) * v
                i += 2

    def __call__(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        """Filter one sample (m); returns the filtered sample (m)."""
        c = self._c
        if not c:
            return x, y, z
        s, n = self._s, 2 * len(c)
        return _cascade(c, s, 0, x), _cascade(c, s, n, y), _cascade(c, s, 2 * n, z)


def _cascade(c: tuple[tuple[float, float, float, float, float], ...], s: list[float], i: int,
             v: float) -> float:
    """One axis through the biquads ``c``, states ``s[i:i + 2 len(c)]`` (updated); the output."""
    for b0, b1, b2, a1, a2 in c:
        w = b0 * v + s[i]
        s[i] = b1 * v - a1 * w + s[i + 1]
        s[i + 1] = b2 * v - a2 * w
        v = w
        i += 2
    return v
