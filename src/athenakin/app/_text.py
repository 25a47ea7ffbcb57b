"""The read-outs and the slot list as small HTML tables (pure; the page shows them as they are).

Every value cell carries ``data-ro="<name>"`` (``q1``, ``p``, ``u3``, ``tip_e_x``,
``mode``, ``d_wrist``, ``cond_tool_tip``, ...) so that scripts and tests can read the
page; cells in the warning colour also carry ``data-warn="1"``.
"""

from __future__ import annotations

import html
import math

import numpy as np

from .._validation import check_choice, check_instance
from ._model import AppView, Readouts, SlotStatus

__all__ = ["WARN_COLOR", "ERROR_COLOR", "readouts_html", "slots_html", "message_html",
           "view_html"]

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


def _row(label: str, key: str, value: str, warn: bool = False, title: str = "") -> str:
    style = f"text-align:right;{f'color:{WARN_COLOR};font-weight:bold' if warn else ''}"
    flag = ' data-warn="1"' if warn else ""
    tip = f' title="{html.escape(title)}"' if title else ""
    return (f"<tr{tip}><td>{html.escape(label)}</td>"
            f'<td data-ro="{key}"{flag} style="{style}">{value}</td></tr>')


def readouts_html(r: Readouts) -> str:
    """The read-outs of one configuration as an HTML table (``r`` a :class:`Readouts`).

    Lengths in mm, angles in degrees; distances to the singular sets in mm (or as a
    sine), in :data:`WARN_COLOR` within the warning distance.

    Parameters
    ----------
    r : Readouts

    Returns
    -------
    str
    """
    check_instance(r, "r", Readouts)
    rows = [_row(f"q{i + 1} [mm]", f"q{i + 1}", _num(v, 1e3)) for i, v in enumerate(r.q)]
    rows.append(_row("p [mm]", "p", _num(r.p, 1e3)))
    rows += [_row(f"u{i + 1} [deg]", f"u{i + 1}", _num(math.degrees(v)))
             for i, v in enumerate(r.u)]
    rows += [_row(f"tip {a} (E) [mm]", f"tip_e_{a}", _num(v, 1e3))
             for a, v in zip("xyz", r.tip_e, strict=True)]
    rows += [_row(f"tip {a} (base) [mm]", f"tip_b_{a}", _num(v, 1e3))
             for a, v in zip("xyz", r.tip_b, strict=True)]
    rows.append(_row("slot / assembly mode", "mode", f"{r.slot} / {r.mode:+d}"))
    out = [_TABLE, *rows, "</table>", "<b>Distance to the singular sets</b>", _TABLE]
    for d in r.distances:
        val = _num(d.value, 1e3) + " mm" if d.unit == "m" else _num(d.value, 1.0, 3)
        out.append(_row(d.name, f"d_{d.name}", val, d.near, d.meaning))
    out += ["</table>", "<b>Conditioning (2-norm)</b>", _TABLE]
    names = {"parallel_condition": ("cond dO_s/dq", "cond_parallel"),
             "tool_tip_condition": ("cond dtip/dq", "cond_tool_tip")}
    for k, v in r.conditioning.items():
        label, key = names.get(k, (k, k))
        out.append(_row(label, key, _num(v, 1.0, 1), r.conditioning_warn.get(k, False)))
    out.append("</table>")
    return "".join(out)


def slots_html(slots: tuple[SlotStatus, ...], shown: int | None) -> str:
    """The 16 slots: valid ones plain (the one drawn in bold), invalid ones greyed with why.

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
    """``(status, read-outs, slots)`` HTML of a view (read-outs empty without a solution)."""
    check_instance(view, "view", AppView)
    ro = readouts_html(view.readouts) if view.readouts is not None else ""
    shown = view.geometry.slot if view.geometry is not None else None
    return message_html(view.message, view.level), ro, slots_html(view.slots, shown)
