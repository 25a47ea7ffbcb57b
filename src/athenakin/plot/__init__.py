"""Views of ATHENA: static 3-D figures, interactive HTML, the 16-solution grid, animations.

matplotlib, plotly, imageio and tqdm (extra ``plot``) are imported only when a
function that needs them runs.

* :func:`robot_geometry`: where every part is in one FK solution (numpy only).
* :func:`plot_robot` (its drawing options :class:`PlotOptions`), :func:`plot_fk_solutions`,
  :func:`save_view`: matplotlib.
* :func:`robot_figure`, :func:`write_html`: interactive plotly page.
* :func:`setup_figure`, :func:`write_setup_html`: a planned set-up as a plotly page: the
  patient, the target's coverage map, the port and the robot at covered targets.
* :func:`animate`, :func:`instrument_cone_path`: GIF / MP4 of a motion.
* :func:`draw_bodies`, :func:`capsule_surface`: the bodies as shaded capsules, the
  pair with the least clearance coloured (``plot_robot(..., bodies=True)``).
"""

from ._animate import animate, instrument_cone_path, render_frames
from ._geometry import (
    COLORS,
    N_CIRCLE,
    RobotGeometry,
    arc_points,
    circle_points,
    robot_geometry,
    slot_label,
)
from ._html import robot_figure, write_html
from ._mpl import PlotOptions, plot_fk_solutions, plot_robot, save_view
from ._setup_view import setup_figure, target_coverage, write_setup_html
from ._solids import capsule_surface, draw_bodies

__all__ = [
    "COLORS",
    "N_CIRCLE",
    "PlotOptions",
    "RobotGeometry",
    "animate",
    "arc_points",
    "capsule_surface",
    "circle_points",
    "draw_bodies",
    "instrument_cone_path",
    "plot_fk_solutions",
    "plot_robot",
    "render_frames",
    "robot_figure",
    "robot_geometry",
    "save_view",
    "setup_figure",
    "slot_label",
    "target_coverage",
    "write_html",
    "write_setup_html",
]
