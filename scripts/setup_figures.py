"""The figures and numbers of docs/setup.md: a set-up planned for the phantom, re-measured.

Run from the repository root (minutes on a 2-core machine; the load is printed)::

    python scripts/setup_figures.py [--samples 100000] [--certify 200] [--cohort 0]
    python scripts/setup_figures.py --view-only     # step 5 only, from the last plan

1. plans a set-up for the shipped phantom (``plan_setup``, the defaults) and times it;
2. re-measures its coverage on ``--samples`` fresh target samples, every test and every
   clearance checked (in chunks of 10 000, bounded memory);
3. certifies, for ``--certify`` covered samples, that an assembled solution exists whose
   tool tip provably lies within a few nanometres of the target point
   (:func:`athenakin.certified.certified_forward_kinematics`);
4. draws the patient, the port, the robot at three covered targets and the coverage map
   (``docs/figures/setup_scene.png``, ``docs/figures/setup_coverage.png``);
5. writes the set-up's HTML view (:func:`athenakin.plot.write_setup_html`, the page of
   ``athenakin setup view``) and a screenshot of it in headless Chromium
   (``docs/figures/setup_view.png``), and a screenshot of the live app on the set-up with
   its patient (``athenakin app --setup ... --patient ...``, ``docs/figures/setup_app.png``),
   both from ``docs/figures/setup_phantom.toml``;
6. with ``--cohort N``, plans N phantoms of sizes 0.85..1.15 as one Dask study
   (:func:`athenakin.synthesis.plan_cohort`, resumable in ``--cohort-out``), on Dask's
   local threads or, with ``--cluster local``, a ``distributed.LocalCluster`` of
   ``--workers`` processes (2) of ``--threads-per-worker`` threads (1)::

       nice -n 19 python scripts/setup_figures.py --cohort-only --cohort 20 --cluster local
7. writes the numbers to ``docs/figures/setup_numbers.json`` and between the markers of
   docs/setup.md.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from athenakin.design import Design
from athenakin.synthesis import SetupOptions, covered_samples, phantom, plan_setup

ROOT = Path(__file__).resolve().parents[1]
#: The cohort's search by default: plan_setup's defaults.
_SEARCH = {"population": 16, "generations": 8, "polish": 3}
FIG = ROOT / "docs" / "figures"


def _load() -> str:
    a, b, c = os.getloadavg()
    return f"load {a:.2f} / {b:.2f} / {c:.2f} on {os.cpu_count()} cores"


def remeasure(patient, setup, design, opts, n: int, seed: int) -> tuple[float, int, float]:
    """Coverage on ``n`` fresh samples (chunks of 10 000), and the time it took."""
    t0 = time.perf_counter()
    P = patient.target_samples(n, seed=seed)
    covered = 0
    for i in range(0, n, 10_000):
        c, _, _ = covered_samples(patient, setup, design, points=P[i:i + 10_000], options=opts)
        covered += int(np.count_nonzero(c))
    return covered / n, covered, time.perf_counter() - t0


def certify(patient, setup, design, opts, k: int, seed: int) -> dict[str, float]:
    """Certified FK at ``k`` covered samples: an assembled solution, its tip boxed."""
    from athenakin.certified import certified_forward_kinematics

    P = patient.target_samples(4 * k, seed=seed)
    cov, q, mode = covered_samples(patient, setup, design, points=P, options=opts)
    idx = np.flatnonzero(cov)[:k]
    t0 = time.perf_counter()
    cert = certified_forward_kinematics(q[idx], setup.T_b_e, design)
    tip_b = (P[idx] - setup.T_p_b[:3, 3]) @ setup.T_p_b[:3, :3]   # the targets, base frame
    t = tip_b[:, None]
    gap = np.linalg.norm(np.maximum(np.maximum(cert.tip_lo - t, t - cert.tip_hi), 0.0), axis=-1)
    # the IK's own slot: the assembly mode of the covered configuration, any branch
    slot_mode = np.where(np.arange(16) < 8, 1, -1)
    mine = cert.certified & (slot_mode[None] == mode[idx, None])
    gap = np.where(mine, gap, np.inf).min(axis=-1)
    proven = gap <= 1e-9
    width = np.max(np.where(mine[..., None], cert.tip_hi - cert.tip_lo, 0.0))
    return {"certified_checked": int(idx.size), "certified_proven": int(np.sum(proven)),
            "certified_target_gap_max_m": float(np.max(gap)),
            "certified_tip_box_max_m": float(width),
            "certified_seconds": time.perf_counter() - t0}


def figures(patient, plan, design, opts) -> None:
    """The scene (patient, port, robot at three targets) and the coverage map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from athenakin._mechanism import BODIES, body_segments, mechanism_points
    from athenakin.collision import Bodies

    setup = plan.chosen
    P = patient.target_samples(3000, seed=11)
    cov, q, mode = covered_samples(patient, setup, design, points=P, options=opts)
    fig = plt.figure(figsize=(10, 7))
    ax = fig.add_subplot(projection="3d")
    colours = {"skin": ("#d9a383", 0.12), "target": ("#e08a00", 0.9),
               "forbidden": ("#b0203a", 0.8), "table": ("#7f8790", 0.25)}
    for m in patient.meshes:
        c, a = colours[m.role]
        V = m.vertices
        if m.role == "table":           # its top, within the plotted region
            lo, hi = m.bounds
            x0, x1 = max(lo[0], -0.5), min(hi[0], 0.5)
            X, Y = np.meshgrid([x0, x1], [lo[1], hi[1]])
            ax.plot_surface(X, Y, np.full_like(X, hi[2]), color=c, alpha=a, linewidth=0)
            continue
        ax.plot_trisurf(V[:, 0], V[:, 1], V[:, 2], triangles=m.faces, color=c, alpha=a,
                        linewidth=0)
    ax.scatter(*setup.port, color="k", s=40, label="port")
    bodies = Bodies.default(design)
    picks = np.flatnonzero(cov)
    picks = picks[np.linspace(0, picks.size - 1, 3).astype(int)]
    for j, i in enumerate(picks):
        pts = mechanism_points(q[i], setup.T_b_e, design, slot=0 if mode[i] == 1 else 8,
                               geometry=bodies.geometry)
        segs = body_segments(pts) @ setup.T_p_b[:3, :3].T + setup.T_p_b[:3, 3]
        for k in range(len(BODIES)):
            ax.plot(*segs[k].T, color=f"C{j}", lw=max(1.0, 300 * bodies.radius_array[k]),
                    alpha=0.8)
        ax.scatter(*P[i], color=f"C{j}", s=25)
    ax.set_xlabel("x (cranial), m")
    ax.set_ylabel("y (left), m")
    ax.set_zlabel("z (anterior), m")
    ax.set_xlim(-0.5, 0.5)
    ax.set_ylim(-0.5, 0.5)
    ax.set_zlim(-0.05, 0.8)
    ax.set_box_aspect((1.0, 1.0, 0.85))
    ax.view_init(elev=24, azim=-58)
    ax.set_title(f"set-up for the phantom: coverage {100 * plan.figures['coverage']:.1f} %, "
                 f"robot at three covered targets")
    fig.tight_layout()
    fig.savefig(FIG / "setup_scene.png", dpi=110)
    plt.close(fig)
    fig, axs = plt.subplots(1, 2, figsize=(11, 3.6))
    for ax, (a, b), lab in zip(axs, ((1, 0), (1, 2)), (("y (left), m", "x (cranial), m"),
                                                         ("y (left), m", "z (anterior), m")),
                               strict=True):
        ax.scatter(P[cov, a], P[cov, b], s=3, color="#2a9d8f", label="covered")
        ax.scatter(P[~cov, a], P[~cov, b], s=6, color="#c1121f", label="not covered")
        ax.set_xlabel(lab[0])
        ax.set_ylabel(lab[1])
        ax.set_aspect("equal")
    fig.legend(*axs[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.suptitle(f"coverage map of the pancreas (3000 samples, {100 * cov.mean():.1f} % "
                 f"covered): top view, front view")
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(FIG / "setup_coverage.png", dpi=110)
    plt.close(fig)


@contextlib.contextmanager
def _chromium_page(width: int, height: int) -> Iterator[Any]:
    """A page of Debian's headless chromium (Playwright drives it, never downloading one)."""
    from playwright.sync_api import sync_playwright

    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=[
            "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"])
        try:
            yield browser.new_page(viewport={"width": width, "height": height})
        finally:
            browser.close()


def view(html: Path | None = None) -> Path:
    """The HTML view of the planned set-up and its screenshot, ``docs/figures/setup_view.png``.

    The page goes to ``html`` (default: a temporary file, removed); chromium renders it
    offline.
    """
    from athenakin.plot import target_coverage, write_setup_html
    from athenakin.plot._setup_view import SETUP_HTML_DIV_ID
    from athenakin.synthesis import evaluate_setup, read_setup

    setup, design, _ = read_setup(FIG / "setup_phantom.toml")
    P, cov, _, _ = target_coverage(phantom(), setup, design)
    print(f"view: {cov.sum()} of {cov.size} target faces covered ({100 * cov.mean():.1f} %)",
          flush=True)
    if np.any(~cov):                  # where the others are, and which test they fail
        m, miss = 1e3 * P[~cov], evaluate_setup(phantom(), setup, design, points=P[~cov])
        print(f"  not covered: x_p {m[:, 0].min():.0f} to {m[:, 0].max():.0f} mm, y_p "
              f"{m[:, 1].min():.0f} to {m[:, 1].max():.0f} mm; reached "
              f"{100 * miss['coverage_reach']:.0f} %, non-singular "
              f"{100 * miss['coverage_nonsingular']:.0f} %", flush=True)
    with tempfile.TemporaryDirectory() as tmp, _chromium_page(1200, 820) as page:
        page_path = write_setup_html(html or Path(tmp) / "setup.html", phantom(), setup, design)
        page.goto(page_path.resolve().as_uri())
        page.wait_for_function(
            f"() => {{ const d = document.getElementById('{SETUP_HTML_DIV_ID}'); "
            "return d && d._fullLayout && d.querySelector('canvas'); }", timeout=60000)
        page.wait_for_timeout(1500)
        page.screenshot(path=str(FIG / "setup_view.png"))
    return FIG / "setup_view.png"


def app_view() -> Path:
    """A screenshot of the live app on the planned set-up with the phantom, ``setup_app.png``."""
    from athenakin.app import AthenaApp
    from athenakin.synthesis import write_patient

    with tempfile.TemporaryDirectory() as tmp:
        patient = write_patient(phantom(), tmp)
        app = AthenaApp(port=0, planned=FIG / "setup_phantom.toml", patient=patient)
        try:
            with _chromium_page(1400, 860) as page:
                page.goto(app.url)
                page.wait_for_selector("[data-ro=q1]", timeout=60000)
                page.wait_for_timeout(2500)
                close = page.locator(".mantine-Notification-closeButton")
                for i in range(close.count()):        # the software-WebGL notice
                    close.nth(i).click()
                page.get_by_role("tab", name="Set-up").click()
                page.wait_for_timeout(1500)
                page.screenshot(path=str(FIG / "setup_app.png"))
        finally:
            app.stop()
    return FIG / "setup_app.png"


@contextlib.contextmanager
def _scheduler(kind: str, workers: int, threads: int) -> Iterator[tuple[Any, str]]:
    """The cohort's scheduler and its description: Dask's local threads or a LocalCluster."""
    if kind == "threads":
        yield None, "Dask's local threads"
        return
    import distributed

    with distributed.LocalCluster(n_workers=workers, threads_per_worker=threads,
                                  processes=True, host="127.0.0.1", dashboard_address=None,
                                  silence_logs=50) as lc, \
            distributed.Client(lc, set_as_default=False) as client:
        yield client, (f"a distributed.LocalCluster of {workers} worker processes, "
                       f"{threads} thread{'s' if threads > 1 else ''} each")


def cohort(n: int, opts, out: Path, *, scheduler: str = "threads", workers: int = 2,
           threads: int = 1, search: dict[str, int] | None = None) -> dict[str, Any]:
    """N phantoms of varied size planned as one study (``plan_cohort``, resumable in ``out``)."""
    from athenakin.synthesis import plan_cohort

    sizes = np.linspace(0.85, 1.15, n)
    patients = {f"phantom-{s:.3f}": phantom(size=float(s), name=f"phantom {s:.3f}")
                for s in sizes}
    resumed = sum((out / f"{k}.json").exists() for k in patients)
    search = {**_SEARCH, **(search or {})}
    with _scheduler(scheduler, workers, threads) as (handle, where):
        load0 = _load()
        print(f"cohort of {n} on {where}, {load0}", flush=True)
        t0 = time.perf_counter()
        df = plan_cohort(patients, **search, options=opts, out=out, scheduler=handle)
        dt = time.perf_counter() - t0
    load1 = _load()
    cov = df["coverage"].to_numpy()
    print(f"cohort of {n} planned in {dt:.0f} s on {where} (at the start {load0}, at the "
          f"end {load1}), {resumed} resumed; >= 95 %: {int(np.sum(cov >= 0.95))}, >= 90 %: "
          f"{int(np.sum(cov >= 0.90))}", flush=True)
    rows = [{"size": float(s), "seconds": float(r.get("seconds", float("nan"))),
             **{c: float(r[c]) for c in ("coverage", "min_clearance", "margin_min",
                                          "collisions")}}
            for s, (_, r) in zip(sizes, df.iterrows(), strict=True)]
    return {"rows": rows, "total_seconds": dt, "where": where, "load_start": load0,
            "load_end": load1, "resumed": resumed,
            "search": {**search, "samples": opts.samples,
                       "final_samples": opts.final_samples}}


def write_numbers(numbers: dict[str, object]) -> None:
    """The numbers as JSON, and as tables between the markers of docs/setup.md."""
    (FIG / "setup_numbers.json").write_text(json.dumps(numbers, indent=1) + "\n")
    doc = ROOT / "docs" / "setup.md"
    f = numbers["figures"]
    assert isinstance(f, dict)
    lines = [
        "| figure | value |", "| --- | --- |",
        f"| planning time (NSGA-II, {numbers['population']} x {numbers['generations']}, "
        f"{numbers.get('polish', 0)} polish rounds, Dask threads) | "
        f"{numbers['plan_seconds']:.0f} s ({numbers['plan_load']}) |",
        f"| coverage, planner ({numbers['final_samples']} samples) | "
        f"{100 * f['coverage']:.2f} % |",
        f"| coverage, re-measured ({numbers['remeasure_samples']} fresh samples) | "
        f"{100 * numbers['remeasured_coverage']:.2f} % ({numbers['remeasure_seconds']:.0f} s) |",
        f"| least clearance of the bodies (patient, table, each other) | "
        f"{1000 * f['min_clearance']:.1f} mm |",
        f"| least singularity margin (length conditions) | {1000 * f['margin_min']:.1f} mm |",
        f"| colliding configurations among the reached samples | {int(f['collisions'])} |",
        f"| largest condition number (tip Jacobian) | {f['cond_tip_max']:.1f} |",
        f"| insertion depth used | {1000 * f['depth_min']:.0f} to {1000 * f['depth_max']:.0f} mm |",
        f"| stroke use q1 / q2 / q3 | {f['stroke_use_q1']:.2f} / {f['stroke_use_q2']:.2f} / "
        f"{f['stroke_use_q3']:.2f} |",
    ]
    if "certified_checked" in numbers:
        lines.append(f"| certified covered samples (a solution of the IK's assembly mode "
                     f"exists, its tip box within 1 nm of the target) | "
                     f"{numbers['certified_proven']} of {numbers['certified_checked']} (tip "
                     f"boxes at most {numbers['certified_tip_box_max_m']:.1e} m wide, target "
                     f"at most {numbers['certified_target_gap_max_m']:.1e} m from its box; "
                     f"{numbers['certified_seconds']:.0f} s) |")
    port = ", ".join(f"{1000 * v:.1f}" for v in numbers["port"])  # type: ignore[attr-defined]
    lines.append(f"| port (patient frame) | {port} mm |")
    block = "\n".join(lines)
    text = doc.read_text()
    text = re.sub(r"(<!-- setup-numbers -->\n).*?(\n<!-- /setup-numbers -->)",
                  lambda m: m.group(1) + block + m.group(2), text, flags=re.S)
    if numbers.get("cohort"):
        text = re.sub(r"(<!-- setup-cohort -->\n).*?(\n<!-- /setup-cohort -->)",
                      lambda m: m.group(1) + _cohort_block(numbers["cohort"]) + m.group(2),
                      text, flags=re.S)
    doc.write_text(text)


def _cohort_block(c: Any) -> str:
    """The cohort's table and its summary line (markdown)."""
    rows = ["| size | coverage | least clearance | least margin | collisions | time |",
            "| --- | --- | --- | --- | --- | --- |"]
    for r in c["rows"]:
        rows.append(f"| {r['size']:.3f} | {100 * r['coverage']:.1f} % | "
                    f"{1000 * r['min_clearance']:.1f} mm | {1000 * r['margin_min']:.1f} mm "
                    f"| {int(r['collisions'])} | {r['seconds']:.0f} s |")
    cov = np.array([r["coverage"] for r in c["rows"]])
    n = len(cov)
    s = c.get("search", _SEARCH)
    rows += ["", f"{n} phantoms in {c['total_seconds']:.0f} s wall on {c['where']}, search "
             f"{s['population']} x {s['generations']} and {s['polish']} polish rounds (load at "
             f"the start {c['load_start'].removeprefix('load ')}, at the end "
             f"{c['load_end'].removeprefix('load ')}; {c['resumed']} read back from the "
             f"folder, not planned): {int(np.sum(cov >= 0.95))} of {n} reach 95 %, "
             f"{int(np.sum(cov >= 0.90))} of {n} reach 90 %."]
    return "\n".join(rows)


def main() -> None:
    """Plan, re-measure, certify, draw, write."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--certify", type=int, default=200)
    ap.add_argument("--cohort", type=int, default=0)
    ap.add_argument("--no-figures", action="store_true")
    ap.add_argument("--cohort-only", action="store_true",
                    help="plan the cohort only; the other numbers from setup_numbers.json")
    ap.add_argument("--cohort-out", type=Path, default=ROOT / "setup_cohort",
                    help="folder of the cohort's set-ups (resumable)")
    ap.add_argument("--cluster", choices=("threads", "local"), default="threads",
                    help="the cohort on Dask's local threads or a distributed.LocalCluster")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--threads-per-worker", type=int, default=1)
    for k, v in _SEARCH.items():
        ap.add_argument(f"--cohort-{k}", type=int, default=v,
                        help=f"the cohort's search: {k} ({v}, plan_setup's default)")
    ap.add_argument("--view-only", action="store_true",
                    help="the HTML view and its screenshot only, from setup_phantom.toml")
    ap.add_argument("--html", type=Path, default=None,
                    help="also keep the HTML view there (default: not kept)")
    args = ap.parse_args()
    if args.view_only:
        print(f"wrote {view(args.html)}, {app_view()}", flush=True)
        return
    if args.cohort_only:
        numbers = json.loads((FIG / "setup_numbers.json").read_text())
        numbers["cohort"] = cohort(args.cohort, SetupOptions(), args.cohort_out,
                                   **_cluster_args(args))
        write_numbers(numbers)
        return
    design = Design.default()
    patient = phantom()
    print("planning,", _load(), flush=True)
    t0 = time.perf_counter()
    plan = plan_setup(patient, design=design)
    dt = time.perf_counter() - t0
    load = _load()
    print(f"planned in {dt:.1f} s ({load}): {plan.figures}", flush=True)
    plan.write(FIG / "setup_phantom.toml", patient="phantom()")
    opts = plan.options
    numbers: dict[str, object] = {
        "plan_seconds": dt, "plan_load": load, "population": 16, "generations": 8, "polish": 3,
        "final_samples": opts.final_samples, "figures": plan.figures,
        "port": plan.chosen.port.tolist(), "decision": plan.chosen.decision.tolist()}
    cov, n_cov, dtm = remeasure(patient, plan.chosen, design, opts, args.samples, seed=12345)
    numbers.update(remeasure_samples=args.samples, remeasured_coverage=cov,
                   remeasure_seconds=dtm, remeasure_load=_load())
    print(f"re-measured on {args.samples} fresh samples: {cov:.4f} ({dtm:.0f} s, {_load()})",
          flush=True)
    if args.certify:
        numbers.update(certify(patient, plan.chosen, design, opts, args.certify, seed=777))
        print({k: numbers[k] for k in numbers if str(k).startswith("certified")}, flush=True)
    if not args.no_figures:
        figures(patient, plan, design, opts)
        view(args.html)
        app_view()
    if args.cohort:
        numbers["cohort"] = cohort(args.cohort, opts, args.cohort_out, **_cluster_args(args))
    elif (FIG / "setup_numbers.json").exists():     # the last cohort's rows stay
        last = json.loads((FIG / "setup_numbers.json").read_text()).get("cohort")
        if last and "rows" in last:
            numbers["cohort"] = last
    write_numbers(numbers)
    print("wrote docs/figures/setup_*.png, setup_numbers.json, docs/setup.md", flush=True)


def _cluster_args(args: argparse.Namespace) -> dict[str, Any]:
    return {"scheduler": args.cluster, "workers": args.workers,
            "threads": args.threads_per_worker,
            "search": {k: getattr(args, f"cohort_{k}") for k in _SEARCH}}


if __name__ == "__main__":
    main()
