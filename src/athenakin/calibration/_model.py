"""Measurement model of calibration: the tool tip (and axis) as a function of every parameter.

The tool tip of ATHENA depends on the mechanism only through ``O_s`` and the RCM point
``c`` (docs/conventions.md, the instrument): the instrument passes through ``O_s`` and
``c``, so with ``u = (c - O_s) / |c - O_s|`` (the ``p > 0`` branch: the instrument is
inserted through the RCM) the tip is ``t = O_s + L u``. ``O_s`` comes from the parallel
module (Eq. 7-10) at the true actuator values ``q_true = q_reading + offset``:

* ``A = (q1, 0, 0)``, ``B = (q2, 0, 0)``, ``h = (q1 - q2) / 2``, ``x_M = (q1 + q2) / 2``;
* in the plane ``x = x_M`` (coordinates ``(y, z)`` about ``M``), ``O_i = P`` is the
  intersection of ``|P| = r1 = sqrt(l1^2 - h^2)`` and ``|P - C| = q3`` with
  ``C = (m_y, l5)``, ``m_y = sqrt(l3^2 - h^2) + l2``, of the robot's assembly mode;
* ``O_s = (x_M, (1 + l4 / r1) P)``.

The Jacobian is analytic: implicit differentiation of the two circle equations
``F(P) = (|P|^2 - r1^2, |P - C|^2 - q3^2) / 2 = 0`` gives
``dP = -(dF/dP)^-1 (dF/dr1 dr1 + dF/dm_y dm_y + dF/dl5 dl5 + dF/dq3 dq3)`` with
``det(dF/dP) = P_z m_y - P_y l5`` (zero where the circles touch: the assembly modes meet);
the chain rule carries it through ``r1``, ``m_y``, ``h`` to the parameters, and
``dt = (I - L/rho (I - u u^T)) dO_s + L/rho (I - u u^T) dc + u dL`` (``rho = |c - O_s|``),
the same matrix as :func:`athenakin.analysis.tool_tip_jacobian`. Tests check it against
central differences and against :func:`athenakin.forward_kinematics`.

Tracker frame: a point ``p_b`` of the base frame is measured at ``p_t = R p_b + tau`` with
``R = exp([omega]) R0`` (``R0`` an initial alignment, ``omega`` a rotation vector, rad);
``d(R p)/d omega = -[R p]_x J_l(omega)`` with ``J_l`` the left Jacobian of SO(3).
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from .._typing import FloatArray
from .._validation import check_choice
from ..design import Design
from ..parallel._module import circle_terms

__all__ = [
    "PARAMETERS",
    "DEFAULT_PARAMETERS",
    "PARAMETER_UNITS",
    "PARAMETER_GROUPS",
    "MeasurementFrame",
    "Seed",
    "resolve_parameters",
    "parameter_vector",
    "calibrated_name",
    "design_from_parameters",
    "rotation_from_vector",
    "predict",
]

#: Every calibration parameter, in the order of the full parameter vector.
PARAMETERS = ("l1", "l2", "l3", "l4", "l5", "tool_length", "q1_offset", "q2_offset",
              "q3_offset", "rcm_x", "rcm_y", "rcm_z", "reg_rx", "reg_ry", "reg_rz", "reg_tx",
              "reg_ty", "reg_tz")
#: Parameters estimated by default (the tracker registration is added for ``frame="tracker"``).
DEFAULT_PARAMETERS = ("l1", "l2", "l3", "l4", "l5", "tool_length")
#: Unit of each parameter.
PARAMETER_UNITS = {n: ("rad" if n.startswith("reg_r") else "m") for n in PARAMETERS}
#: Short names for groups of parameters (accepted by ``params=``).
PARAMETER_GROUPS = {
    "lengths": ("l1", "l2", "l3", "l4", "l5"),
    "offsets": ("q1_offset", "q2_offset", "q3_offset"),
    "rcm": ("rcm_x", "rcm_y", "rcm_z"),
    "registration": ("reg_rx", "reg_ry", "reg_rz", "reg_tx", "reg_ty", "reg_tz"),
    "default": DEFAULT_PARAMETERS,
}
_INDEX = {n: i for i, n in enumerate(PARAMETERS)}
_REG = slice(12, 18)

MeasurementFrame = Literal["base", "tracker"]
#: What ``rng=`` accepts (``np.random.default_rng``).
Seed = int | np.random.Generator | None
_FRAMES = ("base", "tracker")


def resolve_parameters(params: object, frame: str) -> tuple[str, ...]:
    """The estimated parameter names, in :data:`PARAMETERS` order.

    Parameters
    ----------
    params : iterable of str or None
        Names of :data:`PARAMETERS` or of :data:`PARAMETER_GROUPS`; None means
        :data:`DEFAULT_PARAMETERS`.
    frame : {"base", "tracker"}
        With ``"tracker"`` the six registration parameters are always estimated.

    Returns
    -------
    tuple of str
        Names in :data:`PARAMETERS`, in that order, without repeats.

    Raises
    ------
    TypeError, ValueError
        Not an iterable of strings; an unknown name (the message lists the known ones);
        registration parameters with ``frame="base"``.
    """
    check_choice(frame, "frame", _FRAMES)
    if params is None:
        names: list[str] = list(DEFAULT_PARAMETERS)
    else:
        if isinstance(params, str):
            params = [p for p in params.replace(",", " ").split() if p]
        try:
            items = list(params)  # type: ignore[call-overload]
        except TypeError:
            raise TypeError(f"params: expected an iterable of parameter names, got "
                            f"{type(params).__name__}") from None
        names = []
        for p in items:
            if not isinstance(p, str):
                raise TypeError(f"params: expected parameter names (str), got {p!r}")
            if p in PARAMETER_GROUPS:
                names.extend(PARAMETER_GROUPS[p])
            elif p in _INDEX:
                names.append(p)
            else:
                raise ValueError(f"params: unknown parameter {p!r}; expected some of "
                                 f"{list(PARAMETERS)} or a group {list(PARAMETER_GROUPS)}")
    reg = PARAMETER_GROUPS["registration"]
    if frame == "tracker":
        names.extend(reg)
    elif any(n in reg for n in names):
        raise ValueError("params: the registration parameters reg_* only exist with "
                         "frame='tracker' (tips measured in the tracker's own frame)")
    if not names:
        raise ValueError("params: expected at least one parameter to estimate")
    return tuple(n for n in PARAMETERS if n in set(names))


def parameter_vector(design: Design, rcm: FloatArray, *,
                     q_offset: FloatArray | None = None,
                     registration: FloatArray | None = None) -> FloatArray:
    """The full parameter vector (18,) in :data:`PARAMETERS` order.

    ``registration`` holds ``(rx, ry, rz, tx, ty, tz)``: the rotation vector relative to
    the model's ``R0`` (rad) and the translation (m); zeros when None.
    """
    theta = np.zeros(len(PARAMETERS))
    theta[:5] = design.lengths
    theta[5] = design.tool_length
    if q_offset is not None:
        theta[6:9] = q_offset
    theta[9:12] = rcm
    if registration is not None:
        theta[_REG] = registration
    return theta


def calibrated_name(name: str) -> str:
    """The name of a design calibrated from the design ``name``: told apart from it.

    ``"athenakin reference design"`` -> ``"athenakin reference design, calibrated"``; an
    unnamed design gives ``"calibrated design"``.
    """
    return f"{name}, calibrated" if name else "calibrated design"


def design_from_parameters(theta: FloatArray, design: Design) -> Design:
    """``design`` with ``l1..l5`` and ``tool_length`` taken from a full parameter vector."""
    return dataclasses.replace(design, l1=float(theta[0]), l2=float(theta[1]),
                               l3=float(theta[2]), l4=float(theta[3]), l5=float(theta[4]),
                               tool_length=float(theta[5]))


def _skew(v: FloatArray) -> FloatArray:
    """Cross-product matrices ``[v]_x``, shape (..., 3, 3)."""
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def rotation_from_vector(omega: FloatArray) -> FloatArray:
    """Rotation matrix ``exp([omega]_x)`` of a rotation vector (3,), rad (scipy's Rotation)."""
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_rotvec(np.asarray(omega, dtype=float)).as_matrix())


def _left_jacobian(omega: FloatArray) -> FloatArray:
    """Left Jacobian ``J_l`` of SO(3): ``exp(omega + d) = exp(J_l d) exp(omega)`` to first order."""
    th = float(np.linalg.norm(omega))
    K = _skew(np.asarray(omega, dtype=float))
    if th < 1e-8:
        return np.eye(3) + 0.5 * K + K @ K / 6.0
    return (np.eye(3) + (1 - np.cos(th)) / th ** 2 * K
            + (th - np.sin(th)) / th ** 3 * K @ K)


def _rotate(R: FloatArray, J: FloatArray) -> FloatArray:
    """``R @ J`` for J of shape (n, 3, k) as one 2-D product (a batched 3x3 matmul is slow)."""
    n, _, k = J.shape
    return (np.swapaxes(J, 1, 2).reshape(-1, 3) @ R.T).reshape(n, k, 3).swapaxes(1, 2).copy()


@dataclasses.dataclass(frozen=True)
class Prediction:
    """Model output for N poses (private).

    Attributes
    ----------
    tip : ndarray, shape (N, 3)
        Tool tip in the measurement frame, m.
    axis : ndarray, shape (N, 3)
        Unit instrument direction (``O_s`` towards the RCM) in the measurement frame.
    tip_base, O_s : ndarray, shape (N, 3)
        Tip and ``O_s`` in the base frame, m.
    det : ndarray, shape (N,)
        ``P_z m_y - P_y l5`` (m^2): zero where the assembly modes meet.
    rho : ndarray, shape (N,)
        ``|c - O_s|`` (the insertion ``p``), m.
    J_tip, J_axis : ndarray, shape (N, 3, 18) or None
        Derivatives with respect to the full parameter vector.
    J_q : ndarray, shape (N, 3, 3) or None
        ``d tip / d q`` (readings) in the measurement frame.
    """

    tip: FloatArray
    axis: FloatArray
    tip_base: FloatArray
    O_s: FloatArray
    det: FloatArray
    rho: FloatArray
    J_tip: FloatArray | None = None
    J_axis: FloatArray | None = None
    J_q: FloatArray | None = None


def predict(theta: FloatArray, q: FloatArray, mode: FloatArray, *,
            R0: FloatArray | None = None, jacobian: bool = False) -> Prediction:
    """Tool tip and instrument axis for readings ``q`` (N, 3) under parameters ``theta`` (18,).

    ``mode`` (N,) holds the assembly mode (+1 / -1) of each pose. ``R0`` (3, 3) is the
    initial registration rotation: None means the base frame (``reg_*`` unused).
    Values are NaN where the module cannot be assembled with these parameters.
    """
    l1, l2, l3, l4, l5, L = theta[:6]
    qt = q + theta[6:9]
    c = theta[9:12]
    q1, q2, q3 = qt[:, 0], qt[:, 1], qt[:, 2]
    h = 0.5 * (q1 - q2)
    x_M = 0.5 * (q1 + q2)
    with np.errstate(invalid="ignore", divide="ignore"):
        r1 = np.sqrt(l1 * l1 - h * h)
        s3 = np.sqrt(l3 * l3 - h * h)
        m_y = s3 + l2
        d2, d, H, k = circle_terms(r1, m_y, l5, q3)
        a = np.sqrt(k) / (2 * d)
        Py = H * m_y / (2 * d2) - mode * a * l5 / d
        Pz = H * l5 / (2 * d2) + mode * a * m_y / d
        kk = 1.0 + l4 / r1
        O_s = np.stack([x_M, kk * Py, kk * Pz], axis=-1)
        v = c - O_s
        rho = np.linalg.norm(v, axis=-1)
        u = v / rho[:, None]
    tip_b = O_s + L * u
    det = Pz * m_y - Py * l5
    R = None if R0 is None else rotation_from_vector(theta[12:15]) @ R0
    tip, axis = (tip_b, u) if R is None else (tip_b @ R.T + theta[15:18], u @ R.T)
    if not jacobian:
        return Prediction(tip=tip, axis=axis, tip_base=tip_b, O_s=O_s, det=det, rho=rho)
    dOs_dz = _dOs_dz(theta[:6], h, q3, r1, s3, m_y, Py, Pz, det, kk)
    J_tip, J_axis, J_q = _parameter_jacobians(dOs_dz, u, rho, L, theta, R, tip_b, axis)
    return Prediction(tip=tip, axis=axis, tip_base=tip_b, O_s=O_s, det=det, rho=rho,
                      J_tip=J_tip, J_axis=J_axis, J_q=J_q)


def _dOs_dz(lengths: FloatArray, h: FloatArray, q3: FloatArray,
            r1: FloatArray, s3: FloatArray, m_y: FloatArray,
            Py: FloatArray, Pz: FloatArray, det: FloatArray,
            kk: FloatArray) -> FloatArray:
    """``d O_s / d z``, shape (n, 3, 8), ``z = (q1, q2, q3, l1..l5)`` (true ``q``).

    Implicit differentiation of the two circle equations (module docstring), then the
    chain rule through ``r1``, ``m_y``, ``h`` and ``O_s = (x_M, (1 + l4 / r1) P)``.
    """
    l1, _, l3, l4, l5 = lengths[:5]
    n = h.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        # dP/d(r1, m_y, l5, q3) = -A^-1 F_theta with A = [[Py, Pz], [Py - m_y, Pz - l5]]
        # and F_theta = [[-r1, 0, 0, 0], [0, -(Py - m_y), -(Pz - l5), -q3]] (sparse: by hand)
        inv = 1.0 / det
        a00, a01 = (Pz - l5) * inv, -Pz * inv
        a10, a11 = -(Py - m_y) * inv, Py * inv
        dP_dr1 = np.stack([a00 * r1, a10 * r1], axis=-1)               # (n, 2)
        f1, f2, f3 = Py - m_y, Pz - l5, q3
        dP_dmy = np.stack([a01 * f1, a11 * f1], axis=-1)
        dP_dl5 = np.stack([a01 * f2, a11 * f2], axis=-1)
        dP_dq3 = np.stack([a01 * f3, a11 * f3], axis=-1)
        # chain rule to z = (q1, q2, q3, l1, l2, l3, l4, l5) (true q)
        dr1_dh, dmy_dh = -h / r1, -h / s3
        dP_dh = dP_dr1 * dr1_dh[:, None] + dP_dmy * dmy_dh[:, None]
        dP_dz = np.zeros((n, 2, 8))
        dP_dz[:, :, 0] = 0.5 * dP_dh
        dP_dz[:, :, 1] = -0.5 * dP_dh
        dP_dz[:, :, 2] = dP_dq3
        dP_dz[:, :, 3] = dP_dr1 * (l1 / r1)[:, None]
        dP_dz[:, :, 4] = dP_dmy
        dP_dz[:, :, 5] = dP_dmy * (l3 / s3)[:, None]
        dP_dz[:, :, 7] = dP_dl5
        dr1_dz = np.zeros((n, 8))
        dr1_dz[:, 0], dr1_dz[:, 1], dr1_dz[:, 3] = 0.5 * dr1_dh, -0.5 * dr1_dh, l1 / r1
        dk_dz = -(l4 / (r1 * r1))[:, None] * dr1_dz
        dk_dz[:, 6] += 1.0 / r1
        P = np.stack([Py, Pz], axis=-1)
        dOs_dz = np.zeros((n, 3, 8))
        dOs_dz[:, 0, 0] = dOs_dz[:, 0, 1] = 0.5
        dOs_dz[:, 1:, :] = kk[:, None, None] * dP_dz + P[:, :, None] * dk_dz[:, None, :]
    return dOs_dz


def _parameter_jacobians(dOs_dz: FloatArray, u: FloatArray,
                         rho: FloatArray, L: float, theta: FloatArray,
                         R: FloatArray | None, tip_b: FloatArray,
                         axis: FloatArray
                         ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``J_tip``, ``J_axis`` (n, 3, 18) and ``J_q`` (n, 3, 3) from ``d O_s / d z``.

    ``dt = (I - L G) dO_s + L G dc + u dL`` with ``G = (I - u u^T) / rho``; with a
    registration ``R`` (None: the base frame) the rows are rotated into the tracker
    frame and the columns of ``reg_*`` filled.
    """
    n = dOs_dz.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        Pm = np.eye(3) - u[:, :, None] * u[:, None, :]
        G = Pm / rho[:, None, None]                        # du/dc = -du/dO_s
        # G @ dOs_dz without a batched 3x3 matmul (slow for tiny matrices)
        uX = np.sum(u[:, :, None] * dOs_dz, axis=1)        # (n, 8)
        GX = (dOs_dz - u[:, :, None] * uX[:, None, :]) / rho[:, None, None]
    J_tip = np.zeros((n, 3, len(PARAMETERS)))
    J_axis = np.zeros((n, 3, len(PARAMETERS)))
    Jt_z = dOs_dz - L * GX                                 # (I - L G) dO_s/dz, (n, 3, 8)
    Ju_z = -GX
    for J, Jz in ((J_tip, Jt_z), (J_axis, Ju_z)):
        J[:, :, 0:5] = Jz[:, :, 3:8]                      # l1..l5
        J[:, :, 6:9] = Jz[:, :, 0:3]                      # offsets: q_true = q + offset
    J_tip[:, :, 5] = u
    J_tip[:, :, 9:12] = L * G
    J_axis[:, :, 9:12] = G
    J_q = Jt_z[:, :, 0:3]
    if R is not None:
        J_tip, J_axis, J_q = (_rotate(R, J) for J in (J_tip, J_axis, J_q))
        Jl = _left_jacobian(theta[12:15])
        J_tip[:, :, 12:15] = -(_skew(tip_b @ R.T).reshape(-1, 3) @ Jl).reshape(n, 3, 3)
        J_tip[:, :, 15:18] = np.eye(3)
        J_axis[:, :, 12:15] = -(_skew(axis).reshape(-1, 3) @ Jl).reshape(n, 3, 3)
    return J_tip, J_axis, J_q
