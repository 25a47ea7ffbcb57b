"""Benchmark cases of athenakin.calibration: solving and planning.

Groups:

* ``calibration-solve``: one :func:`athenakin.calibration.calibrate` call on 200 synthetic
  poses (20 um noise), batch = poses. Target: under 1 s per call on one core. Baseline:
  the bare least-squares solve by scipy with a finite-difference Jacobian
  (``jac="2-point"``); next to it the bare solve with the analytic Jacobian, then the
  full ``calibrate`` (row checks, identifiability SVD, solve, covariance, residuals).
* ``calibration-plan``: D-optimal choice of 30 poses among 2000 candidates (batch =
  candidates).
"""

from scipy.optimize import least_squares

import athenakin as ak
from athenakin import calibration as cal
from athenakin.calibration._solve import _setup


def _solve_only(data, T, d, params, jac):
    _, prob, _, _, _, _ = _setup(data.q, data.tips, T, d, params=params, frame="base",
                                 axes=None, mode=1, q_offset=None, registration=None,
                                 axis_weight=cal.DEFAULT_AXIS_WEIGHT, bad_rows="exclude",
                                 max_bad_fraction=0.1)
    x0 = prob.theta0[prob.free]

    def call():
        return least_squares(prob.residual, x0, jac=prob.jacobian if jac else "2-point",
                             method="trf", x_scale="jac",
                             ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=200)
    return call


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    n = 200
    noise = cal.SyntheticOptions(noise=20e-6)
    offsets = cal.SyntheticOptions(noise=20e-6, offset_std=3e-4)
    plain = cal.synthetic_measurements(T, d, n=n, rng=1, options=noise)
    base = cal.synthetic_measurements(T, d, n=n, rng=1, options=offsets)
    tracker = cal.synthetic_measurements(
        T, d, n=n, frame="tracker", rng=2, options=cal.SyntheticOptions(
            noise=20e-6, offset_std=3e-4, true={"q1_offset": 0.0, "q2_offset": 0.0}))
    off = ["default", "offsets"]
    m = 300 if quick else 2000
    return [
        {"name": "scipy least_squares, finite-difference Jacobian (l1..l5, L)",
         "group": "calibration-solve", "batch": n, "baseline": True,
         "call": _solve_only(plain, T, d, None, False)},
        {"name": "scipy least_squares, analytic Jacobian (l1..l5, L), solve only",
         "group": "calibration-solve", "batch": n,
         "call": _solve_only(plain, T, d, None, True)},
        {"name": "calibrate (checks, identifiability, solve, covariance; l1..l5, L)",
         "group": "calibration-solve",
         "batch": n, "call": lambda: cal.calibrate(plain.q, plain.tips, T, d),
         "note": "target < 1 s per call"},
        {"name": "calibrate + offsets + RCM (12 parameters)", "group": "calibration-solve",
         "batch": n, "call": lambda: cal.calibrate(base.q, base.tips, T, d,
                                                    params=off + ["rcm"])},
        {"name": "calibrate, tracker frame (+q3 offset, registration: 13 parameters)",
         "group": "calibration-solve", "batch": n,
         "call": lambda: cal.calibrate(tracker.q, tracker.tips, T, d, frame="tracker",
                                       params=["default", "q3_offset"])},
        {"name": "calibrate, soft_l1 robust loss (l1..l5, L, offsets)",
         "group": "calibration-solve", "batch": n,
         "call": lambda: cal.calibrate(base.q, base.tips, T, d, params=off,
                                       options=cal.CalibrationOptions(loss="soft_l1"))},
        {"name": "plan_poses 30 of the candidates (l1..l5, L, offsets)",
         "group": "calibration-plan", "batch": m, "baseline": True,
         "call": lambda: cal.plan_poses(30, T, d, params=off, n_candidates=m, rng=3)},
    ]
