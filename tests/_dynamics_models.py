"""Mass models for the dynamics tests (shared by test_dynamics and test_dynamics_pinocchio)."""

from __future__ import annotations

import numpy as np

from athenakin.dynamics import MassModel


def with_full_inertias(base: MassModel, seed: int) -> MassModel:
    """``base`` with general (non-axisymmetric) inertias and offset centres, seeded.

    Each body gets a random rotation of eigenvalues in [1e-4, 2e-3] kg m^2 that obey the
    triangle inequality, and its centre of mass moved by about 1 cm.
    """
    rng = np.random.default_rng(seed)
    data = base.to_mapping()
    for entry in data.values():
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        ev = np.sort(rng.uniform(1e-4, 2e-3, 3))
        ev[2] = min(ev[2], ev[0] + ev[1])
        entry["inertia"] = (R @ np.diag(ev) @ R.T).tolist()
        entry["com"] = (np.asarray(entry["com"]) + rng.normal(scale=0.01, size=3)).tolist()
    return MassModel.from_mapping(data)
