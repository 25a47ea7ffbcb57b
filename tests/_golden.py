"""Golden outputs of the public API, recorded at main 6c198b4 before the round-5 rebuild.

:func:`compute` evaluates a fixed, seeded set of calls over every area that the rebuild
touches (FK/IK/Jacobians, singularities, clearance, dynamics, force capability,
calibration, a design-study row, the exports and an MCAP file) and returns a flat
``{name: value}`` dict; ``tests/test_golden.py`` compares it with the values stored in
``tests/data/golden/`` (:func:`mismatches`: arrays to 1e-12 of their scale, XML texts
as parsed documents, other texts exactly).
``python scripts/golden.py --write`` regenerates the stored values (only ever at a
commit whose results are known to be right: the baseline was 6c198b4).

The calls use the public API as the rebuild leaves it; where an argument order or a
name changes, this module changes with it, the stored values never do.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

GOLDEN_DIR = Path(__file__).parent / "data" / "golden"


def _q_samples(n: int, seed: int) -> np.ndarray:
    """Actuator values spread over the default strokes (some unreachable: flags count too)."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.2, 0.0, n), rng.uniform(0.0, 0.2, n),
                            rng.uniform(0.35, 0.55, n)])


def _fields(prefix: str, obj: Any, out: dict[str, Any]) -> None:
    """Every array field of a frozen result dataclass, under ``prefix.field``."""
    import dataclasses

    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, np.ndarray) and v.dtype.kind in "fiub":
            out[f"{prefix}.{f.name}"] = v
        elif isinstance(v, (float, int, np.floating, np.integer)) and not isinstance(v, bool):
            out[f"{prefix}.{f.name}"] = np.asarray(v)


def compute() -> dict[str, Any]:
    """The golden values: arrays and texts, compared by :func:`mismatches`."""
    import athenakin as ak
    from athenakin import analysis, collision, dynamics, sim

    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    out: dict[str, Any] = {}

    # kinematics: FK (16 solutions), IK, tool-tip IK, Jacobians, singularities
    q = _q_samples(64, 1)
    fk = ak.forward_kinematics(q, T, d, errors="flag")
    _fields("fk", fk, out)
    qr = sim.sample_reachable_q(16, T, d, rng=3)
    out["q_reachable"] = qr
    fk0 = ak.forward_kinematics(qr, T, d)
    _fields("fk_reachable", fk0, out)
    u345 = fk0.u[:, 0, 2:]  # slot 0
    q_ik, passive = ak.inverse_kinematics(T, u345, d)
    out["ik.q"] = q_ik
    _fields("ik.passive", passive, out)
    tips_b = fk0.tip[:, 0]
    tips_e = (tips_b - T[:3, 3]) @ T[:3, :3]
    q_tip, inst = ak.q_from_tool_tip(T, tips_e, d)
    out["tip_ik.q"] = q_tip
    _fields("tip_ik.inst", inst, out)
    out["jac.tool_tip_base"] = analysis.tool_tip_jacobian(qr, T, d)
    out["jac.tool_tip_inv"] = analysis.tool_tip_inverse_jacobian(qr, T, d)
    out["jac.parallel"] = analysis.parallel_jacobian(qr, design=d)
    sing = analysis.singularities(qr, T, d)
    _fields("sing", sing, out)

    # collision: clearance of the robot's bodies, every slot, with witnesses
    cl = collision.clearance(qr, T, d, slot="all")
    _fields("clearance", cl, out)

    # dynamics: inverse dynamics, mass matrix, statics, force capability
    rng = np.random.default_rng(5)
    qd = rng.normal(0.0, 0.05, qr.shape)
    qdd = rng.normal(0.0, 0.5, qr.shape)
    out["dyn.inverse_dynamics"] = np.asarray(dynamics.inverse_dynamics(qr, qd, qdd, T, d))
    out["dyn.mass_matrix"] = np.asarray(dynamics.mass_matrix(qr, T, d))
    _fields("dyn.statics", dynamics.statics(qr, T, d), out)
    _fields("dyn.capability", dynamics.force_capability(qr, T, d, f_max=50.0), out)
    out["dyn.max_tip_force"] = np.asarray(
        dynamics.max_tip_force(qr[0], [1.0, 0.0, 0.0], T, d, f_max=50.0))

    # calibration: synthetic measurements, then the fit
    from athenakin import calibration

    data = calibration.synthetic_measurements(T, d, n=40, rng=7)
    out["cal.q"] = data.q
    out["cal.tips"] = data.tips
    res = calibration.calibrate(data.q, data.tips, T, d)
    for name, value in sorted(res.parameters.items()):
        out[f"cal.param.{name}"] = np.asarray(value)

    # a design-study row (one design, few samples)
    from athenakin import synthesis

    task = synthesis.Task.from_toml(synthesis.example_task_path())
    row = synthesis.evaluate_design(d, task, samples=400, seed=2)
    for name, value in sorted(row.items()):
        out[f"study.{name}"] = np.asarray(value, dtype=float)

    # exports: text, compared exactly
    out["urdf"] = sim.urdf_from_design(T, d)
    out["mjcf"] = sim.mjcf_from_design(T, d)

    # an MCAP file of a tracked stream: every decoded message, numbers and texts
    from athenakin import ros

    stamps = np.arange(len(qr), dtype=np.int64) * 1_000_000
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "golden.mcap"
        ros.track_to_mcap(stamps, qr, path, T, d)
        out.update(_mcap_values(path))
    # the carriages lie on one line (the rail): their closest points are not unique, and
    # the numpy reference and the compiled kernel may pick different, equally close pairs
    # (collision/_distance.py); their distance is compared, their witnesses are not
    pair = collision.Bodies.default().pairs.index(("carriage_a", "carriage_b"))
    out["clearance.witness_points"][..., pair, :, :] = np.nan
    return out


def _mcap_values(path: Path) -> dict[str, Any]:
    """Every message of an MCAP file, decoded: per topic its numbers (float64, message by
    message, fields in order) and its texts (joined), read by the mcap library."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    numbers: dict[str, list[float]] = {}
    texts: dict[str, list[str]] = {}

    def walk(x: Any, topic: str) -> None:
        if isinstance(x, str):
            texts.setdefault(topic, []).append(x)
        elif isinstance(x, (bool, int, float, np.number)):
            numbers.setdefault(topic, []).append(float(x))
        elif isinstance(x, (list, tuple, np.ndarray)):
            for v in x:
                walk(v, topic)
        elif isinstance(x, (bytes, bytearray)):
            numbers.setdefault(topic, []).extend(float(b) for b in x)
        else:
            for name in x.__slots__:
                walk(getattr(x, name), topic)

    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages():
            numbers.setdefault(channel.topic, []).append(float(message.log_time))
            walk(decoded, channel.topic)

    def key(topic: str) -> str:
        return "mcap." + topic.strip("/").replace("/", ".")

    out: dict[str, Any] = {f"{key(t)}.numbers": np.array(v) for t, v in numbers.items()}
    out.update({f"{key(t)}.text": "\n".join(v) for t, v in texts.items()})
    return out


def save(values: dict[str, Any], folder: Path = GOLDEN_DIR) -> None:
    """Store ``values``: arrays in ``arrays.npz``, texts in ``<name>.txt``."""
    folder.mkdir(parents=True, exist_ok=True)
    arrays = {k: v for k, v in values.items() if isinstance(v, np.ndarray)}
    np.savez_compressed(folder / "arrays.npz", **arrays)
    for k, v in values.items():
        if isinstance(v, str):
            (folder / f"{k}.txt").write_text(v)


def load(folder: Path = GOLDEN_DIR) -> dict[str, Any]:
    """The stored values, as :func:`save` wrote them."""
    with np.load(folder / "arrays.npz") as z:
        values: dict[str, Any] = {k: z[k] for k in z.files}
    for p in sorted(folder.glob("*.txt")):
        values[p.stem] = p.read_text()
    return values


#: The texts that are XML documents (URDF, MJCF, the URDF on ``/robot_description``):
#: compared as parsed trees, their numbers to ``athenakin.testing.TEXT_RTOL`` of each
#: attribute's scale (a float's last printed digits depend on the CPU); every other text
#: (frame names, joint names, the status words) exactly.
XML_TEXTS = ("urdf", "mjcf", "mcap.robot_description.text")


def mismatches(values: dict[str, Any], stored: dict[str, Any]) -> list[str]:
    """One line per golden value that is missing, new or different.

    Arrays agree to ``IMPLEMENTATION_RTOL`` of each entry's magnitude with a floor of one
    unit (the arrays mix quantities: an MCAP topic's stamps in s and ns beside its
    positions in m), integer arrays exactly; texts as :data:`XML_TEXTS` says.
    """
    from athenakin.testing import scaled_differences, xml_differences

    bad = [f"missing: {k}" for k in sorted(set(stored) - set(values))]
    bad += [f"new (not stored): {k}" for k in sorted(set(values) - set(stored))]
    for k in sorted(set(values) & set(stored)):
        a, b = values[k], stored[k]
        if isinstance(b, np.ndarray):
            a = np.asarray(a)
            scale = np.maximum(1.0, np.abs(np.nan_to_num(b.astype(float), nan=0.0,
                                                         posinf=0.0, neginf=0.0)))
            why = scaled_differences(a, b, scale=scale if a.shape == b.shape else None)
            if why:
                bad.append(f"{k}: {why}")
        elif k in XML_TEXTS:
            bad += [f"{k}: {line}" for line in xml_differences(a, b)]
        elif a != b:
            bad.append(f"{k}: text differs")
    return bad
