"""Figures and numbers of docs/dynamics.md (the reference design, MassModel.reference()).

Run from the repository root: ``python docs/figures/dynamics.py``. Writes
``dynamics_gravity_cone.png``, ``dynamics_gravity_plane.png``,
``dynamics_capability.png`` and ``dynamics_motion.png`` here and prints every number
that docs/dynamics.md quotes.
"""

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import athenakin as ak  # noqa: E402
from athenakin import dynamics as dy  # noqa: E402

HERE = Path(__file__).resolve().parent
#: Where the figures go: docs/figures, or ATHENAKIN_FIGURES_OUT (regenerate.py --out).
OUT = Path(os.environ.get("ATHENAKIN_FIGURES_OUT", HERE))
EXAMPLES = HERE.parent.parent / "examples" / "motion"
D = ak.Design.default()
T = ak.default_rcm_frame(D)
M = dy.MassModel.reference(D)
#: Actuator force limit assumed for the capability figures, N (each actuator, both ways).
F_MAX = 50.0
#: Insertion of the cone maps: O_s 0.20 m before the RCM, the tip 0.25 m beyond it.
P_CONE = 0.20


def cone_grid(n_az=91, n_pol=61):
    """Directions on an (azimuth, polar) grid about z_e at insertion P_CONE, and their q."""
    az = np.linspace(-np.pi, np.pi, n_az)
    pol = np.radians(np.linspace(0.0, 180.0, n_pol))
    A, P = np.meshgrid(az, pol, indexing="ij")
    d_e = ak.direction_from_angles(A, P)
    q, res = ak.q_from_instrument(T, d_e, np.full(A.shape, P_CONE), D, errors="flag")
    return az, pol, q, res


def cone_chart(az, values, occupied):
    """Azimuths (deg) and values on the chart of every cone figure of the docs.

    As :func:`athenakin.analysis.figures.figure_instrument_cone`: the azimuth axis starts in
    the widest gap of unreachable azimuths (one piece across +-180 deg), polar downwards.
    The grid's last azimuth (+180 deg, the first one again) is dropped.
    """
    from athenakin.analysis.figures import wrapped_azimuth

    a, order = wrapped_azimuth(np.degrees(az[:-1]), occupied[:-1])
    return a[order], [v[:-1][order] for v in values]


def forces_in_cone(q, res):
    """Static forces per item in its assembly mode (slot 0 or 8), NaN where unreachable."""
    f = np.full(q.shape, np.nan)
    cap_min = np.full(q.shape[:-1], np.nan)
    weak = np.full(q.shape, np.nan)
    for mode, slot in ((1, 0), (-1, 8)):
        sel = res.valid & (res.mode == mode)
        if not np.any(sel):
            continue
        st = dy.statics(q[sel], T, D, masses=M, slot=slot, errors="flag")
        f[sel] = st.forces
        cap = dy.force_capability(q[sel], T, D, masses=M, f_max=F_MAX, slot=slot,
                                  errors="flag")
        cap_min[sel] = cap.min_force
        weak[sel] = cap.weakest_direction
    return f, cap_min, weak


def polytope_section(ax, cap, d_b) -> None:
    """The force polytope of ``cap`` cut through zero tip force, in a plane (N).

    The plane holds the weakest direction ``w`` and the instrument direction ``d_b``
    (orthogonalised); its boundary along each of 720 directions is
    :func:`athenakin.dynamics.max_tip_force` there, on equal axes.
    """
    w = cap.weakest_direction
    e2 = d_b - (d_b @ w) * w
    e2 /= np.linalg.norm(e2)
    th = np.linspace(0.0, 2.0 * np.pi, 721)
    dirs = np.cos(th)[:, None] * w + np.sin(th)[:, None] * e2
    r = dy.max_tip_force(ak.robot.REFERENCE_Q, dirs, T, D, masses=M, f_max=F_MAX)
    x, y = r * np.cos(th), r * np.sin(th)
    ax.fill(x, y, color="C0", alpha=0.25, lw=0)
    ax.plot(x, y, color="C0", lw=1.2, label=f"boundary: a limit |f_i| = {F_MAX:g} N reached")
    ax.plot([0.0, cap.min_force], [0.0, 0.0], color="C3", lw=3.0,
            label=f"weakest direction: {cap.min_force:.1f} N resisted")
    ax.scatter([0.0], [0.0], color="k", s=14, zorder=3, label="zero tip force")
    ax.axhline(0.0, color="0.7", lw=0.6)
    ax.axvline(0.0, color="0.7", lw=0.6)
    ax.set_aspect("equal")
    ax.set_xlabel("tip force along the weakest direction (N)")
    ax.set_ylabel("along the instrument, orthogonal to it (N)")
    q_mm = ", ".join(f"{1e3 * v:.0f}" for v in ak.robot.REFERENCE_Q)
    ax.set_title(f"tip forces resisted at q = ({q_mm}) mm, |f_i| <= {F_MAX:g} N:\n"
                 "the force polytope cut in the plane of its weakest direction",
                 fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)


def main() -> None:
    """Write the four figures and print the numbers."""
    print(f"mass model: MassModel.reference(), {M.total_mass:.2f} kg moving")
    # --- 1. gravity over the instrument cone ----------------------------------------
    az, pol, q, res = cone_grid()
    f, cap_min, weak = forces_in_cone(q, res)
    ok = np.isfinite(f[..., 0])
    print(f"cone: {ok.sum()} of {ok.size} directions (p = {P_CONE} m) reachable")
    for i in range(3):
        fi = f[..., i][ok]
        p5, p50, p95 = np.percentile(fi, [5, 50, 95])
        print(f"  gravity f{i + 1}: {fi.min():+.2f} .. {fi.max():+.2f} N; 5/50/95 % "
              f"{p5:+.2f} / {p50:+.2f} / {p95:+.2f} N")
    lim = np.nanpercentile(np.abs(f), 95)
    az_w, (f_w, cap_w) = cone_chart(az, [f, cap_min], ok.any(axis=1))
    fig, axs = plt.subplots(1, 3, figsize=(14, 3.6))
    for i, ax in enumerate(axs):
        m = ax.pcolormesh(az_w, np.degrees(pol), f_w[..., i].T, shading="auto",
                          cmap="coolwarm", vmin=-lim, vmax=lim)
        ax.set_title(f"f{i + 1} (N) holding the weight", fontsize=10)
        ax.set_xlabel("azimuth about z_e (deg)")
        ax.set_ylabel("polar from z_e (deg)")
        ax.set_ylim(180, 0)
        fig.colorbar(m, ax=ax)
    fig.suptitle("Actuator forces under gravity over the instrument cone "
                 f"(p = {P_CONE} m; white: unreachable; colour clipped at the 95th "
                 "percentile of |f|)", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "dynamics_gravity_cone.png", dpi=80, bbox_inches="tight")
    plt.close(fig)

    # --- 2. gravity over the actuator plane (q3 = 0.45 m, mode +1) ------------------
    q1 = np.linspace(D.stroke_min[0], D.stroke_max[0], 81)
    q2 = np.linspace(D.stroke_min[1], D.stroke_max[1], 81)
    Q1, Q2 = np.meshgrid(q1, q2, indexing="ij")
    qq = np.stack([Q1, Q2, np.full(Q1.shape, 0.45)], -1)
    st = dy.statics(qq, T, D, masses=M, slot=0, errors="flag")
    okp = st.valid
    print(f"actuator plane q3 = 0.45 m, slot 0: {okp.sum()} of {okp.size} valid")
    for i in range(3):
        fi = st.forces[..., i][okp]
        print(f"  gravity f{i + 1}: {fi.min():+.2f} .. {fi.max():+.2f} N")
    rcm = np.linalg.norm(st.rcm_force, axis=-1)[okp]
    print(f"  load on the RCM mount: {rcm.min():.2f} .. {rcm.max():.2f} N")
    fig, axs = plt.subplots(1, 4, figsize=(16, 3.6))
    data = [st.forces[..., 0], st.forces[..., 1], st.forces[..., 2],
            np.linalg.norm(st.rcm_force, axis=-1)]
    titles = ["f1 (N)", "f2 (N)", "f3 (N)", "|RCM mount load| (N)"]
    for ax, z, title in zip(axs, data, titles, strict=True):
        m = ax.pcolormesh(q1 * 1e3, q2 * 1e3, z.T, shading="auto", cmap="viridis")
        ax.set_xlabel("q1 (mm)")
        ax.set_ylabel("q2 (mm)")
        ax.set_title(title, fontsize=10)
        fig.colorbar(m, ax=ax)
    fig.suptitle("Gravity over the actuator plane, q3 = 450 mm, FK slot 0 "
                 "(white: no configuration)", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "dynamics_gravity_plane.png", dpi=80)
    plt.close(fig)

    # --- 3. force capability -----------------------------------------------------------
    cap = dy.force_capability(ak.robot.REFERENCE_Q, T, D, masses=M, f_max=F_MAX)
    w = cap.weakest_direction
    print(f"capability at REFERENCE_Q, |f_i| <= {F_MAX} N: min {cap.min_force:.1f} N along "
          f"{np.round(w, 3).tolist()} (base); gravity forces "
          f"{np.round(cap.gravity_forces, 2).tolist()} N")
    axes_names = ["+x", "-x", "+y", "-y", "+z", "-z"]
    dirs = np.concatenate([np.eye(3), -np.eye(3)])[[0, 3, 1, 4, 2, 5]]
    smax = dy.max_tip_force(ak.robot.REFERENCE_Q, dirs, T, D, masses=M, f_max=F_MAX)
    print("  largest tip force along base axes: "
          + ", ".join(f"{n} {s:.1f} N" for n, s in zip(axes_names, smax, strict=True)))
    d_b = T[:3, 0]        # the reference instrument direction is x_e (default_rcm_frame)
    s_in, s_out = dy.max_tip_force(ak.robot.REFERENCE_Q, np.stack([d_b, -d_b]), T, D,
                                   masses=M, f_max=F_MAX)
    print(f"  along the instrument: {s_out:.1f} N against the tip (tissue pushing back), "
          f"{s_in:.1f} N pulling it in")
    okc = np.isfinite(cap_min)
    print(f"cone: isotropic capability {np.nanmin(cap_min):.1f} .. {np.nanmax(cap_min):.1f} N, "
          f"median {np.nanmedian(cap_min):.1f} N; below 10 N in "
          f"{np.mean(cap_min[okc] < 10) * 100:.0f} % of the reachable directions")
    k = np.nanargmin(np.where(okc, cap_min, np.inf))
    ia, ip = np.unravel_index(k, cap_min.shape)
    print(f"  weakest at azimuth {np.degrees(az[ia]):.0f} deg, polar {np.degrees(pol[ip]):.0f} "
          f"deg, along {np.round(weak[ia, ip], 3).tolist()} (base)")
    wz = np.abs(weak[..., 2][okc])
    print(f"  weakest direction's |z_b| component: median {np.median(wz):.2f}")
    fig = plt.figure(figsize=(12, 4.8))
    ax = fig.add_subplot(1, 2, 1)
    m = ax.pcolormesh(az_w, np.degrees(pol), np.maximum(cap_w, 0).T,
                      shading="auto", cmap="magma")
    ax.set_xlabel("azimuth about z_e (deg)")
    ax.set_ylabel("polar from z_e (deg)")
    ax.set_ylim(180, 0)
    ax.set_title(f"tip force resisted in every direction (N), |f_i| <= {F_MAX:g} N",
                 fontsize=9)
    fig.colorbar(m, ax=ax)
    polytope_section(fig.add_subplot(1, 2, 2), cap, d_b)
    fig.tight_layout()
    fig.savefig(OUT / "dynamics_capability.png", dpi=80)
    plt.close(fig)

    # --- 4. the example motion ---------------------------------------------------------
    from athenakin.motion import PlanOptions, plan, read_path_csv

    spec = read_path_csv(EXAMPLES / "tip_square.csv")
    traj = plan(spec.tips_e, T, D,
                options=PlanOptions(rate=1000.0, v_max=0.05, a_max=0.5, j_max=5.0))
    slot = np.where(traj.mode == 1, 0, 8)
    assert np.all(slot == slot[0])
    tau = dy.inverse_dynamics(traj.q, traj.qd, traj.qdd, T, D, masses=M, slot=int(slot[0]))
    tg = dy.actuator_forces(traj.q, T, D, masses=M, slot=int(slot[0]))
    dyn = tau - tg
    print(f"example motion (examples/motion/tip_square.csv, v_max 0.05, a_max 0.5, j_max 5): "
          f"{traj.duration:.2f} s")
    for i in range(3):
        print(f"  f{i + 1}: {tau[:, i].min():+.2f} .. {tau[:, i].max():+.2f} N; inertial part "
              f"at most {np.abs(dyn[:, i]).max():.3f} N")
    fig, (ax, axd) = plt.subplots(2, 1, figsize=(9, 5.2), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 2]})
    for i in range(3):
        ax.plot(traj.t, tau[:, i], color=f"C{i}", lw=1.4, label=f"f{i + 1}")
        ax.plot(traj.t, tg[:, i], color=f"C{i}", ls="--", lw=0.9,
                label=f"f{i + 1}, gravity alone")
        axd.plot(traj.t, dyn[:, i], color=f"C{i}", lw=1.2, label=f"f{i + 1}")
    ax.set_ylabel("actuator force (N)")
    ax.set_title("Example motion (tip_square.csv, 4 corners): inverse dynamics (solid) and "
                 "gravity alone (dashed)", fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    axd.axhline(0.0, color="0.6", lw=0.6)
    axd.set_xlabel("t (s)")
    axd.set_ylabel("inertial part (N)")
    axd.set_title("inverse dynamics minus gravity: the tip stops and starts at each corner; "
                  "jerk-limited, its acceleration is triangular", fontsize=9)
    axd.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(OUT / "dynamics_motion.png", dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    main()
    sys.exit(0)
