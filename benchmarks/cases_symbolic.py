"""Benchmark cases of athenakin.symbolic: the algebraic FK solver against the closed form.

Group ``fk-algebraic``: all 16 forward-kinematics solutions per pose, by the closed-form
solver (:func:`athenakin.forward_kinematics`, baseline) and by the solver generated from the
paper's derivation (:func:`athenakin.symbolic.forward_kinematics_algebraic`: quadratic in p,
SVD of the 4x4 skew matrix, U-joint and wrist quadrics). Also the serial part alone
(8 solutions from the Study vector of ``T_s_e``), and one item at a time (call overhead).
"""

import numpy as np

import athenakin as ak
from athenakin.symbolic import forward_kinematics_algebraic, serial_solutions_algebraic
from athenakin.testing import random_configurations


def cases(quick: bool) -> list[dict]:
    d = ak.Design.default()
    n = 2_000 if quick else 100_000
    rc = random_configurations(n, d, rng=11)
    q, T = rc.q, rc.T_b_e
    f = ak.study.study_from_transform(np.linalg.solve(rc.T_b_s, rc.T_b_e))
    Tse = np.linalg.solve(rc.T_b_s, rc.T_b_e)
    forward_kinematics_algebraic(q[:2], T[:2], d)     # load the generated module once
    return [
        {"name": "forward_kinematics (closed form)", "group": "fk-algebraic", "batch": n,
         "baseline": True, "call": lambda: ak.forward_kinematics(q, T, d)},
        {"name": "forward_kinematics_algebraic (paper's route)", "group": "fk-algebraic",
         "batch": n, "call": lambda: forward_kinematics_algebraic(q, T, d),
         "note": "generated from the cached sympy derivation"},
        {"name": "serial chain, closed form (ups_solutions)", "group": "fk-algebraic-serial",
         "batch": n, "baseline": True, "call": lambda: ak.chain.ups_solutions(Tse)},
        {"name": "serial chain, algebraic (serial_solutions_algebraic)",
         "group": "fk-algebraic-serial", "batch": n,
         "call": lambda: serial_solutions_algebraic(f),
         "note": "no closure check (ups_solutions includes one)"},
        {"name": "forward_kinematics, one pose", "group": "fk-algebraic-single", "batch": 1,
         "baseline": True, "call": lambda: ak.forward_kinematics(q[0], T[0], d)},
        {"name": "forward_kinematics_algebraic, one pose", "group": "fk-algebraic-single",
         "batch": 1, "call": lambda: forward_kinematics_algebraic(q[0], T[0], d)},
    ]
