"""The CLI calls the public functions (backend="auto"), not the numpy reference (issue 24)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import athenakin as ak
from athenakin.cli import _demo, _fk, _ik, main


@pytest.mark.parametrize(("module", "names"), [
    (_fk, ["forward_kinematics"]),
    (_ik, ["inverse_kinematics", "q_from_instrument", "q_from_tool_tip"]),
    (_demo, ["forward_kinematics", "inverse_kinematics"]),
])
def test_cli_modules_use_the_public_functions(module, names) -> None:
    for name in names:
        assert getattr(module, name) is getattr(ak, name), f"{module.__name__}.{name}"
        assert getattr(module, name) is not getattr(ak.robot, name)


def test_fk_cli_prints_what_the_public_function_returns(capsys) -> None:
    q = [-0.10, 0.10, 0.45]
    assert main(["fk", *map(str, q), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    d = ak.Design.default()
    sol = ak.forward_kinematics(q, ak.default_rcm_frame(d), d)
    p = np.array([np.nan if s["p_m"] is None else s["p_m"] for s in out["solutions"]])
    np.testing.assert_allclose(p, sol.p, rtol=0, atol=1e-12, equal_nan=True)
