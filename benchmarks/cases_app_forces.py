"""Benchmark cases of the app's actuator-force layer (issue 21 item 6, app/_forces.py).

Group ``app-forces``: what showing the actuator forces adds to one update of the live
page. Baseline: the whole server-side update (``AthenaApp.set_q``) with the layer's
checkbox off; against it the same update with the forces on and a 10 N tip force (the
statics of the drawn slot with the RCM load, the arrow, the handle and the read-out),
and ``forces_view`` alone (the statics and the limits, no viser). Each case alternates
between two configurations so that nothing is skipped as unchanged.
"""

import atexit
import importlib.util

import numpy as np
from cases_app import Q_A, Q_B, _alternate  # the same two poses, alternated, as the app group

from athenakin.app import app_setup, forward_view
from athenakin.app._forces import forces_view

TIP_FORCE_N = np.array([6.0, 0.0, -8.0])


def cases(quick: bool) -> list[dict]:
    if importlib.util.find_spec("viser") is None:
        return []
    from athenakin.app import AthenaApp

    be = "numba" if importlib.util.find_spec("numba") is not None else "numpy"
    s = app_setup(backend=be)
    geometries = [forward_view(s, q).geometry for q in (Q_A, Q_B)]
    off = AthenaApp(port=0, backend=be)
    off.forces.checkbox.value = False
    atexit.register(off.stop)
    on = AthenaApp(port=0, backend=be, f_max=40.0)
    on.forces.set_tip_force(TIP_FORCE_N)
    atexit.register(on.stop)
    state = {"k": 0}

    def pure():
        state["k"] ^= 1
        return forces_view(geometries[state["k"]], tip_force=TIP_FORCE_N, f_max=40.0)

    return [
        {"name": f"AthenaApp.set_q, forces off ({be})", "group": "app-forces", "batch": 1,
         "baseline": True, "call": _alternate(off.set_q)},
        {"name": f"AthenaApp.set_q, forces on, 10 N at the tip ({be})",
         "group": "app-forces", "batch": 1, "call": _alternate(on.set_q),
         "note": "x base < 1: the share of the update the forces add"},
        {"name": "forces_view alone (statics + RCM load, numpy)", "group": "app-forces",
         "batch": 1, "call": pure},
    ]
