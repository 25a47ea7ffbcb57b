"""Design and measure the tremor filters of athenakin.teleop (docs/teleop.md, "The tremor filter").

    python scripts/design_tremor_filter.py            # the table of docs/teleop.md
    python scripts/design_tremor_filter.py --design   # refine notch8-12-lp15 (about a minute)

``--design`` runs the search that gave :data:`athenakin.teleop.TREMOR_NOTCH_LOWPASS`:
scipy ``SLSQP`` over seven analog biquads ``(f_zero, zeta_zero, f_pole, zeta_pole)``
(each of unit DC gain, digital by the bilinear transform at 1 kHz pre-warped at 10 Hz, as
``_filter._digital``), minimising the largest gain subject to the specification below,
from ``START`` (the result of earlier runs of the same search from the three notches of
``notch8-12`` plus three low-pass biquads). It prints the biquads rounded to 4 digits.
Without ``--design`` it measures every named filter on dense grids: the numbers of the
table in docs/teleop.md.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from athenakin.teleop import TREMOR_FILTERS, filter_response
from athenakin.teleop._filter import PREWARP_HZ

RATE = 1000.0
#: The specification of the search (margins over the tested bounds of tests/test_teleop.py).
BAND_DB, HF15_DB, HF30_DB, DELAY_S, GAIN_TOL, MIN_ZETA_POLE = 21.6, 12.1, 20.1, 0.0085, 0.025, 0.15
START = ((8.1339, 0.02, 1.6189, 0.15), (9.2567, 0.1145, 7.4346, 0.15),
         (11.8147, 0.0689, 7.4123, 0.15), (1.5714, 0.1649, 3.9029, 0.7452),
         (5.651, 1.165, 12.6366, 0.15), (30.4005, 0.1188, 26.9445, 0.15),
         (59.9657, 1.0387, 38.4101, 1.452))
F_LOW = np.geomspace(0.01, 1.0, 25)


def _response(x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Digital response of the biquads ``x`` (flat, 4 per biquad) at ``f`` Hz."""
    wc = 2 * math.pi * PREWARP_HZ
    K = wc / math.tan(wc / (2 * RATE))
    z1 = np.exp(-2j * np.pi * f / RATE)
    s = K * (1 - z1) / (1 + z1)
    h = np.ones_like(z1)
    for fz, zz, fp, zp in x.reshape(-1, 4):
        wz, wp = 2 * np.pi * fz, 2 * np.pi * fp
        h = h * ((s * s + 2 * zz * wz * s + wz * wz) / (s * s + 2 * zp * wp * s + wp * wp)
                 * (wp * wp / (wz * wz)))
    return h


def _delays(h_of, f: np.ndarray, df: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """Phase delay and group delay (s) at ``f`` of the response function ``h_of``."""
    phase = -np.angle(h_of(f)) / (2 * np.pi * f)
    group = -np.angle(h_of(f + df) / h_of(f - df)) / (2 * np.pi * 2 * df)
    return phase, group


def design() -> None:
    """Run the search from ``START``; print the biquads of ``TREMOR_NOTCH_LOWPASS``."""
    from scipy.optimize import minimize

    f_band = np.linspace(8.0, 12.0, 81)
    f15 = np.geomspace(15.0, RATE / 2 * 0.999, 120)
    f30 = np.geomspace(30.0, RATE / 2 * 0.999, 100)
    f_all = np.geomspace(0.01, RATE / 2 * 0.999, 600)

    def db(h: np.ndarray) -> np.ndarray:
        return 20 * np.log10(np.abs(h))

    def constraints(y: np.ndarray) -> np.ndarray:
        x, t = y[:-1], y[-1]
        phase, group = _delays(lambda f: _response(x, f), F_LOW)
        gain = np.abs(_response(x, F_LOW))
        return np.concatenate([t - db(_response(x, f_all)), -BAND_DB - db(_response(x, f_band)),
                               -HF15_DB - db(_response(x, f15)), -HF30_DB - db(_response(x, f30)),
                               (DELAY_S - phase) * 1e3, (DELAY_S - group) * 1e3, phase * 1e3,
                               group * 1e3, (GAIN_TOL - np.abs(gain - 1)) * 100])

    x0 = np.array(START, dtype=float).ravel()
    y0 = np.append(x0, db(_response(x0, f_all)).max())
    bounds = [(1.0, 200.0), (0.0, 2.0), (1.0, 200.0), (MIN_ZETA_POLE, 2.0)] * len(START)
    r = minimize(lambda y: y[-1], y0, method="SLSQP", bounds=bounds + [(-5.0, 30.0)],
                 constraints=[{"type": "ineq", "fun": constraints}],
                 options={"maxiter": 500, "ftol": 1e-9})
    print(f"SLSQP: {r.message}; largest gain {r.x[-1]:.2f} dB")
    for b in np.round(r.x[:-1].reshape(-1, 4), 4):
        print("    (" + ", ".join(f"{v:g}" for v in b) + "),")


def table() -> None:
    """Print the table of docs/teleop.md: every named filter measured on dense grids."""
    f_band = np.linspace(8.0, 12.0, 4001)
    f_hi = np.geomspace(15.0, RATE / 2 * 0.999, 20000)
    f_all = np.geomspace(0.01, RATE / 2 * 0.999, 20000)
    f_low = np.geomspace(0.01, 1.0, 400)
    print("| | " + " | ".join(f"`{n}`" for n in TREMOR_FILTERS if n != "none") + " |")
    print("|---|" + "---|" * (len(TREMOR_FILTERS) - 1))
    rows: dict[str, list[str]] = {k: [] for k in ("band", "hf15", "hf30", "phase", "group",
                                                  "gain1", "max")}
    for name in TREMOR_FILTERS:
        if name == "none":
            continue

        def h_of(f: np.ndarray, name: str = name) -> np.ndarray:
            return filter_response(name, RATE, f)

        def att(f: np.ndarray) -> float:
            return float(-20 * np.log10(np.abs(h_of(f))).max())

        phase, group = _delays(h_of, f_low)
        g_all = 20 * np.log10(np.abs(h_of(f_all)))
        rows["band"].append(f">= {att(f_band):.1f} dB")
        rows["hf15"].append(f">= {att(f_hi):.1f} dB")
        rows["hf30"].append(f">= {att(f_hi[f_hi >= 30.0]):.1f} dB")
        rows["phase"].append(f"{phase.min() * 1e3:.1f} - {phase.max() * 1e3:.1f} ms")
        rows["group"].append(f"{group.min() * 1e3:.1f} - {group.max() * 1e3:.1f} ms")
        rows["gain1"].append(f"within {np.abs(np.abs(h_of(f_low)) - 1).max() * 100:.1f} % of 1")
        rows["max"].append(f"+{g_all.max():.1f} dB at {f_all[g_all.argmax()]:.1f} Hz")
    names = {"band": "attenuation, 8-12 Hz", "hf15": "attenuation above 15 Hz",
             "hf30": "attenuation above 30 Hz", "phase": "phase delay, 0.01-1 Hz",
             "group": "group delay, 0.01-1 Hz", "gain1": "gain, 0.01-1 Hz",
             "max": "largest gain"}
    for k, cells in rows.items():
        print(f"| {names[k]} | " + " | ".join(cells) + " |")


def main() -> None:
    """Parse the command line; the table, or the search with ``--design``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", action="store_true", help="refine notch8-12-lp15")
    if ap.parse_args().design:
        design()
    else:
        table()


if __name__ == "__main__":
    main()
