"""The app on a planned set-up (``athenakin app --setup SETUP.toml --patient PATIENT.toml``):
its RCM frame and design, the patient drawn where T_p_b places it, the port at the RCM, the
tip at the target's centre, the patient's surfaces among the obstacles; bad files refused
before the server starts. In process (a real viser server, no browser)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("viser")
pytest.importorskip("trimesh")
pytest.importorskip("coal")

from athenakin import q_from_tool_tip  # noqa: E402
from athenakin.design import Design  # noqa: E402
from athenakin.errors import InvalidInputError  # noqa: E402
from athenakin.synthesis import (  # noqa: E402
    Patient,
    phantom,
    reference_decision,
    setup_environment,
    setup_from_decision,
    write_patient,
)

#: float32 vertices of the scene nodes: about 3e-8 m of rounding at 0.5 m.
F32_TOL_M = 1e-6


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """A phantom's files and a set-up file, with a design of its own name."""
    folder = tmp_path_factory.mktemp("planned")
    patient = phantom(resolution=12)
    design = Design.default()
    setup = setup_from_decision(patient, reference_decision(patient, design,
                                                            yaw=np.radians(270), roll=0.4))
    import dataclasses

    design = dataclasses.replace(design, name="planned design")
    return {"patient": patient, "setup": setup, "design": design,
            "patient_file": write_patient(patient, folder / "patient"),
            "setup_file": setup.write(folder / "setup.toml", design=design)}


def _patient_frame(setup, p_b):
    """Points (..., 3) of the base frame in the patient's."""
    return np.asarray(p_b, dtype=float) @ setup.T_p_b[:3, :3].T + setup.T_p_b[:3, 3]


def test_the_app_starts_on_the_planned_setup_with_its_patient(planned):
    from athenakin.app import AthenaApp
    from athenakin.collision import clearance

    # the patient as the app reads it (STL files: float32 coordinates)
    patient, setup = Patient.from_toml(planned["patient_file"]), planned["setup"]
    app = AthenaApp(port=0, backend="numpy", planned=planned["setup_file"],
                    patient=planned["patient_file"])
    try:
        assert app.errors == []
        np.testing.assert_allclose(app.setup.T_b_e, setup.T_b_e, rtol=0, atol=1e-15)
        assert app.setup.design == planned["design"]
        # the tool tip at the target's centre, through the port: the exact IK's q, and its
        # FK's tip there
        T_p_e = setup.T_p_e
        tip_e = T_p_e[:3, :3].T @ (patient.target_centroid - T_p_e[:3, 3])
        q_ref, res = q_from_tool_tip(setup.T_b_e, tip_e, planned["design"], backend="numpy")
        np.testing.assert_allclose(app.q, q_ref, rtol=0, atol=1e-12)
        assert app.slot == (0 if res.mode == 1 else 8)
        tip_p = _patient_frame(setup, app.view.readouts.tip_b)
        np.testing.assert_allclose(tip_p, patient.target_centroid, rtol=0, atol=1e-12)
        nodes = app.setup_tab.nodes
        assert sorted(nodes) == sorted([f"patient_{m.name}" for m in patient.meshes]
                                       + ["port", "nominal_axis"])
        for m in patient.meshes:       # each mesh where T_p_b places it, its own faces
            h = nodes[f"patient_{m.name}"]
            np.testing.assert_allclose(_patient_frame(setup, h.vertices), m.vertices, rtol=0,
                                       atol=F32_TOL_M)
            np.testing.assert_array_equal(h.faces, m.faces)
        np.testing.assert_allclose(nodes["port"].position, setup.T_b_e[:3, 3], rtol=0,
                                   atol=F32_TOL_M)                # the port is the RCM
        axis = np.asarray(nodes["nominal_axis"].points)[0]
        np.testing.assert_allclose(_patient_frame(setup, axis[1]), patient.target_centroid,
                                   rtol=0, atol=F32_TOL_M)
        # the obstacles are the planner's: the clearance read-out checks the patient
        env = setup_environment(patient, setup)
        assert app.bodies.environment == env
        g = app.view.geometry
        c = clearance(g.q, g.T_b_e, g.design, slot=g.slot, environment=env)
        assert app.bodies.clearance_of(g).clearance == pytest.approx(float(c.min_distance),
                                                                      rel=0, abs=1e-12)
        app.setup_tab.patient_cb.value = False                   # the checkbox hides them
        assert not any(h.visible for h in nodes.values())
    finally:
        app.stop()


def test_teleoperation_on_a_planned_setup_guards_against_the_patient(planned, monkeypatch):
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy", planned=planned["setup_file"],
                    patient=planned["patient_file"])
    try:
        tab = app.teleop
        monkeypatch.setattr(app.server, "get_clients", lambda: {0: object()})  # a page open
        tab.start()
        try:
            assert tab.running, tab.readout.content
            assert tab.tele.robot.environment == app.bodies.environment   # the guard's
            fixtures = sorted(n for n in tab._nodes if n.startswith("fixture_"))
            assert fixtures == sorted(f"fixture_{o.name}"
                                      for o in app.bodies.environment.obstacles)
        finally:
            tab.stop()
    finally:
        app.stop()


def test_the_setup_tab_reads_a_setup_file_as_the_rcm_frame(planned):
    from athenakin.app import AthenaApp

    app = AthenaApp(port=0, backend="numpy")
    try:
        assert not app.setup_tab.nodes and not hasattr(app.setup_tab, "patient_cb")
        app.setup_tab.rcm_path.value = str(planned["setup_file"])
        app.setup_tab.apply()
        np.testing.assert_allclose(app.setup.T_b_e, planned["setup"].T_b_e, rtol=0, atol=0)
    finally:
        app.stop()


def test_a_setup_and_patient_given_as_objects_and_a_design_that_overrides(planned):
    from athenakin.app import AthenaApp

    other = Design.default()
    app = AthenaApp(None, other, port=0, backend="numpy", planned=planned["setup"],
                    patient=planned["patient"])
    try:
        assert app.errors == [] and app.setup.design == other
        assert "patient_skin" in app.setup_tab.nodes
    finally:
        app.stop()


def test_bad_planned_inputs_stop_the_start(planned, tmp_path, capsys):
    from athenakin.app import AthenaApp, launch

    with pytest.raises(InvalidInputError, match="patient: .*--setup"):
        launch(port=0, backend="numpy", patient=planned["patient_file"])
    with pytest.raises(InvalidInputError, match="T_b_e"):
        launch(port=0, backend="numpy", planned=planned["patient_file"])   # not a set-up
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        launch(port=0, backend="numpy", planned=tmp_path / "nope.toml")
    with pytest.raises(InvalidInputError, match="T_b_e: expected none with planned="):
        launch(planned["setup"].T_b_e, port=0, backend="numpy", planned=planned["setup"])
    with pytest.raises(TypeError, match="planned: expected Setup"):
        AthenaApp(port=0, backend="numpy", planned=3)
    with pytest.raises(TypeError, match="patient: expected Patient"):
        AthenaApp(port=0, backend="numpy", planned=planned["setup"], patient=3)
    assert "ATHENA at" not in capsys.readouterr().out                       # never served


def test_the_app_command_takes_setup_and_patient(planned, capsys):
    from athenakin.cli import build_parser, main

    args = build_parser().parse_args(["app", "--setup", "s.toml", "--patient", "p.toml"])
    assert str(args.setup) == "s.toml" and str(args.patient) == "p.toml"
    assert main(["app", "--port", "0", "--backend", "numpy", "--setup",
                 str(planned["setup_file"]), "--rcm-file", "x.json"]) == 1
    assert "--setup" in capsys.readouterr().err
    assert main(["app", "--port", "0", "--backend", "numpy", "--patient",
                 str(planned["patient_file"])]) == 1
    err = capsys.readouterr().err
    assert "--setup" in err and len(err.strip().splitlines()) == 1
