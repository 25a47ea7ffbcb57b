"""Ball-arithmetic helpers over python-flint's ``arb`` (private).

Every function here is rigorous: it returns a ball that contains the exact
value for every exact input inside the argument balls, or says that it could
not decide (``None`` / sign 0).
"""

from __future__ import annotations

from typing import Any

__all__ = ["sign", "angle", "wrap", "ball", "import_flint"]


def import_flint() -> Any:
    """Import python-flint, or say which extra installs it."""
    try:
        import flint
    except ImportError as exc:
        raise ModuleNotFoundError("athenakin.certified needs python-flint: "
                                  "pip install 'athenakin[certified]'", name="flint") from exc
    return flint


def ball(arb: Any, x: float, rel: float) -> Any:
    """The ball ``x * (1 +- rel)`` (exactly ``x`` when ``rel == 0``)."""
    if rel == 0.0 or x == 0.0:
        return arb(x)
    return arb(x, abs(x) * rel)


def sign(x: Any) -> int:
    """+1 if ``x > 0`` is proven, -1 if ``x < 0`` is proven, 0 if the ball holds 0."""
    if x > 0:
        return 1
    if x < 0:
        return -1
    return 0


def angle(y: Any, x: Any, pi: Any) -> Any | None:
    """``atan2(y, x)`` as a ball, or None when neither ``x`` nor ``y`` excludes 0.

    The branch is chosen from the proven signs so that the ball never straddles
    the cut at +-pi: for ``x < 0`` and ``y`` of unknown sign the result is a ball
    about ``+pi`` that may extend beyond it (an angle is meant modulo 2 pi).
    """
    sx = sign(x)
    if sx > 0:
        return (y / x).atan()
    sy = sign(y)
    if sy > 0:
        return pi / 2 - (x / y).atan()
    if sy < 0:
        return -pi / 2 - (x / y).atan()
    if sx < 0:
        return (y / x).atan() + pi
    return None


def wrap(a: Any, pi: Any) -> Any:
    """Shift an angle ball by a multiple of 2 pi so that its midpoint lies in (-pi, pi]."""
    m = float(a.mid())
    if m > 3.141592653589793:
        return a - 2 * pi
    if m <= -3.141592653589793:
        return a + 2 * pi
    return a
