"""Teleoperation benchmarks (issue 29): latency, hostile streams, the closed loop in MuJoCo.

Run from the repository root (each prints the machine's load beside its numbers)::

    python benchmarks/bench_teleop.py latency [--cycles 1000000] [--block 1000]
    python benchmarks/bench_teleop.py guard [--cycles 100000] [--block 1000]
    python benchmarks/bench_teleop.py hostile [--cycles 1000000] [--seed 0] [--clearance]
        [--oracle]
    python benchmarks/bench_teleop.py session [--seconds 20] [--figure FILE.png]

``latency``: the whole chain per cycle (mapping, filter, IK, safety, feed-forward) on a
smooth master, p50 / p99 / max, with and without the feed-forward, beside the core's own
jitter (a constant workload of the chain's p50, timed as the chain is) and the chain's own
work (each cycle's least time over three runs of the same samples), and where the time
goes (each stage timed alone over the same states). ``guard``: every guard on, each case
beside the plain chain in the same run (round robin, blocks of cycles, so that the
machine's load falls on every case alike): ``Bodies.default`` and three obstacles (a
halfspace, a sphere, a box) while the robot moves freely; the tip pressed against a
fixture; a body (the carrier) held at the clearance margin; p50 / p99 / max, p99 over the
plain chain's, the share of guarded cycles and the most clearance evaluations of a cycle
(bound ``CLEARANCE_EVALUATIONS``). ``hostile``: streams of jumps, NaN,
dropouts, far targets, clutch chatter into fixtures and the singular set; counts every
stroke, velocity, acceleration, fixture, clearance and NaN violation (all must be 0).
``session``: 20 s of master motion at 1 kHz with gravity through the chain and the MuJoCo
arm (the clutch open from 45 % to 50 % of the run, the master silent for 60 ms at 75 %),
with feed-forward and PD only: tip tracking error, loop-closure drift; the figure of
docs/teleop.md.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from _machine import load_text

import athenakin as ak
from athenakin.collision import Bodies, Environment
from athenakin.teleop import Teleop, TeleopOptions, TeleopStatus
from athenakin.teleop._fixtures import TipFixtures

D = ak.Design.default()
T = ak.default_rcm_frame(D)
Q0 = (-0.1, 0.1, 0.45)
RATE = 1000.0


def master(k: int) -> tuple[float, float, float]:
    """A surgeon-like motion: a few cm at 0.2-0.5 Hz (master frame, m) plus 10 Hz tremor."""
    s = k / RATE
    return (0.05 * math.sin(2 * math.pi * 0.5 * s) + 0.0005 * math.sin(2 * math.pi * 10 * s),
            0.03 * math.sin(2 * math.pi * 0.3 * s), 0.02 * (1 - math.cos(2 * math.pi * 0.2 * s)))


def _percentiles(dt: np.ndarray) -> str:
    us = dt * 1e6
    return (f"p50 {np.percentile(us, 50):7.1f} us  p99 {np.percentile(us, 99):7.1f} us  "
            f"max {us.max():8.1f} us")


def latency(cycles: int, block: int = 0) -> None:
    """The chain with and without the feed-forward, then each stage alone.

    ``block``: 0 runs all the cycles without the feed-forward, then all with it; more
    runs the two round robin in blocks of ``block`` cycles (the machine's speed changes
    over seconds: blocks spread it over both alike, as ``guard`` does).
    """
    print(f"latency over {cycles} cycles ({load_text()})"
          + (f", round robin in blocks of {block}" if block else ""))
    clock = time.perf_counter
    teles = {}
    for ff in (False, True):
        tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=ff))
        for k in range(2000):                       # warm up (compile, caches)
            tele.step(k / RATE, master(k))
        teles[ff] = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=ff))
    samples = [master(k) for k in range(cycles)]
    dts = {ff: np.empty(cycles) for ff in teles}
    step = block if block > 0 else cycles
    order = [(k0, ff) for k0 in range(0, cycles, step) for ff in teles] if block > 0 else \
        [(0, False), (0, True)]
    for k0, ff in order:
        tele, dt = teles[ff], dts[ff]
        for k in range(k0, min(k0 + step, cycles)):
            m = samples[k]
            t0 = clock()
            tele.step(k / RATE, m)
            dt[k] = clock() - t0
    for ff, dt in dts.items():
        print(f"  feed-forward {'on ' if ff else 'off'} ({cycles} cycles, backend "
              f"{teles[ff].backend}): {_percentiles(dt)}")
    d50, d99 = ((np.percentile(dts[True], x) - np.percentile(dts[False], x)) * 1e6
                for x in (50, 99))
    print(f"  feed-forward on - off: p50 {d50:+.1f} us, p99 {d99:+.1f} us "
          f"({load_text()} at the end)")
    # the core's own jitter, and the chain's work without it
    core_jitter(float(np.percentile(dts[True], 50)), min(cycles, 200_000), dts[True])
    repeat_minimum(samples[:min(cycles, 50_000)], repeats=3)
    # where the time goes: each stage alone, over the states of a run
    tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=False))
    cmds = [tele.step(k / RATE, master(k)) for k in range(5000)]
    from athenakin.dynamics import InverseDynamicsLoop, MassModel, inverse_dynamics
    from athenakin.motion import Tracker
    from athenakin.teleop._filter import TremorFilter
    from athenakin.teleop._limiter import _IK

    filt = TremorFilter("notch8-12", RATE)
    filt.reset(0.0, 0.0, 0.0)
    ik = _IK(np.asarray(T), D, tele.backend == "numba")
    tr = Tracker(T, D, q0=Q0)
    masses = MassModel.reference(D)
    ff = InverseDynamicsLoop(T, D, masses=masses, slot=0)
    stages = {
        "filter (3 axes)": lambda c, k: filt(*master(k)),
        "IK q_from_tool_tip (x1 per cycle)": lambda c, k: ik(*c.tip),
        "tool-tip inverse Jacobian (x1)": lambda c, k: ik.along(c.q, 1, (1.0, 0.0, 0.0)),
        "tracker update (x1)": lambda c, k: tr.update(c.q),
        "feed-forward (InverseDynamicsLoop)": lambda c, k: ff(c.q, c.qd, c.qdd),
        "inverse_dynamics (public, for scale)": lambda c, k: inverse_dynamics(
            c.q, c.qd, c.qdd, T, D, masses=masses, slot=0, errors="flag"),
    }
    for name, fn in stages.items():
        m = len(cmds) if "public" not in name else 1000
        dt = np.empty(m)
        for k in range(m):
            c = cmds[k]
            t0 = clock()
            fn(c, k)
            dt[k] = clock() - t0
        print(f"  stage {name:36s} {_percentiles(dt)}")


def _constant_work(n: int) -> float:
    """A fixed amount of Python work (``n`` float additions): the same on every call."""
    s = 0.0
    for i in range(n):
        s += i * 0.5
    return s


def core_jitter(target_s: float, cycles: int, chain: np.ndarray) -> None:
    """Time a constant workload of the chain's p50 as the chain is timed; print both tails.

    The constant work's p99 / p50 is what the core (interrupts, the VM, the other core's
    traffic) adds to a cycle that does the same thing every time; the chain's own p99 /
    p50 beside it (``chain``: its cycle times, s).
    """
    clock = time.perf_counter
    n = 64
    while True:                          # the count whose median time is the chain's p50
        t = []
        for _ in range(200):
            t0 = clock()
            _constant_work(n)
            t.append(clock() - t0)
        if np.median(t) >= target_s or n > 10**7:
            break
        n = int(n * max(1.1, target_s / float(np.median(t))))
    dt = np.empty(cycles)
    for k in range(cycles):
        t0 = clock()
        _constant_work(n)
        dt[k] = clock() - t0
    r_work = np.percentile(dt, 99) / np.percentile(dt, 50)
    r_chain = np.percentile(chain, 99) / np.percentile(chain, 50)
    print(f"  the core's own jitter, a constant workload ({n} float additions) timed "
          f"{cycles} times: {_percentiles(dt)}, p99/p50 {r_work:.2f} (the chain with "
          f"feed-forward: {r_chain:.2f}; {load_text()})")


def repeat_minimum(samples: list, repeats: int = 3) -> None:
    """The chain's own work: each cycle's least time over ``repeats`` runs of one stream.

    The same master samples through a new core (feed-forward on) ``repeats`` times: a
    cycle's work is the same in every run, the machine's interruptions are not (they
    fall on other cycles), so the per-cycle minimum keeps the work and drops them.
    """
    clock = time.perf_counter
    runs = np.empty((repeats, len(samples)))
    for r in range(repeats):
        tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=True))
        for k, m in enumerate(samples):
            t0 = clock()
            tele.step(k / RATE, m)
            runs[r, k] = clock() - t0
    least = runs.min(axis=0)
    each = ", ".join(f"p99 {1e6 * np.percentile(x, 99):.1f} us" for x in runs)
    # the slowest 1 % of cycles of each run: the same cycles where the work makes them slow
    slow = [set(np.flatnonzero(x > np.percentile(x, 99)).tolist()) for x in runs]
    common = ", ".join(str(len(slow[r] & slow[r + 1])) for r in range(repeats - 1))
    print(f"  the chain's own work (feed-forward on), each cycle's least over {repeats} runs "
          f"of the same {len(samples)} samples: {_percentiles(least)} (the runs: {each}; "
          f"of the {len(slow[0])} slowest cycles of a run, {common} are among the next "
          f"run's; {load_text()})")


def _env() -> Environment:
    tb = T[:3, :3] @ np.array([0.25, 0.0, 0.0]) + T[:3, 3]
    return (Environment().sphere(tb + np.array([0.0, 0.0, -0.03]), 0.01, name="vessel")
            .halfspace(tb + np.array([0.0, 0.0, -0.06]), [0.0, 0.0, 1.0], name="floor"))


def _three_obstacles() -> Environment:
    """A halfspace 6 cm below the tip, a sphere 5 cm beside it, a box 6 cm on the other side."""
    tb = T[:3, :3] @ np.array([0.25, 0.0, 0.0]) + T[:3, 3]
    box = np.eye(4)
    box[:3, 3] = tb + np.array([0.0, 0.07, 0.0])
    return (Environment().halfspace(tb + np.array([0.0, 0.0, -0.06]), [0.0, 0.0, 1.0],
                                    name="floor")
            .sphere(tb + np.array([0.0, -0.06, -0.02]), 0.012, name="vessel")
            .box(box, [0.015, 0.01, 0.015], name="retractor"))


def _guard_cases() -> dict[str, tuple[Teleop, object]]:
    """The four cases of ``guard``: (Teleop, master(k) -> sample) by name."""
    from athenakin._mechanism import POINT_NAMES, mechanism_points

    R, c0 = T[:3, :3], T[:3, 3]
    tip_b = R @ np.array([0.25, 0.0, 0.0]) + c0
    B = Bodies.default(D)
    opts = TeleopOptions()
    cases: dict[str, tuple[Teleop, object]] = {}
    cases["plain chain"] = (Teleop(ak.Robot(T, D), q0=Q0, options=opts), master)
    cases["bodies + 3 obstacles, moving freely"] = (
        Teleop(ak.Robot(T, D, bodies=B, environment=_three_obstacles()), q0=Q0, options=opts),
        master)
    # the tip pressed against an organ (a sphere of 2 cm, its surface 9 mm below the tip;
    # the master 10 cm into it): the target projected out of the fixture and slid along
    # it, the instrument's capsule held at the clearance margin
    floor = Environment().sphere(tip_b - np.array([0.0, 0.0, 0.029]), 0.02, name="tissue")
    down = R.T @ np.array([0.0, 0.0, -0.1])

    def press(k: int) -> tuple[float, float, float]:
        m = master(k)
        return (m[0] + down[0], m[1] + down[1], m[2] + down[2])

    cases["tip pressed against a fixture"] = (
        Teleop(ak.Robot(T, D, bodies=B, environment=floor), q0=Q0, options=opts), press)
    # a sphere at the clearance floor of the carrier, in the way of the tip's +y motion
    pts0 = mechanism_points(np.array(Q0), T, D).xyz
    q1, _ = ak.q_from_tool_tip(T, np.array([0.25, 0.01, 0.0]), D)
    pts1 = mechanism_points(q1, T, D).xyz
    i, j = POINT_NAMES.index("C"), POINT_NAMES.index("D")
    mid0, mid1 = 0.5 * (pts0[i] + pts0[j]), 0.5 * (pts1[i] + pts1[j])
    way = (mid1 - mid0) / np.linalg.norm(mid1 - mid0)
    r = 0.01
    gap = opts.clearance_margin + opts.clearance_buffer + 0.0005
    organ = Environment().sphere(mid0 + way * (B.radius["carrier"] + r + gap), r, name="organ")
    push = np.array([0.0, 0.1, 0.0])

    def toward(k: int) -> tuple[float, float, float]:
        m = master(k)
        return (m[0] + push[0], m[1] + push[1], m[2] + push[2])

    cases["carrier held at the clearance margin"] = (
        Teleop(ak.Robot(T, D, bodies=B, environment=organ), q0=Q0, options=opts), toward)
    return cases


def guard(cycles: int, block: int = 1000) -> None:
    """The guard's cost, each case beside the plain chain (see the module docstring).

    ``block``: cycles of one case before the next case's (about 50 ms: the machine's load
    changes over seconds, so short blocks spread it over every case alike).
    """
    from athenakin.teleop._limiter import CLEARANCE_EVALUATIONS

    print(f"guard over {cycles} cycles per case, blocks of {block} ({load_text()} at the start)")
    clock = time.perf_counter
    warm = _guard_cases()
    for tele, src in warm.values():                   # compile, caches
        for k in range(2000):
            tele.step(k / RATE, src(k))    # type: ignore[operator]
    cases = _guard_cases()
    dts = {name: np.empty(cycles) for name in cases}
    cpu = {name: np.empty(cycles) for name in cases}
    tclock = time.thread_time
    guarded = dict.fromkeys(cases, 0)
    evals = dict.fromkeys(cases, 0)
    bits = int(TeleopStatus.CLEARANCE | TeleopStatus.FIXTURE)
    loads = []
    for k0 in range(0, cycles, block):
        for name, (tele, src) in cases.items():
            dt, dc = dts[name], cpu[name]
            for k in range(k0, min(k0 + block, cycles)):
                m = src(k)                 # type: ignore[operator]
                c0 = tclock()
                t0 = clock()
                cmd = tele.step(k / RATE, m)
                t1 = clock()
                dc[k] = tclock() - c0
                dt[k] = t1 - t0
                guarded[name] += int(cmd.status) & bits != 0
                evals[name] = max(evals[name], tele.clearance_evaluations)
        loads.append(os.getloadavg()[0])
    p99_plain = np.percentile(dts["plain chain"], 99)
    c99_plain = np.percentile(cpu["plain chain"], 99)
    for name, dt in dts.items():
        dc = cpu[name] * 1e6
        print(f"  {name:38s} wall {_percentiles(dt)}  p99/plain "
              f"{np.percentile(dt, 99) / p99_plain:4.2f}")
        print(f"  {'':38s} cpu  p50 {np.percentile(dc, 50):7.1f} us  p99 "
              f"{np.percentile(dc, 99):7.1f} us  p99/plain "
              f"{np.percentile(cpu[name], 99) / c99_plain:4.2f}; guarded "
              f"{guarded[name] / cycles:6.1%}, clearance evaluations <= {evals[name]} a cycle "
              f"(K = {CLEARANCE_EVALUATIONS})")
    print(f"  load during the run: {min(loads):.2f}-{max(loads):.2f} (1-min average, "
          f"{os.cpu_count()} cores)")


def _four_fixtures() -> Environment:
    """:func:`_env`'s sphere and halfspace, a capsule and a box: every fixture shape."""
    tb = T[:3, :3] @ np.array([0.25, 0.0, 0.0]) + T[:3, 3]
    box = np.eye(4)
    box[:3, 3] = tb + np.array([0.0, 0.07, -0.02])
    return (_env().capsule(tb + np.array([-0.03, -0.05, -0.03]),
                           tb + np.array([0.03, -0.05, -0.03]), 0.006, name="duct")
            .box(box, [0.015, 0.01, 0.015], name="retractor"))


#: Cycles per block of the independent oracle (``hostile --oracle``).
ORACLE_BLOCK = 20_000


def hostile(cycles: int, seed: int, *, with_clearance: bool,
            oracle: bool = False) -> dict[str, int]:
    env = _four_fixtures() if oracle else _env()
    fx = TipFixtures(env)
    block: list = []
    found = {}
    opts = TeleopOptions(feedforward=False, check_clearance=with_clearance)
    tele = Teleop(T, D, q0=Q0, options=opts, environment=env,
                  bodies=Bodies.default(D) if with_clearance else None)
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(D.stroke_min), np.asarray(D.stroke_max)
    vmax, amax = np.asarray(tele.v_max), np.asarray(tele.a_max)
    R, c0 = T[:3, :3], T[:3, 3]
    bad = dict(stroke=0, velocity=0, acceleration=0, fixture=0, clearance=0, nan=0, fault=0)
    flags = 0
    m = np.zeros(3)
    drift = np.zeros(3)
    t0 = time.perf_counter()
    down = R.T @ np.array([0.0, 0.0, -1.0])
    for k in range(cycles):
        r = rng.random()
        clutch = bool(rng.random() > 0.02) if (k // 5000) % 4 == 3 else True   # chatter phases
        if r < 0.001:
            m = m + rng.normal(scale=1.0, size=3)               # a metre
            sample = m
        elif r < 0.002:
            sample = (math.nan, rng.random(), math.inf)
        elif r < 0.004:
            sample = None
        else:
            phase = (k // 3000) % 3
            if phase == 0:
                m = m + rng.normal(scale=0.0005, size=3)        # wander (0.5 m/s)
            elif phase == 1:
                m = m + 0.0002 * down                           # into the fixtures
            else:                                               # far out, across the
                if k % 3000 == 0:                               # singular set, back
                    drift = rng.normal(size=3)
                    drift *= 0.0005 / np.linalg.norm(drift)
                m = m + drift
            sample = m
        cmd = tele.step(k / RATE, sample, clutch)
        flags |= int(cmd.status)
        q, qd, qdd = np.asarray(cmd.q), np.asarray(cmd.qd), np.asarray(cmd.qdd)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))
                and all(math.isfinite(x) for x in cmd.tip)):
            bad["nan"] += 1
        bad["stroke"] += int(np.any(q < lo) or np.any(q > hi))
        bad["velocity"] += int(np.any(np.abs(qd) > vmax * (1 + 1e-9)))
        bad["acceleration"] += int(np.any(np.abs(qdd) > amax * (1 + 1e-9)))
        if fx.nearest(tuple(R @ np.asarray(cmd.tip) + c0))[0] < 0.0:
            bad["fixture"] += 1
        if with_clearance and not cmd.clearance >= opts.clearance_margin:
            bad["clearance"] += 1
        bad["fault"] += int(bool(cmd.status & TeleopStatus.FAULT))
        if oracle:
            block.append(cmd)
            if len(block) > ORACLE_BLOCK or k == cycles - 1:
                found = _oracle(block, tele, env, with_clearance, found)
                block = block[-1:]            # the backward differences across blocks
    el = time.perf_counter() - t0
    print(f"hostile streams: {cycles} cycles, seed {seed}, clearance "
          f"{'on' if with_clearance else 'off'}, {el:.1f} s ({load_text()})")
    print(f"  flags seen: {TeleopStatus(flags)!r}")
    print(f"  violations: {bad}")
    if oracle:
        print(f"  independent oracle (athenakin.testing.teleop_violations: reference FK tips, "
              f"coal distances to the {len(env)} fixtures, clearance from rebuilt points): "
              f"{found}")
        bad.update({f"oracle_{k}": v for k, v in found.items() if not k.startswith("least")})
    return bad


def _oracle(block: list, tele: Teleop, env: Environment, with_clearance: bool,
            found: dict) -> dict:
    """Add the violations ``athenakin.testing`` finds in ``block`` to ``found``."""
    from athenakin.testing import teleop_violations

    robot = ak.Robot(T, D, bodies=Bodies.default(D) if with_clearance else None,
                     environment=env)
    v = teleop_violations(block, robot, rate=RATE, v_max=tele.v_max, a_max=tele.a_max,
                          bodies=None if with_clearance else False,
                          clearance_margin=tele.options.clearance_margin
                          if with_clearance else 0.0)
    out = {k: found.get(k, 0) + v.counts[k] for k in v.counts}
    for k, x in (("least_clearance_m", v.least_clearance),
                 ("least_fixture_distance_m", v.least_fixture_distance)):
        out[k] = min(found.get(k, math.inf), x) if math.isfinite(x) else found.get(k, x)
    return out


def session(seconds: float, figure: str | None) -> None:
    from athenakin.teleop import SimulatedArm, run_session

    n = int(seconds * RATE)

    def stream():
        for k in range(n):
            silent = 0.75 * n <= k < 0.75 * n + 0.06 * RATE        # 60 ms without the master
            yield k / RATE, None if silent else master(k), not (0.45 * n <= k < 0.5 * n)

    logs = {}
    for ff in (True, False):
        t0 = time.perf_counter()
        tele = Teleop(T, D, q0=Q0, options=TeleopOptions(feedforward=ff))
        arm = SimulatedArm(T, D, q0=Q0, feedforward=ff)
        arm.enable()
        log = run_session(tele, arm, stream(), check_bodies=False)     # the plain chain
        err = log.tip_error
        logs[ff] = log
        print(f"session {seconds:g} s at {RATE:g} Hz with gravity, "
              f"{'PD + feed-forward' if ff else 'PD only'}: tip error "
              f"{np.sqrt(np.mean(err ** 2)) * 1e3:.4f} mm RMS, {err.max() * 1e3:.4f} mm max; "
              f"loop closure {np.nanmax(log.closure_error):.2e} m max; "
              f"{time.perf_counter() - t0:.1f} s ({load_text()})")
    if figure:
        _figure(logs[True], logs[False], figure)
        print(f"wrote {figure}")


def _figure(log, log_pd, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = log.t
    fig, ax = plt.subplots(4, 1, figsize=(10.5, 10), sharex=True,
                           gridspec_kw={"height_ratios": [2, 2, 2, 1.3]})
    for i, c in enumerate("xyz"):
        ax[0].plot(t, log.master[:, i] * 1e3, lw=0.8, label=f"master {c}")
    ax[0].set_ylabel("master [mm]\n(master frame)")
    beside = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "fontsize": 8,
              "frameon": False}                 # legends beside the data, never over it
    ax[0].legend(**beside)
    for i, c in enumerate("xyz"):
        ax[1].plot(t, (log.tip_b[:, i] - log.tip_b[0, i]) * 1e3, lw=1.2, label=f"command {c}")
        ax[1].plot(t, (log.measured_tip_b[:, i] - log.tip_b[0, i]) * 1e3, "k:", lw=0.8)
    ax[1].plot([], [], "k:", label="MuJoCo tip")
    ax[1].set_ylabel("tip - start [mm]\n(base frame)")
    ax[1].legend(**beside)
    ax[2].semilogy(t, np.maximum(log.tip_error, 1e-9) * 1e3, lw=0.8, label="PD + feed-forward")
    ax[2].semilogy(t, np.maximum(log_pd.tip_error, 1e-9) * 1e3, lw=0.8, label="PD only")
    ax[2].set_ylabel("|MuJoCo tip -\ncommand| [mm]")
    ax[2].legend(**beside)
    names = [f for f in TeleopStatus if f]
    for j, f in enumerate(names):
        on = (log.status & int(f)) != 0
        if np.any(on):
            ax[3].fill_between(t, j - 0.4, j + 0.4, where=on, step="mid", lw=0)
    ax[3].set_yticks(range(len(names)), [f.name for f in names], fontsize=7)
    ax[3].set_xlabel("t [s]")
    ax[3].set_title("status flags", fontsize=9)
    fig.suptitle("athenakin.teleop: a recorded-style master, the command and MuJoCo's tip")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    a = sub.add_parser("latency")
    a.add_argument("--cycles", type=int, default=1_000_000)
    a.add_argument("--block", type=int, default=0,
                   help="run with and without the feed-forward round robin in blocks of "
                        "this many cycles (0: one after the other)")
    g = sub.add_parser("guard")
    g.add_argument("--cycles", type=int, default=100_000)
    g.add_argument("--block", type=int, default=1000, help="cycles per case in each round")
    b = sub.add_parser("hostile")
    b.add_argument("--cycles", type=int, default=1_000_000)
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--clearance", action="store_true",
                   help="also check the bodies' clearance (tens of microseconds per cycle)")
    b.add_argument("--oracle", action="store_true",
                   help="every fixture shape (halfspace, sphere, capsule, box), and every "
                        "block of cycles checked again by athenakin.testing.teleop_violations")
    c = sub.add_parser("session")
    c.add_argument("--seconds", type=float, default=20.0)
    c.add_argument("--figure", default=None)
    args = p.parse_args()
    if args.what == "latency":
        latency(args.cycles, args.block)
    elif args.what == "guard":
        guard(args.cycles, args.block)
    elif args.what == "hostile":
        bad = hostile(args.cycles, args.seed, with_clearance=args.clearance,
                      oracle=args.oracle)
        raise SystemExit(1 if any(bad.values()) else 0)
    else:
        session(args.seconds, args.figure)


if __name__ == "__main__":
    main()
