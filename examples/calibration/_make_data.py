"""Regenerate measurements.csv and truth.toml of this folder (synthetic, seeded).

The "real" robot is the reference design with every length and the tool length moved by
N(0, 0.5 mm), actuator zero offsets N(0, 0.3 mm), measured at the 80 D-optimal poses of
``athenakin calibrate --plan 80 --params default offsets`` by a registered tracker with
20 um noise per coordinate; two rows carry a 2 mm gross error and one a missed reading.
"""

from pathlib import Path

import numpy as np

import athenakin as ak
from athenakin import calibration as cal

HERE = Path(__file__).resolve().parent

d = ak.Design.default()
T = ak.default_rcm_frame(d)
plan = cal.plan_poses(80, T, d, params=["default", "offsets"], rng=0)
data = cal.synthetic_measurements(T, d, q=plan.q, rng=2026, options=cal.SyntheticOptions(
    noise=20e-6, offset_std=3e-4, outlier_fraction=2 / 80, outlier_size=2e-3))
tips = data.tips.copy()
tips[17] = np.nan   # the tracker lost the marker on this pose
(HERE / "measurements.csv").write_text(cal.measurements_csv_text(
    data.q, tips, comment="synthetic: see _make_data.py (truth in truth.toml)"))
truth = data.true_design.to_toml() + "\n[truth]\n" + "\n".join(
    f"{k} = {v!r}" for k, v in data.true_parameters.items() if not k.startswith("reg_")) + (
    "\noutlier_rows = " + str(np.flatnonzero(data.outliers).tolist()) + "\n")
(HERE / "truth.toml").write_text(truth)
print("wrote measurements.csv and truth.toml")
