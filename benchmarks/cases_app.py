"""Benchmark cases of athenakin.app: the server-side latency of one update of the live page.

Group ``app-update`` (target: under 5 ms per update, so that a dragged slider keeps up):

* ``forward_view`` (numba kernels): actuator values -> the 16 slots with their reasons,
  the robot's geometry (plot/_geometry.py), the read-outs (singularity distances,
  Jacobian conditioning). The pure layer of one q-slider move.
* the same with the numpy reference kernels, and with all valid slots ghosted;
* ``inverse_step`` + ``forward_view``: one move of the tip handle / IK sliders (48 IK
  samples on the segment from the last tip, then the view);
* ``AthenaApp.set_q``: the whole server-side update, the pure layer plus the viser
  scene and GUI messages (a server on a free loopback port, no browser connected), with
  one slot and with all valid slots ghosted.

Baseline: the core 16-solution forward kinematics of one q (numpy), what any update
needs at least. Each case alternates between two configurations so that nothing is
skipped as unchanged.

Group ``app-ghosts`` (what ghosting the other valid slots costs; 15 ghosts at these q):
the whole update with all valid slots ghosted against the whole one-slot update
(``AthenaApp.set_q``, the baseline). Group ``app-ghost-scene``: the ghosts' geometry and
scene alone (from the FK to the line sets), batched over the slots (``slot_ghosts`` +
``ghost_scene``) against one slot at a time (``robot_geometry`` + ``robot_scene`` per
ghost, the app's first implementation, kept here as the baseline).
"""

import atexit
import importlib.util

import numpy as np

import athenakin as ak
from athenakin.app import app_setup, forward_view, ghost_scene, inverse_step, slot_ghosts
from athenakin.app._scene import robot_scene
from athenakin.plot import robot_geometry

Q_A = np.array([-0.100, 0.100, 0.450])
Q_B = np.array([-0.105, 0.098, 0.452])


def _alternate(f):
    state = {"k": 0}

    def call():
        state["k"] ^= 1
        return f(Q_B if state["k"] else Q_A)
    return call


def cases(quick: bool) -> list[dict]:
    has_numba = importlib.util.find_spec("numba") is not None
    be = "numba" if has_numba else "numpy"
    s = app_setup(backend=be)
    s_np = app_setup(backend="numpy")
    T, d = s.T_b_e, s.design
    r = forward_view(s, Q_A).readouts
    tips = [r.tip_e, r.tip_e + np.array([0.0, 0.01, 0.005])]

    def ik_move():
        state = {"k": 0, "q": r.q}

        def call():
            a, b = tips[state["k"]], tips[1 - state["k"]]
            state["k"] ^= 1
            st = inverse_step(s, a, b, state["q"], r.mode)
            state["q"] = st.q
            return forward_view(s, st.q)
        return call

    out = [
        {"name": "core forward_kinematics of one q (16 slots, numpy)", "group": "app-update",
         "batch": 1, "baseline": True,
         "call": _alternate(lambda q: ak.forward_kinematics(q, T, d, errors="flag",
                                                          backend="numpy"))},
        {"name": f"forward_view, one slot ({be})", "group": "app-update", "batch": 1,
         "call": _alternate(lambda q: forward_view(s, q)),
         "note": "pure layer of a q-slider move; target < 5 ms"},
        {"name": "forward_view, one slot (numpy)", "group": "app-update", "batch": 1,
         "call": _alternate(lambda q: forward_view(s_np, q))},
        {"name": f"forward_view, all valid slots ghosted ({be})", "group": "app-update",
         "batch": 1, "call": _alternate(lambda q: forward_view(s, q, slot="all"))},
        {"name": f"inverse_step (48 IK samples) + forward_view ({be})", "group": "app-update",
         "batch": 1, "call": ik_move(), "note": "a tip-handle / IK-slider move"},
    ]
    def ghosts_batched(q):
        sol = ak.forward_kinematics(q, T, d, errors="flag", backend=be)
        k = np.flatnonzero(sol.valid)
        solid = robot_geometry(q, T, d, slot=int(k[0]), fk=sol)
        return ghost_scene(slot_ghosts(sol, q, T, d, k[1:]), solid)

    def ghosts_loop(q):
        sol = ak.forward_kinematics(q, T, d, errors="flag", backend=be)
        k = np.flatnonzero(sol.valid)
        robot_geometry(q, T, d, slot=int(k[0]), fk=sol)
        return [robot_scene(robot_geometry(q, T, d, slot=int(j), fk=sol), frames=False,
                            labels=False) for j in k[1:]]

    out += [
        {"name": f"ghosts' geometry + scene, one slot at a time ({be})",
         "group": "app-ghost-scene", "batch": 1, "baseline": True,
         "call": _alternate(ghosts_loop), "note": "the first implementation"},
        {"name": f"ghosts' geometry + scene, batched over the slots ({be})",
         "group": "app-ghost-scene", "batch": 1, "call": _alternate(ghosts_batched)},
    ]
    if importlib.util.find_spec("viser") is not None:
        from athenakin.app import AthenaApp

        app = AthenaApp(port=0, backend=be)
        atexit.register(app.stop)
        out.append({"name": f"AthenaApp.set_q: view + viser messages ({be})",
                    "group": "app-update", "batch": 1, "call": _alternate(app.set_q),
                    "note": "whole server-side update; target < 5 ms"})
        ghosted = AthenaApp(port=0, backend=be)
        ghosted.slot = "all"
        atexit.register(ghosted.stop)
        out.append({"name": f"AthenaApp.set_q, all valid slots ghosted ({be})",
                    "group": "app-update", "batch": 1, "call": _alternate(ghosted.set_q),
                    "note": "target < 5 ms"})
        out += [
            {"name": f"AthenaApp.set_q, one slot ({be})", "group": "app-ghosts", "batch": 1,
             "baseline": True, "call": _alternate(app.set_q)},
            {"name": f"AthenaApp.set_q, all valid slots ghosted ({be})",
             "group": "app-ghosts", "batch": 1, "call": _alternate(ghosted.set_q),
             "note": "x base: the one-slot update's time / this one's"},
        ]
    return out
