"""The read-outs and the slot list as small HTML tables (pure; the page shows them as they are).

Every value cell carries ``data-ro="<name>"`` (``q1``, ``p``, ``u3``, ``tip_e_x``,
``mode``, ``d_wrist``, ``cond_tool_tip``, ...) so that scripts and tests can read the
page; joint and tip cells also carry their full-precision SI value in ``data-v``, and
cells in the warning colour carry ``data-warn="1"``.
"""

from __future__ import annotations

import html
import math

import numpy as np

from .._validation import check_choice, check_instance
from ._model import WARN_DISTANCE_M, WARN_SINE, AppView, Readouts, SlotStatus

__all__ = ["WARN_COLOR", "ERROR_COLOR", "SINGULAR_NAMES", "readouts_html", "slots_html",
           "message_html", "view_html"]

#: Colour of a read-out near a singular set (and of warnings).
WARN_COLOR = "#d35400"
#: Colour of an error message.
ERROR_COLOR = "#c0392b"

_TABLE = '<table style="font-size:0.8em;border-collapse:collapse;width:100%">'


def _num(x: float, scale: float = 1.0, nd: int = 2) -> str:
    if math.isnan(x):
        return "-"
    if math.isinf(x):
        return "inf"
    text = f"{x * scale:.{nd}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def _cell(key: str, value: str, warn: bool = False, exact: float | None = None) -> str:
    style = f"text-align:right;{f'color:{WARN_COLOR};font-weight:bold' if warn else ''}"
    flag = ' data-warn="1"' if warn else ""
    v = f' data-v="{exact!r}"' if exact is not None else ""
    return f'<td data-ro="{key}"{flag}{v} style="{style}">{value}</td>'


def _row(label: str, key: str, value: str, warn: bool = False, title: str = "") -> str:
    tip = f' title="{html.escape(title)}"' if title else ""
    return f"<tr{tip}><td>{html.escape(label)}</td>{_cell(key, value, warn)}</tr>"


def _multi_row(label: str, cells: list[str]) -> str:
    return f"<tr><td>{html.escape(label)}</td>{''.join(cells)}</tr>"


#: Plain name of each singular set (key of :data:`athenakin.analysis.CONDITIONS`) as shown
#: in the read-outs, and how its distance is shown: ``"mm"`` (a length) or ``"deg"`` (a
#: sine shown as the angle ``asin`` of it, so the warning threshold ``WARN_SINE`` reads 5 deg).
SINGULAR_NAMES: dict[str, tuple[str, str]] = {
    "circles_tangent": ("circles k1, k2 tangent (modes meet)", "mm"),
    "d_on_rail": ("links l3 along the rail", "mm"),
    "k1_degenerate": ("circle k1 shrinks to a point", "mm"),
    "ab_coincide": ("carriages A and B meet", "mm"),
    "k2_degenerate": ("circle k2 shrinks to a point (q3 = 0)", "mm"),
    "stroke_limit": ("an actuator at its stroke limit", "mm"),
    "p_zero": ("O_s at the RCM (p = 0)", "mm"),
    "ujoint": ("instrument along z_s (U-joint lock)", "deg"),
    "wrist": ("instrument along z_e (wrist lock)", "deg"),
    "ik_cos_u1": ("paper IK: instrument across the rail", "deg"),
    "ik_sin_u1_sin_u2": ("paper IK: instrument in the rail plane", "deg"),
    "tip_at_rcm": ("tool tip at the RCM (p = L)", "mm"),
}


def _distance_text(value: float, unit: str, shown: str) -> str:
    if shown == "deg" and unit == "1":
        if math.isnan(value):
            return "-"
        return _num(math.degrees(math.asin(min(abs(value), 1.0))), 1.0, 1) + " deg"
    if unit == "m":
        return _num(value, 1e3) + " mm"
    return _num(value, 1.0, 3)


def _legend(warn_mm: float, warn_deg: float) -> str:
    sw = "display:inline-block;width:0.8em;height:0.8em;margin:0 0.3em 0 0.8em;"
    return (f'<div data-ro="legend" style="font-size:0.75em">distance to each singular set:'
            f'<span style="{sw}background:#222222"></span>far'
            f'<span style="{sw}background:{WARN_COLOR}"></span>within {warn_mm:g} mm or '
            f"{warn_deg:g} deg (hover a row for its meaning)</div>")


def readouts_html(r: Readouts) -> str:
    """The read-outs of one configuration as HTML tables.

    Lengths in mm, angles in degrees, each value cell with its full-precision SI value
    in ``data-v`` (m or rad) where it is a joint or tip coordinate. The distances to
    the singular sets under plain names (:data:`SINGULAR_NAMES`), in mm or (for a
    sine) as the angle in degrees, in :data:`WARN_COLOR` within the warning distance,
    with a colour legend; hovering a row shows the set's meaning.

    Parameters
    ----------
    r : Readouts

    Returns
    -------
    str
    """
    check_instance(r, "r", Readouts)
    deg = math.degrees
    mode = f'<td colspan="2" data-ro="mode" style="text-align:right">{r.slot} / {r.mode:+d}</td>'
    rows = [
        _multi_row("q1, q2, q3 [mm]", [_cell(f"q{i + 1}", _num(v, 1e3), exact=float(v))
                                       for i, v in enumerate(r.q)]),
        _multi_row("p [mm], slot / mode", [_cell("p", _num(r.p, 1e3), exact=float(r.p)), mode]),
        _multi_row("u1, u2, u3 [deg]", [_cell(f"u{i + 1}", _num(deg(r.u[i])), exact=float(r.u[i]))
                                        for i in range(3)]),
        _multi_row("u4, u5 [deg]", [_cell(f"u{i + 1}", _num(deg(r.u[i])), exact=float(r.u[i]))
                                    for i in (3, 4)] + ["<td></td>"]),
        _multi_row("tip in E [mm]", [_cell(f"tip_e_{a}", _num(v, 1e3), exact=float(v))
                                     for a, v in zip("xyz", r.tip_e, strict=True)]),
        _multi_row("tip in base [mm]", [_cell(f"tip_b_{a}", _num(v, 1e3), exact=float(v))
                                        for a, v in zip("xyz", r.tip_b, strict=True)]),
    ]
    out = [_TABLE, *rows, "</table>", "<b>Distance to the singular sets</b>",
           _legend(WARN_DISTANCE_M * 1e3, round(math.degrees(math.asin(WARN_SINE)), 6)),
           _TABLE]
    for d in r.distances:
        name, shown = SINGULAR_NAMES.get(d.name, (d.name, "mm" if d.unit == "m" else "1"))
        out.append(_row(name, f"d_{d.name}", _distance_text(d.value, d.unit, shown), d.near,
                        f"{d.name}: {d.meaning}"))
    out += ["</table>", "<b>Conditioning (2-norm condition number)</b>", _TABLE]
    names = {"parallel_condition": ("parallel module, dO_s/dq", "cond_parallel"),
             "tool_tip_condition": ("tool tip, dtip/dq", "cond_tool_tip")}
    for k, v in r.conditioning.items():
        label, key = names.get(k, (k, k))
        out.append(_row(label, key, _num(v, 1.0, 1), r.conditioning_warn.get(k, False)))
    out.append("</table>")
    return "".join(out)


def slots_html(slots: tuple[SlotStatus, ...], shown: int | None) -> str:
    """The 16 slots: valid ones plain (the one drawn in bold), invalid ones greyed with why.

    Parameters
    ----------
    slots : tuple of SlotStatus
        From :func:`slot_statuses`.
    shown : int or None
        Slot drawn in the 3-D view (bold), None for none.

    Returns
    -------
    str
        An HTML ``<table>``, one row per slot.

    Raises
    ------
    TypeError
        ``slots`` is not a sequence of :class:`SlotStatus`, or ``shown`` not an int or None.
    """
    if not isinstance(slots, (tuple, list)) or not all(isinstance(x, SlotStatus) for x in slots):
        raise TypeError(f"slots: expected a tuple of SlotStatus, got {type(slots).__name__}")
    if shown is not None and (isinstance(shown, bool) or not isinstance(shown, (int, np.integer))):
        raise TypeError(f"shown: expected an int or None, got {type(shown).__name__}")
    out = [_TABLE]
    for s in slots:
        if s.valid:
            weight = "font-weight:bold;" if s.slot == shown else ""
            out.append(f'<tr data-slot="{s.slot}" data-valid="1"><td style="{weight}">'
                       f"{html.escape(s.label)}</td></tr>")
        else:
            out.append(f'<tr data-slot="{s.slot}" data-valid="0" title="{html.escape(s.why)}">'
                       f'<td style="color:#999999">{html.escape(s.label)}: '
                       f"{html.escape(s.why.split(':')[0])}</td></tr>")
    out.append("</table>")
    return "".join(out)


def message_html(text: str, level: str) -> str:
    """A status line: ``level`` ``"ok"`` (plain), ``"warn"`` or ``"error"`` (coloured).

    Parameters
    ----------
    text : str
        The message (HTML-escaped; empty shows ``"ok"``).
    level : {"ok", "warn", "error"}

    Returns
    -------
    str
        One ``<div data-ro="status">`` element.

    Raises
    ------
    TypeError
        ``text`` is not a str.
    ValueError
        ``level`` is not ``"ok"``, ``"warn"`` or ``"error"``.
    """
    if not isinstance(text, str):
        raise TypeError(f"text: expected str, got {type(text).__name__}")
    check_choice(level, "level", ("ok", "warn", "error"))
    color = {"warn": WARN_COLOR, "error": ERROR_COLOR}.get(level)
    style = f' style="color:{color};font-weight:bold"' if color else ""
    return f'<div data-ro="status" data-level="{level}"{style}>{html.escape(text) or "ok"}</div>'


def view_html(view: AppView) -> tuple[str, str, str]:
    """``(status, read-outs, slots)`` HTML of a view (read-outs empty without a solution).

    Parameters
    ----------
    view : AppView

    Returns
    -------
    status, readouts, slots : str
        :func:`message_html`, :func:`readouts_html` (``""`` without a solution) and
        :func:`slots_html` of the view.
    """
    check_instance(view, "view", AppView)
    ro = readouts_html(view.readouts) if view.readouts is not None else ""
    shown = view.geometry.slot if view.geometry is not None else None
    return message_html(view.message, view.level), ro, slots_html(view.slots, shown)
