"""Write the figures of docs/figures that come from athenakin's plotting functions.

Run from the repository root: ``python docs/figures/regenerate.py [NAME ...]``
(default: all of them). Names: robot_reference, conditioning, instrument_cone.
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


if __name__ == "__main__":
    names = sys.argv[1:] or ["robot_reference", "conditioning", "instrument_cone"]
    for name in names:
        globals()[name]()
        print(f"wrote {OUT / name}.png")
