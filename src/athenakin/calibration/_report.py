"""Figures and the written report of a calibration (matplotlib imported on demand)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._figstyle import MICRO_M
from .._output import check_output_path, write_text_atomic
from .._validation import check_axes, check_instance, check_text
from ._accuracy import TipErrorMap, tip_error_map
from ._model import PARAMETER_UNITS
from ._solve import CalibrationResult

__all__ = ["plot_residuals", "plot_parameter_confidence", "plot_tip_error_map", "write_report"]

_UM = 1e6


def _pyplot() -> Any:
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ModuleNotFoundError as exc:  # pragma: no cover - depends on the install
        raise ModuleNotFoundError("calibration figures need matplotlib: pip install "
                                  "'athenakin[calibration]'", name="matplotlib") from exc
    return plt


def _axes(ax: Any, *, figsize: tuple[float, float] = (7, 4), **kw: Any) -> Any:
    """``ax`` checked (None or an Axes), or a new figure's axes (``plt.subplots`` keywords)."""
    check_axes(ax)
    if ax is not None:
        return ax
    plt = _pyplot()
    _, ax = plt.subplots(figsize=figsize, **kw)
    return ax


def plot_residuals(result: CalibrationResult, *, ax: Any = None) -> Any:
    """Tip residual per row (norm, µm) before and after calibration; outliers marked.

    Parameters
    ----------
    result : CalibrationResult
    ax : matplotlib.axes.Axes, optional, keyword-only
        Axes to draw into (default: a new figure).

    Returns
    -------
    matplotlib.axes.Axes
    """
    check_instance(result, "result", CalibrationResult)
    ax = _axes(ax)
    rows = np.arange(result.excluded.size)
    b = np.linalg.norm(result.residuals_before[:, :3], axis=1) * _UM
    a = np.linalg.norm(result.residuals_after[:, :3], axis=1) * _UM
    ax.plot(rows, b, "o", ms=3, color="0.6",
            label=f"before (RMS {result.rms_before * _UM:.1f} {MICRO_M})")
    ax.plot(rows, a, "o", ms=3, color="C0",
            label=f"after (RMS {result.rms_after * _UM:.1f} {MICRO_M})")
    if np.any(result.outliers):
        ax.plot(rows[result.outliers], a[result.outliers], "x", color="C3", ms=8,
                label="flagged outlier")
    ax.set_yscale("log")
    ax.set_xlabel("measurement row")
    ax.set_ylabel(f"|tip residual| ({MICRO_M})")
    ax.set_title("Residuals before and after calibration", pad=24)
    # above the axes, in one row: the points fill the whole plot
    ax.legend(fontsize=8, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3,
              frameon=False, borderaxespad=0.2)
    return ax


def plot_parameter_confidence(result: CalibrationResult, *, ax: Any = None) -> Any:
    """Change of each estimated parameter from nominal with its 3-sigma interval.

    Lengths in µm, registration angles in µrad.

    Parameters
    ----------
    result : CalibrationResult
    ax : matplotlib.axes.Axes, optional, keyword-only
        Axes to draw into (default: a new figure).

    Returns
    -------
    matplotlib.axes.Axes
    """
    check_instance(result, "result", CalibrationResult)
    ax = _axes(ax)
    delta = (result.estimates - result.nominal) * _UM
    err = 3 * result.std * _UM
    y = np.arange(len(result.names))
    ax.errorbar(delta, y, xerr=err, fmt="o", color="C0", capsize=3)
    ax.axvline(0.0, color="0.5", lw=0.8)
    ax.set_yticks(y)
    ax.set_yticklabels([f"{n} ({'µrad' if PARAMETER_UNITS[n] == 'rad' else MICRO_M})"
                        for n in result.names], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel(f"estimate − nominal ({MICRO_M} or µrad), bars: ±3σ")
    ax.set_title("Parameter estimates and confidence")
    return ax


def plot_tip_error_map(m: TipErrorMap, *, ax: Any = None) -> Any:
    """Expected RMS tip error (µm) over the instrument cone, as a polar chart.

    The angle of the chart is the azimuth of the instrument direction about ``z_e`` (deg),
    its radius the polar angle of the direction from ``z_e`` (deg); both axes are named on
    the chart. The title gives the tip depth and, when the map includes it, the encoder
    resolution (a map without encoder noise says "calibration only").

    Parameters
    ----------
    m : TipErrorMap
        From :func:`tip_error_map`.
    ax : matplotlib.axes.Axes, optional, keyword-only
        Polar axes to draw into (default: a new figure with polar axes).

    Returns
    -------
    matplotlib.axes.Axes
    """
    check_instance(m, "m", TipErrorMap)
    ax = _axes(ax, figsize=(6.4, 5.6), subplot_kw={"projection": "polar"},
               layout="constrained")
    A, B = np.meshgrid(m.azimuth, np.degrees(m.polar), indexing="ij")
    pc = ax.pcolormesh(A, B, np.ma.masked_invalid(m.rms * _UM), shading="nearest",
                       cmap="viridis")
    ax.figure.colorbar(pc, ax=ax, pad=0.12, label=f"expected RMS tip error ({MICRO_M})")
    ax.set_xticks(np.radians(np.arange(0, 360, 45)))
    ax.set_xticklabels([f"{a}°" for a in range(0, 360, 45)], fontsize=8)
    ax.set_rlim(0.0, 180.0)
    ax.set_rticks([45.0, 90.0, 135.0, 180.0])
    ax.set_yticklabels(["45°", "90°", "135°", "180°"], fontsize=7, color="0.3")
    ax.set_rlabel_position(247.5)
    # the axis names: the angle is the azimuth, the radius the polar angle
    ax.set_xlabel("angle: azimuth of the direction about z_e\n"
                  "radius: polar angle of the direction from z_e", fontsize=8)
    source = (f"encoders {m.encoder_resolution * _UM:g} {MICRO_M}"
              if m.encoder_resolution > 0 else "calibration only, no encoder noise")
    ax.set_title(f"Expected tip error over the instrument cone\n(tip {m.depth * 1e3:.0f} mm "
                 f"beyond the RCM; {source})", fontsize=9)
    return ax


def write_report(result: CalibrationResult, path: str | Path, *, figures: bool = True,
                 encoder_resolution: float = 0.0, title: str = "athenakin calibration report"
                 ) -> list[Path]:
    """Write a Markdown (``.md``) or HTML (``.html``) report with PNG figures next to it.

    Parameters
    ----------
    result : CalibrationResult
    path : str or Path
        The report file; figures are ``<stem>_residuals.png``, ``<stem>_parameters.png``,
        ``<stem>_tip_error.png``.
    figures : bool, keyword-only
    encoder_resolution : float, keyword-only
        For the tip-error map, m.
    title : str, keyword-only

    Returns
    -------
    list of Path
        The files written (report first).
    """
    check_instance(result, "result", CalibrationResult)
    path = check_output_path(path)
    check_text(title, "title", max_length=1000)
    out = [path]
    lines = [f"# {title}", "",
             f"Measurements in the **{result.frame}** frame; "
             f"{int(result.excluded.size)} rows, {int(np.sum(result.excluded))} excluded, "
             f"{int(np.sum(result.outliers))} flagged as outliers.", "",
             f"RMS tip residual: **{result.rms_before * _UM:.2f} {MICRO_M}** before, "
             f"**{result.rms_after * _UM:.2f} {MICRO_M}** after; noise estimate sigma = "
             f"{result.sigma * _UM:.2f} {MICRO_M} per coordinate.", "",
             f"Identifiability: {len(result.names)} parameters, condition "
             f"{result.identifiability.condition:.3g} (scaled columns).", "",
             "| parameter | nominal | estimate | change | std (1 sigma) |",
             "|---|---:|---:|---:|---:|"]
    for n, a, b, s in zip(result.names, result.nominal, result.estimates, result.std, strict=True):
        u, f = ("µrad", 1e6) if PARAMETER_UNITS[n] == "rad" else (MICRO_M, 1e6)
        lines.append(f"| {n} | {a:.9g} | {b:.9g} | {(b - a) * f:+.2f} {u} | {s * f:.2f} {u} |")
    lines += ["", f"Actuator offsets (q_true = q_reading + offset): "
              f"{np.array2string(result.q_offset * _UM, precision=2)} {MICRO_M}.",
              f"RCM point: {np.array2string(result.rcm, precision=6)} m."]
    if result.T_t_b is not None:
        lines.append("Tracker registration T_t_b: `" + np.array2string(
            result.T_t_b, precision=6).replace("\n", " ") + "`.")
    if np.any(result.excluded):
        lines += ["", "Excluded rows: " + result.check.describe(limit=20) + "."]
    if np.any(result.outliers):
        lines += ["", "Outlier rows: " + ", ".join(str(i) for i in
                                                   np.flatnonzero(result.outliers)) + "."]
    if figures:
        plt = _pyplot()
        stem = path.with_suffix("")
        for suffix, fn in (("residuals", lambda: plot_residuals(result)),
                           ("parameters", lambda: plot_parameter_confidence(result)),
                           ("tip_error", lambda: plot_tip_error_map(tip_error_map(
                               result, encoder_resolution=encoder_resolution)))):
            ax = fn()
            fig = ax.figure
            if fig.get_layout_engine() is None:
                fig.tight_layout()
            png = Path(f"{stem}_{suffix}.png")
            fig.savefig(png, dpi=110)
            plt.close(fig)
            out.append(png)
            lines += ["", f"![{suffix}]({png.name})"]
    text = "\n".join(lines) + "\n"
    write_text_atomic(path, _html(text, title) if path.suffix.lower() in (".html", ".htm")
                      else text)
    return out


def _html(markdown: str, title: str) -> str:
    """The report's own Markdown (headings, paragraphs, one table, images) as HTML."""
    import html
    import re

    def inline(t: str) -> str:
        t = html.escape(t)
        t = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", t)
        return re.sub(r"`(.+?)`", r"<code>\1</code>", t)

    body: list[str] = []
    rows: list[str] = []
    for ln in markdown.splitlines() + [""]:
        if ln.startswith("|"):
            if not set(ln) <= set("|-: "):
                rows.append(ln)
            continue
        if rows:
            cells = [[c.strip() for c in r.strip("|").split("|")] for r in rows]
            head = "".join(f"<th>{inline(c)}</th>" for c in cells[0])
            tr = "".join("<tr>" + "".join(f"<td>{inline(c)}</td>" for c in r) + "</tr>"
                         for r in cells[1:])
            body.append(f"<table><tr>{head}</tr>{tr}</table>")
            rows = []
        m = re.match(r"!\[(.*)\]\((.*)\)", ln)
        if ln.startswith("# "):
            body.append(f"<h1>{inline(ln[2:])}</h1>")
        elif m:
            body.append(f'<p><img alt="{html.escape(m[1])}" src="{html.escape(m[2])}"></p>')
        elif ln.strip():
            body.append(f"<p>{inline(ln)}</p>")
    style = ("body{font-family:sans-serif;max-width:60em;margin:2em auto}"
             "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 8px;"
             "text-align:right}img{max-width:100%}")
    return (f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>{html.escape(title)}"
            f"</title><style>{style}</style></head><body>\n" + "\n".join(body)
            + "\n</body></html>\n")
