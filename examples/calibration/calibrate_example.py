"""Calibrate the example data set and compare with the truth it was generated from.

``measurements.csv`` holds 80 poses of a robot whose lengths, tool length and actuator
zero offsets differ from the reference design by fractions of a millimetre (the truth is
in ``truth.toml``; ``_make_data.py`` regenerates both). The tracker noise is 20 um; two
rows carry a 2 mm gross error and one a missed reading. The same as::

    athenakin calibrate examples/calibration/measurements.csv -o calibrated.toml \\
        --params default offsets --loss soft_l1
"""

import sys
import warnings
from pathlib import Path

import numpy as np

import athenakin as ak
from athenakin import calibration as cal

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

HERE = Path(__file__).resolve().parent

design = ak.Design.default()
T_b_e = ak.default_rcm_frame(design)
data = cal.read_measurements_csv(HERE / "measurements.csv")
print(f"{len(data.q)} rows read")

# 1. identifiability of the chosen parameters from these poses, before solving
ok = np.all(np.isfinite(data.tips), axis=1)
report = cal.identifiability(data.q[ok], T_b_e, design, params=["default", "offsets"])
print(report.summary())

# 2. calibrate with a robust loss: bad rows excluded, outliers flagged
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always", cal.CalibrationWarning)
    res = cal.calibrate(data.q, data.tips, T_b_e, design, params=["default", "offsets"],
                        options=cal.CalibrationOptions(loss="soft_l1"))
for w in caught:
    print("warning:", w.message)

truth = tomllib.loads((HERE / "truth.toml").read_text())["truth"]
print(f"{'parameter':>12} {'estimate':>14} {'std (um)':>9} {'error (um)':>10} {'z':>6}")
for name, _, est, std in res.table():
    err = est - truth[name]
    print(f"{name:>12} {est:14.9f} {std * 1e6:9.2f} {err * 1e6:10.2f} {err / std:6.2f}")
print(f"RMS tip residual {res.rms_before * 1e6:.1f} um -> {res.rms_after * 1e6:.1f} um; "
      f"outlier rows {np.flatnonzero(res.outliers).tolist()} "
      f"(true: {truth['outlier_rows']})")

# 3. how accurate is the calibrated robot? (10 um encoders)
m = cal.tip_error_map(res, resolution=(36, 19), encoder_resolution=10e-6)
print(f"expected RMS tip error over the reachable cone: {np.nanmin(m.rms) * 1e6:.1f} .. "
      f"{np.nanmax(m.rms) * 1e6:.1f} um at {m.depth * 1e3:.0f} mm depth")
Path("calibrated.toml").write_text(cal.calibration_toml(res))
assert ak.Design.from_toml("calibrated.toml") == res.design
