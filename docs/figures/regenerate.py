"""Write the figures of docs/figures that come from athenakin's plotting functions.

Run from the repository root: ``python docs/figures/regenerate.py [NAME ...]``
(default: all of them). Names: robot_reference, conditioning, instrument_cone,
robot_solids, instrument_cone_collisions; ``collision_numbers`` prints the numbers of
docs/motion.md section 7.
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin.analysis import figures as F  # noqa: E402

OUT = Path(__file__).resolve().parent
D = ak.Design.default()
T = ak.default_rcm_frame(D)


def robot_reference() -> None:
    """README: ``athenakin view -o robot.png`` (reference configuration, slot 0)."""
    from athenakin.plot import save_view

    save_view(OUT / "robot_reference.png", dpi=120)


def conditioning() -> None:
    """docs/singularities.md, Figure 3."""
    from athenakin.analysis import actuator_map, point_workspace, tool_tip_workspace

    fig = F.figure_conditioning(actuator_map(D, resolution=161),
                                point_workspace(D, resolution=81),
                                tool_tip_workspace(T, D, resolution=81))
    fig.savefig(OUT / "conditioning.png", dpi=80)
    plt.close(fig)


def instrument_cone() -> None:
    """docs/singularities.md, Figure 4."""
    from athenakin.analysis import instrument_cone as cone

    fig = F.figure_instrument_cone(cone(T, D), reference_q=ak.robot.REFERENCE_Q)
    fig.savefig(OUT / "instrument_cone.png", dpi=80)
    plt.close(fig)


def robot_solids() -> None:
    """docs/visualization.md: the bodies as capsules, the closest pair coloured (issue 20)."""
    from athenakin.plot import plot_robot

    ax = plot_robot(bodies=True)
    ax.figure.savefig(OUT / "robot_solids.png", dpi=100)
    plt.close(ax.figure)


def instrument_cone_collisions() -> None:
    """docs/motion.md, section 7: the cone with the directions a collision blocks."""
    from athenakin.analysis import instrument_cone as cone

    fig = F.figure_instrument_cone(cone(T, D, clearance_margin=0.0),
                                   reference_q=ak.robot.REFERENCE_Q)
    fig.savefig(OUT / "instrument_cone_collisions.png", dpi=80)
    plt.close(fig)


def collision_numbers() -> None:
    """docs/motion.md, section 7: the numbers quoted there (printed, no figure)."""
    import collections

    import numpy as np

    from athenakin.analysis import instrument_cone as cone
    from athenakin.analysis import workspace_summary
    from athenakin.analysis._collision import labelled_clearance
    from athenakin.collision import Bodies

    ic = cone(T, D, clearance_margin=0.0)
    for k, v in workspace_summary(ic=ic).items():
        if "solid angle" in k:
            print(f"{k}: {v:.3f}")
    A, P, Pp = np.meshgrid(ic.azimuth, ic.polar, ic.p, indexing="ij")
    bad = ic.reachable & ~ic.collision_free
    d_e = ak.direction_from_angles(A[bad], P[bad])
    q, res = ak.q_from_instrument(T, d_e, Pp[bad], D, errors="flag")
    _, pair = labelled_clearance(q, T, D, res.mode, Pp[bad] < 0, bodies=Bodies.default(D),
                                 environment=None)
    share = collections.Counter(f"{a}/{b}" for a, b in pair)
    print(f"colliding (direction, insertion) samples: {bad.sum()} of {ic.reachable.sum()}")
    for name, n in share.most_common(6):
        print(f"  closest pair {name}: {n}")


if __name__ == "__main__":
    names = sys.argv[1:] or ["robot_reference", "conditioning", "instrument_cone",
                             "robot_solids", "instrument_cone_collisions"]
    for name in names:
        globals()[name]()
        if name != "collision_numbers":
            print(f"wrote {OUT / name}.png")
