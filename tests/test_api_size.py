"""No public function of athenakin takes more than 12 parameters (issue 28 item 3).

Every name in the ``__all__`` of the package and of each of its subpackages that is a
function is checked; ``*args`` and ``**kwargs`` count as one parameter each. A function
that grows past the bound takes a frozen options object instead (``PlanOptions``,
``TrackOptions``, ``CalibrationOptions``, ``StudyOptions``, ``PlotOptions``, ...).
"""

import importlib
import inspect
import pkgutil

import pytest

import athenakin

#: Most parameters of a public function.
MAX_PARAMETERS = 12

SUBPACKAGES = ["athenakin"] + sorted(f"athenakin.{m.name}"
                                     for m in pkgutil.iter_modules(athenakin.__path__)
                                     if m.ispkg)


def _module(name):
    try:
        return importlib.import_module(name)
    except ImportError as exc:      # an optional extra, or numba off (athenakin.fast)
        pytest.skip(f"{name} does not import here: {exc}")


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_public_functions_take_at_most_12_parameters(name):
    mod = _module(name)
    assert hasattr(mod, "__all__"), f"{name} has no __all__"
    big = {}
    for attr in mod.__all__:
        obj = getattr(mod, attr)
        if not inspect.isfunction(obj):
            continue
        n = len(inspect.signature(obj).parameters)
        if n > MAX_PARAMETERS:
            big[f"{name}.{attr}"] = n
    assert not big, f"more than {MAX_PARAMETERS} parameters (use an options object): {big}"


def test_every_subpackage_is_walked():
    assert {"athenakin.motion", "athenakin.ros", "athenakin.cli", "athenakin.calibration",
            "athenakin.synthesis", "athenakin.plot"} <= set(SUBPACKAGES)


def test_the_check_sees_a_function_too_large():
    def wide(a, b, c, d, e, f, g, h, i, j, k, m, *, n=None):
        return None

    assert len(inspect.signature(wide).parameters) > MAX_PARAMETERS
