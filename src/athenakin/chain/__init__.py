"""The serial UPS chain (paper Eq. 5, 6, 11, 12): forward map and its 8 solutions."""

from ._ups import (
    CLOSURE_TOL,
    DEGENERATE_TOL,
    P_ZERO_TOL,
    SERIAL_P_SIGN,
    SERIAL_UJOINT,
    SERIAL_WRIST,
    UPSSolution,
    closure_residual,
    rotation_u_pair,
    ups_solutions,
    ups_study,
    ups_transform,
)

__all__ = [
    "CLOSURE_TOL",
    "DEGENERATE_TOL",
    "P_ZERO_TOL",
    "SERIAL_P_SIGN",
    "SERIAL_UJOINT",
    "SERIAL_WRIST",
    "UPSSolution",
    "closure_residual",
    "rotation_u_pair",
    "ups_solutions",
    "ups_study",
    "ups_transform",
]
