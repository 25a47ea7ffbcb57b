"""Run the Examples sections of the core modules' docstrings."""

import doctest
import importlib

import pytest

MODULES = ["athenakin.robot._fk", "athenakin.robot._ik", "athenakin.study._study",
           "athenakin.chain._ups", "athenakin.parallel._module", "athenakin.design",
           "athenakin.study._interop", "athenakin.sim._layout", "athenakin._serialize",
           "athenakin.collision._bodies", "athenakin.collision._clearance",
           "athenakin.dynamics._api", "athenakin._robot_model", "athenakin._mechanism._placement",
           "athenakin.dynamics._loop"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    mod = importlib.import_module(name)
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.failed == 0
