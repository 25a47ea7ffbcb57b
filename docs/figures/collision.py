"""Figures and the finding of docs/collision.md (issue 20), computed here, never typed.

Run from the repository root: ``python docs/figures/collision.py [bodies] [finding]``
(default: both). ``bodies`` draws the capsules of the default bodies at the reference
configuration (collision_bodies.png). ``finding`` samples the strokes and the instrument
cone of the reference design with the default radii, writes collision_workspace.png,
collision_cone.png and collision_finding.json, and rewrites the block between the
``finding`` markers of docs/collision.md with the numbers.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin._mechanism import BODIES, body_segments, mechanism_points  # noqa: E402
from athenakin.collision import Bodies, clearance  # noqa: E402
from athenakin.robot import REFERENCE_Q  # noqa: E402

HERE = Path(__file__).resolve().parent
#: Where the figures go: docs/figures, or ATHENAKIN_FIGURES_OUT (regenerate.py --out); the
#: page docs/collision.md is rewritten only when they go to docs/figures.
OUT = Path(os.environ.get("ATHENAKIN_FIGURES_OUT", HERE))
DOC = HERE.parent / "collision.md"
#: Coarser grids with ATHENAKIN_FIGURES_QUICK=1 (regenerate.py --quick, CI).
QUICK = os.environ.get("ATHENAKIN_FIGURES_QUICK") == "1"
D = ak.Design.default()
T = ak.default_rcm_frame(D)
BODIES_DEFAULT = Bodies.default(D)
GRID = 11 if QUICK else 31      # samples per stroke (31^3 configurations)
CONE = (24, 12, 8) if QUICK else (72, 36, 24)   # azimuth, polar, insertion samples of the cone
COLOURS = {"rail": "#555555", "carriage_a": "#777777", "carriage_b": "#777777",
           "link_a": "#1f4fbf", "link_b": "#1f4fbf", "link_ad": "#4f7fdf", "link_bd": "#4f7fdf",
           "carrier": "#2f9f5f", "actuator": "#f28e0f", "platform": "#8f3fbf",
           "instrument": "#d62728", "sphere_link_1": "#9467bd", "sphere_link_2": "#c5b0d5"}


def _capsule_surface(ax, a, b, r, colour, n=14):
    d = b - a
    L = np.linalg.norm(d)
    z = d / L if L > 0 else np.array([0.0, 0.0, 1.0])
    x = np.cross(z, np.eye(3)[np.argmin(np.abs(z))])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    th = np.linspace(0, 2 * np.pi, n)
    ring = np.cos(th)[:, None] * x + np.sin(th)[:, None] * y
    t = np.array([0.0, 1.0])
    P = a + t[None, :, None] * d + r * ring[:, None, :]
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color=colour, alpha=0.55, linewidth=0)
    ph = np.linspace(0, np.pi / 2, 6)
    for c, s in ((b, z), (a, -z)):
        S = (c + r * (np.cos(ph)[None, :, None] * ring[:, None, :]
                      + np.sin(ph)[None, :, None] * s))
        ax.plot_surface(S[..., 0], S[..., 1], S[..., 2], color=colour, alpha=0.55, linewidth=0)


def _mm_ticks(ax, names=("x", "y", "z")) -> None:
    """Tick labels in mm (the data stay in m), axis labels that say so: as every figure."""
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    fmt = FuncFormatter(lambda v, _pos: f"{v * 1e3:.0f}")
    axes = (ax.xaxis, ax.yaxis, ax.zaxis) if hasattr(ax, "zaxis") else (ax.xaxis, ax.yaxis)
    for axis, name in zip(axes, names, strict=False):
        axis.set_major_locator(MaxNLocator(5))
        axis.set_major_formatter(fmt)
        axis.set_label_text(f"{name} [mm]")


def bodies() -> None:
    """collision_bodies.png: the 13 capsules at the reference configuration, slot 0."""
    from athenakin.plot._mpl import place_labels

    seg = body_segments(mechanism_points(REFERENCE_Q, T, D, slot=0,
                                         geometry=BODIES_DEFAULT.geometry))
    fig = plt.figure(figsize=(8.5, 6.5))
    ax = fig.add_subplot(projection="3d")
    for j, name in enumerate(BODIES):
        a, b = seg[j]
        _capsule_surface(ax, a, b, BODIES_DEFAULT.radius[name], COLOURS[name])
    allp = seg.reshape(-1, 3)
    c = 0.5 * (allp.min(0) + allp.max(0))
    h = 0.5 * (allp.max(0) - allp.min(0)).max()
    ax.set_xlim(c[0] - h, c[0] + h)
    ax.set_ylim(c[1] - h, c[1] + h)
    ax.set_zlim(c[2] - h, c[2] + h)
    ax.set_box_aspect((1, 1, 1))
    _mm_ticks(ax, ("x$_b$", "y$_b$", "z$_b$"))
    ax.view_init(elev=22, azim=-60)
    q_mm = ", ".join(f"{1e3 * x:.0f}" for x in REFERENCE_Q)
    ax.set_title(f"Default bodies (Bodies.default), reference design, q = ({q_mm}) mm, "
                 "FK slot 0", fontsize=9)
    fig.subplots_adjust(left=0.0, right=0.95, bottom=0.04, top=0.94)
    # one label per body at its middle, placed apart (leader lines where it is crowded)
    items = [(name, 0.5 * (seg[j, 0] + seg[j, 1]), "#111111")
             for j, name in enumerate(BODIES)]
    place_labels(ax, items, lines=[s_ for s_ in seg], fontsize=7.5)
    fig.savefig(OUT / "collision_bodies.png", dpi=90)
    plt.close(fig)


def _stroke_grid() -> np.ndarray:
    axes = [np.linspace(D.stroke_min[i], D.stroke_max[i], GRID) for i in range(3)]
    Q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return Q


class _Lean:
    """The fields of a Clearance this script uses, gathered chunk by chunk (no witnesses)."""

    def __init__(self, q: np.ndarray, slot, chunk: int = 1000) -> None:
        parts = [clearance(q[i:i + chunk], T, D, slot=slot, bodies=BODIES_DEFAULT)
                 for i in range(0, len(q), chunk)]
        self.pairs = parts[0].pairs
        for f in ("distances", "valid", "colliding", "closest_pair"):
            setattr(self, f, np.concatenate([getattr(c, f) for c in parts]))


def finding() -> dict:
    """Which pairs collide over the strokes and in the instrument cone; figures and doc block."""
    Q = _stroke_grid()
    res: dict = {"grid": GRID, "n_configurations": len(Q), "radii": dict(BODIES_DEFAULT.radius),
                 "cone": list(CONE)}
    # --- the strokes, all 16 slots ------------------------------------------------------
    c = _Lean(Q, "all")
    pairs = c.pairs
    res["pairs_checked"] = len(pairs)
    per_slot = {}
    for k in range(16):
        v = c.valid[:, k]
        dk = c.distances[v, k]
        per_slot[k] = {"valid": int(v.sum()), "colliding": int(c.colliding[v, k].sum())}
        if k == 0:
            can = np.any(dk < 0, axis=0)
            frac = np.mean(dk < 0, axis=0)
            mp0 = mechanism_points(Q[v], T, D, slot=0)
            p_ins = np.linalg.norm(mp0["O_s"] - mp0["RCM"], axis=-1)
            gap = np.abs(Q[v, 0] - Q[v, 1])

            def rng(x, sel):
                return [float(x[sel].min()), float(x[sel].max())]

            res["slot0_pairs_that_collide"] = sorted(
                [{"pair": list(pairs[i]), "fraction": float(frac[i]),
                  "min_distance": float(dk[:, i].min()),
                  "p_range": rng(p_ins, dk[:, i] < 0), "gap_range": rng(gap, dk[:, i] < 0)}
                 for i in np.flatnonzero(can)], key=lambda x: -x["fraction"])
            res["slot0_p_range"] = rng(p_ins, np.ones(len(p_ins), bool))
            res["slot0_gap_range"] = rng(gap, np.ones(len(gap), bool))
    res["per_slot"] = per_slot
    v_any = c.valid
    can_any = np.any(np.where(v_any[..., None], c.distances, np.inf) < 0, axis=(0, 1))
    res["any_slot_pairs_that_collide"] = [list(pairs[i]) for i in np.flatnonzero(can_any)]
    v0 = c.valid[:, 0]
    res["slot0_valid"] = int(v0.sum())
    res["slot0_collision_free"] = int((v0 & ~c.colliding[:, 0]).sum())
    res["slot0_free_fraction"] = res["slot0_collision_free"] / max(res["slot0_valid"], 1)
    # figure: O_s of slot 0, collision-free or not, and the colliding pairs
    pts = mechanism_points(Q[v0], T, D, slot=0, geometry=BODIES_DEFAULT.geometry)
    Os = pts["O_s"]
    col = c.colliding[v0, 0]
    fig, axs = plt.subplots(1, 3, figsize=(13, 4.2))
    for ax, (i, j, lab) in zip(axs[:2], ((0, 1, "x_b, y_b"), (0, 2, "x_b, z_b")), strict=True):
        ax.scatter(1e3 * Os[~col, i], 1e3 * Os[~col, j], s=2, c="#2f9f5f",
                   label="collision-free")
        ax.scatter(1e3 * Os[col, i], 1e3 * Os[col, j], s=2, c="#d62728", label="colliding",
                   alpha=0.5)
        ax.set_xlabel(f"{lab.split(',')[0]} (mm)")
        ax.set_ylabel(f"{lab.split(',')[1].strip()} (mm)")
        ax.set_aspect("equal")
        ax.set_title(f"O_s over the strokes ({lab}), slot 0", fontsize=9)
    fig.legend(*axs[0].get_legend_handles_labels(), markerscale=5, fontsize=8,
               loc="upper left", ncols=2, frameon=False)   # above the panels, off the data
    top = res["slot0_pairs_that_collide"][:10]
    axs[2].barh([f"{p['pair'][0]} / {p['pair'][1]}" for p in top][::-1],
                [100 * p["fraction"] for p in top][::-1], color="#d62728")
    axs[2].set_xlabel("% of slot-0 configurations where the pair collides")
    axs[2].tick_params(axis="y", labelsize=7)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    fig.savefig(OUT / "collision_workspace.png", dpi=80)
    plt.close(fig)
    # --- the instrument cone (mode +1, p > 0: FK slot 0) -------------------------------------
    na, npol, npp = CONE
    L = D.tool_length
    az = np.linspace(-np.pi, np.pi, na, endpoint=False) + 2 * np.pi / na
    pol = np.linspace(0.0, np.pi, npol)
    p = np.linspace(0.01 * L, L, npp)
    A, B, P = np.meshgrid(az, pol, p, indexing="ij")
    d_e = ak.direction_from_angles(A.ravel(), B.ravel())
    q, ik = ak.q_from_instrument(T, d_e, P.ravel(), D, errors="flag")
    ok = ik.valid & (ik.mode == 1)
    cc = _Lean(np.where(ok[:, None], q, REFERENCE_Q), 0)
    # the slot-0 configuration is the IK's: same O_s (checked)
    Os_fk = mechanism_points(np.where(ok[:, None], q, REFERENCE_Q), T, D, slot=0)["O_s"]
    Os_ik = T[:3, 3] - P.ravel()[:, None] * (d_e @ T[:3, :3].T)
    reach = ok & cc.valid
    err = np.abs(Os_fk[reach] - Os_ik[reach]).max()
    res["cone_slot0_matches_ik_m"] = float(err)
    free = reach & ~cc.colliding
    sh = (na, npol, npp)
    reach3, free3 = reach.reshape(sh), free.reshape(sh)
    dirs_reach = reach3.any(-1)
    dirs_free = free3.any(-1)
    res["cone_directions_reachable"] = int(dirs_reach.sum())
    res["cone_directions_with_a_free_insertion"] = int(dirs_free.sum())
    res["cone_directions_blocked"] = int((dirs_reach & ~dirs_free).sum())
    res["cone_samples_reachable"] = int(reach.sum())
    res["cone_samples_free"] = int(free.sum())
    names = np.array([f"{a}/{b}" for a, b in cc.pairs])
    blocked = reach & cc.colliding
    cnt = {}
    for k in cc.closest_pair[blocked]:
        cnt[names[k]] = cnt.get(names[k], 0) + 1
    res["cone_blocking_pairs"] = dict(sorted(cnt.items(), key=lambda kv: -kv[1]))
    # pairs that collide anywhere in slot 0: on the stroke grid or in the cone
    dmin_grid = {tuple(p["pair"]): p["min_distance"] for p in res["slot0_pairs_that_collide"]}
    dmin_all = np.nanmin(np.concatenate([c.distances[c.valid[:, 0], 0],
                                         cc.distances[reach]]), axis=0)
    res["slot0_min_distance_grid_and_cone"] = {f"{a}-{b}": float(dmin_all[i])
                                               for i, (a, b) in enumerate(pairs)}
    res["cone_only_collisions"] = [f"{a}-{b}" for i, (a, b) in enumerate(pairs)
                                   if dmin_all[i] < 0 and (a, b) not in dmin_grid]
    frac = np.where(reach3.sum(-1) > 0, free3.sum(-1) / np.maximum(reach3.sum(-1), 1), np.nan)
    # the chart of every cone figure (figure_instrument_cone): the azimuths in one piece
    # across +-180 deg from the widest unreachable gap, polar downwards
    from athenakin.analysis.figures import wrapped_azimuth

    az_w, order = wrapped_azimuth(np.degrees(az), dirs_reach.any(axis=1))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    im = ax.pcolormesh(az_w[order], np.degrees(pol), frac[order].T, cmap="RdYlGn", vmin=0,
                       vmax=1, shading="nearest")
    ax.set_ylim(180, 0)
    fig.colorbar(im, ax=ax, label="collision-free share of the reachable insertions")
    ax.set_xlabel("azimuth about z_e (deg)")
    ax.set_ylabel("polar angle from z_e (deg)")
    ax.set_title("Instrument cone of the reference set-up (mode +1): where collisions block "
                 "(white: unreachable)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "collision_cone.png", dpi=80)
    plt.close(fig)
    (OUT / "collision_finding.json").write_text(json.dumps(res, indent=1) + "\n")
    if OUT == HERE:
        _write_doc(res)
    return res


def _write_doc(res: dict) -> None:
    lines = [
        f"Computed by `python docs/figures/collision.py finding` on a {res['grid']}^3 grid of "
        f"the strokes ({res['n_configurations']} configurations, all 16 FK slots) and "
        f"{res['cone'][0]} x {res['cone'][1]} instrument directions x {res['cone'][2]} "
        f"insertions, default radii, {res['pairs_checked']} checked pairs.",
        "",
        f"- **Working slot 0** (mode +1, p > 0): {res['slot0_valid']} configurations assemble; "
        f"{res['slot0_collision_free']} of them "
        f"({100 * res['slot0_free_fraction']:.1f} %) are collision-free.",
        "- Pairs that collide somewhere in slot 0 (share of its configurations, deepest "
        "penetration):",
        "",
        "| pair | share | deepest (mm) | insertion p where it collides (m) "
        "| q1 - q2 where it collides (abs, m) |",
        "|---|---:|---:|---|---|",
    ]
    for p in res["slot0_pairs_that_collide"]:
        lines.append(f"| {p['pair'][0]} / {p['pair'][1]} | {100 * p['fraction']:.1f} % | "
                     f"{-1000 * p['min_distance']:.1f} | {p['p_range'][0]:.3f} .. "
                     f"{p['p_range'][1]:.3f} | {p['gap_range'][0]:.3f} .. "
                     f"{p['gap_range'][1]:.3f} |")
    lines += ["", f"(Over all of slot 0: p in {res['slot0_p_range'][0]:.3f} .. "
              f"{res['slot0_p_range'][1]:.3f} m, q1 - q2 (abs) in {res['slot0_gap_range'][0]:.3f}"
              f" .. {res['slot0_gap_range'][1]:.3f} m.)"]
    never = sorted([(k, v) for k, v in res["slot0_min_distance_grid_and_cone"].items()
                    if v >= 0], key=lambda kv: kv[1])[:5]
    cone_only = res["cone_only_collisions"]
    lines += [
        "",
        "- Colliding in the cone samples but not on the stroke grid (a thin band the grid "
        "steps over): " + (", ".join(cone_only) if cone_only else "none") + ".",
        "- Never colliding in slot 0 on either sampling, closest first (smallest clearance): "
        + ", ".join(f"{k} {1000 * v:.1f} mm" for k, v in never) + ".",
        f"- In any slot, {len(res['any_slot_pairs_that_collide'])} pairs can collide.",
        f"- **Instrument cone** (mode +1): {res['cone_directions_reachable']} directions are "
        f"reachable; {res['cone_directions_with_a_free_insertion']} keep at least one "
        f"collision-free insertion and {res['cone_directions_blocked']} are blocked at every "
        f"reachable insertion; {res['cone_samples_free']} of {res['cone_samples_reachable']} "
        f"reachable (direction, insertion) samples "
        f"({100 * res['cone_samples_free'] / max(res['cone_samples_reachable'], 1):.1f} %) "
        "are collision-free. Closest pair where the cone collides: "
        + ", ".join(f"{k} ({v})" for k, v in list(res["cone_blocking_pairs"].items())[:5])
        + ".",
        f"- The paper's design (the reference design) is "
        f"{'not ' if res['slot0_collision_free'] < res['slot0_valid'] else ''}"
        "collision-free over its workspace with these radii.",
    ]
    text = DOC.read_text()
    start, end = "<!-- finding:start -->", "<!-- finding:end -->"
    i, j = text.index(start) + len(start), text.index(end)
    DOC.write_text(text[:i] + "\n" + "\n".join(lines) + "\n" + text[j:])


if __name__ == "__main__":
    for name in sys.argv[1:] or ["bodies", "finding"]:
        out = globals()[name]()
        print(f"{name}: done" if out is None else json.dumps(out, indent=1)[:3000])
