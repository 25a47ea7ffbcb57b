"""Backend dispatch: the public kinematics functions run compiled by default (private module).

Layers, each importing only those below it::

    numpy reference   robot (FK, IK, robot._jacobians), parallel, chain, study, design
          ^
    compiled kernels  fast (numba; falls back to the reference for what it cannot do)
          ^
    dispatch          this module: ``backend="auto" | "numpy" | "numba"``
          ^
    public names      athenakin.forward_kinematics, ..., athenakin.analysis.*_jacobian

``backend="auto"`` (the default) runs the compiled kernels of :mod:`athenakin.fast`
where numba imports, and the numpy reference otherwise (a platform without numba
wheels, or ``ATHENAKIN_BACKEND=numpy`` in the environment): :mod:`athenakin._backend`
decides, for this module as for every compiled path. Both return the same values to
1e-12, the same reason codes and raise the same errors (tested).

The compiled kernels are cached on disk (numba ``cache=True``) next to their
sources, or under the user cache directory (``~/.cache/athenakin/numba``) when the
package directory is not writable. A kernel that is not in the cache is announced
by one line on stderr before it compiles (the first time, about a minute); loading
numba and the cache later (about a second) prints nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from ._backend import _STATE as _BACKEND
from ._backend import (
    Backend,
    numba_available,  # noqa: F401 - re-exported: the tests and the CLI ask it here
    resolve_backend,
)
from ._typing import FloatArray
from ._validation import OPTION_AUTO, is_option
from .chain._ups import CLOSURE_TOL, DEGENERATE_TOL, P_ZERO_TOL
from .design import Design
from .parallel._module import TANGENT_TOL
from .robot import _fk as _ref_fk
from .robot import _ik as _ref_ik
from .robot import _jacobians as _ref_jac
from .robot._common import ErrorPolicy
from .robot._fk import FKMethod, FKSolution
from .robot._ik import IK_SINGULAR_TOL, InstrumentIK, PassiveJoints
from .robot._jacobians import Frame

_F8 = np.dtype(np.float64)
_STATE: dict[str, Any] = {}     # "api": fast._api, "jac": fast._jac_api
_WARM: set[str] = set()         # entry points whose first compiled call has returned
_R = TypeVar("_R")


# --- backend resolution: athenakin._backend decides ----------------------------------------
def _compiled_choice(backend: object) -> bool:
    """``backend`` is "auto" or "numba" (a str; False for any other object: it is checked later)."""
    return is_option(backend, "auto") or is_option(backend, "numba")


def _api() -> ModuleType:
    if "api" not in _STATE:
        from .fast import _api

        _STATE["api"] = _api
    return _STATE["api"]  # type: ignore[no-any-return]


def _jac() -> ModuleType:
    if "jac" not in _STATE:
        from .fast import _jac_api

        _STATE["jac"] = _jac_api
    return _STATE["jac"]  # type: ignore[no-any-return]


def _first(name: str, call: Callable[[], _R]) -> _R:
    """The first compiled call of an entry point: ``call()``, then ``name`` marked warm.

    A kernel that is not in numba's cache is announced on stderr before it compiles,
    one line per kernel area (:func:`athenakin._backend.numba_module` registers the
    notice), so a long first call is never silent and a cached one never speaks.
    """
    try:
        return call()
    finally:
        _WARM.add(name)


def warmup(design: Design | None = None, *, backend: Backend = "auto") -> int:
    """Run every compiled entry point once, single pose and batch: compiles or loads the kernels.

    Parameters
    ----------
    design : Design, optional
    backend : {"auto", "numpy", "numba"}, keyword-only
        Nothing to warm where it resolves to the numpy reference
        (:func:`athenakin._backend.resolve_backend`).

    Returns
    -------
    int
        Number of entry points run (0 on the numpy reference).
    """
    if not resolve_backend(backend):
        return 0
    from .robot._setup import REFERENCE_Q, default_rcm_frame

    T = default_rcm_frame(design)
    q = np.array(REFERENCE_Q, dtype=float)
    qq = np.stack([q, q])
    sol = forward_kinematics(q, T, design, errors="flag")
    forward_kinematics(qq, T, design, errors="flag")
    forward_kinematics(qq, T, design, errors="flag", fields=("p", "u", "valid"))
    u345 = np.nan_to_num(np.ascontiguousarray(sol.u[0, 2:]))
    inverse_kinematics(T, u345, design, errors="flag")
    inverse_kinematics(T, np.stack([u345, u345]), design, errors="flag")
    inverse_kinematics(T, np.stack([u345, u345]), design, errors="flag", fields=("valid",))
    tip = np.array([0.0, 0.0, 0.1])
    q_from_tool_tip(T, tip, design, errors="flag")
    q_from_tool_tip(T, np.stack([tip, tip]), design, errors="flag")
    q_from_instrument(T, tip, 0.2, design, errors="flag")
    q_from_instrument(T, np.stack([tip, tip]), np.array([0.2, 0.2]), design, errors="flag")
    names = ("parallel_jacobian", "parallel_inverse_jacobian", "parallel_twist_jacobian",
             "instrument_jacobian", "instrument_inverse_jacobian", "tool_tip_jacobian",
             "tool_tip_inverse_jacobian")
    for name in names:
        fn = globals()[name]
        for x in (q, qq):
            if name.startswith("parallel"):
                fn(x, design)
            else:
                fn(x, None, design)
    return 4 + len(names)


# --- whole robot ---------------------------------------------------------------------------
def forward_kinematics(q: ArrayLike, T_b_e: ArrayLike, design: Design | None = None, *,
                       method: FKMethod = "closed", errors: ErrorPolicy = "auto",
                       tangent_tol: float = TANGENT_TOL, degenerate_tol: float = DEGENERATE_TOL,
                       p_zero_tol: float = P_ZERO_TOL, closure_tol: float = CLOSURE_TOL,
                       fields: tuple[str, ...] | None = None, backend: Backend = "auto"
                       ) -> FKSolution:
    """All (up to) 16 configurations of the robot for actuator values ``q`` (Section 3).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame E in the base frame (set-up, fixed by the surgeon). Broadcasts with ``q``.
    design : Design, optional
        Defaults to :meth:`~athenakin.Design.default`.
    method : {"closed", "algebraic"}, keyword-only
        How the serial chain is solved: ``"closed"`` (default) by the closed form of
        :func:`athenakin.chain.ups_solutions`; ``"algebraic"`` the paper's way (Section
        3.2: the quadratic in ``p`` and the remaining joints from the cached
        derivation, :func:`athenakin.symbolic.forward_kinematics_algebraic`). Both
        return the same slots; the parallel module is shared.
    errors : {"auto", "raise", "flag"}, keyword-only
        ``"raise"``: an item with no valid slot raises the matching
        :class:`~athenakin.errors.KinematicsError`; ``"flag"``: never raise for
        a domain failure, report it in ``valid``/``reason``; ``"auto"``
        (default): raise for a single item, flag in a batch.
    tangent_tol, degenerate_tol, p_zero_tol, closure_tol : float, keyword-only
        See :data:`~athenakin.parallel.TANGENT_TOL`, :data:`~athenakin.chain.DEGENERATE_TOL`,
        :data:`~athenakin.chain.P_ZERO_TOL`, :data:`~athenakin.chain.CLOSURE_TOL`.
    fields : tuple of str, optional, keyword-only
        Compute and return only these arrays (names in :data:`athenakin.robot.FK_FIELDS`, e.g.
        ``("p", "u", "valid")`` for a sweep); ``None`` (default): all. The result
        always holds ``item_reason``; reading an array left out raises
        ``AttributeError``.
    backend : {"auto", "numpy", "numba"}, keyword-only
        ``"auto"`` (default): the compiled kernels of :mod:`athenakin.fast` where
        numba imports, else the numpy reference; ``"numba"``: compiled (ImportError
        without numba); ``"numpy"``: the reference. Same results to 1e-12, same
        reason codes and errors.

    Returns
    -------
    FKSolution

    Raises
    ------
    TypeError, InvalidInputError
        Wrong type/shape, or NaN/inf input with ``errors`` resolving to raise.
    StrokeLimitError, OutOfWorkspaceError, DegenerateChainError, SingularConfigurationError
        With ``errors`` resolving to raise, when an item has no valid slot.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> d = ak.Design.default()
    >>> sol = ak.forward_kinematics([-0.10, 0.10, 0.45], ak.default_rcm_frame(d), d)
    >>> int(sol.n_solutions)
    16
    """
    if ("fk" in _WARM and _BACKEND["numba"]
            and (backend is OPTION_AUTO or _compiled_choice(backend))):
        # the lean single call (control loops): fast._api's one guard, then the kernel
        sol = _STATE["api"].lean_fk(q, T_b_e, design, method, errors, tangent_tol,
                                    degenerate_tol, p_zero_tol, closure_tol, fields)
        if sol is not None:
            return sol  # type: ignore[no-any-return]
        return _STATE["api"].forward_kinematics(  # type: ignore[no-any-return]
            q, T_b_e, design, method=method, errors=errors, tangent_tol=tangent_tol,
            degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol, closure_tol=closure_tol,
            fields=fields)
    kw = dict(method=method, errors=errors, tangent_tol=tangent_tol,
              degenerate_tol=degenerate_tol, p_zero_tol=p_zero_tol, closure_tol=closure_tol,
              fields=fields)
    if resolve_backend(backend):
        api = _api()
        return _first("fk", lambda: api.forward_kinematics(q, T_b_e, design, **kw))
    return _ref_fk.forward_kinematics(q, T_b_e, design, **kw)  # type: ignore[arg-type]


def inverse_kinematics(T_b_e: ArrayLike, u345: ArrayLike, design: Design | None = None, *,
                       errors: ErrorPolicy = "auto", singular_tol: float = IK_SINGULAR_TOL,
                       closure_tol: float = CLOSURE_TOL, fields: tuple[str, ...] | None = None,
                       backend: Backend = "auto") -> tuple[FloatArray, PassiveJoints]:
    """Actuator values for a given RCM frame and spherical-joint angles (paper Section 4).

    Parameters
    ----------
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame E in the base frame.
    u345 : array-like, shape (..., 3)
        ``(u3, u4, u5)`` of the spherical joint, radians. Broadcasts with ``T_b_e``.
    design : Design, optional
    errors : {"auto", "raise", "flag"}, keyword-only
        Failure policy, as in :func:`forward_kinematics`.
    singular_tol : float, keyword-only
        See :data:`athenakin.robot.IK_SINGULAR_TOL`.
    closure_tol : float, keyword-only
        Largest closure residual accepted.
    fields : tuple of str, optional, keyword-only
        Compute and return only these arrays of ``passive`` (names in
        :data:`athenakin.robot.IK_FIELDS`; ``q`` is always returned); ``None`` (default): all.
    backend : {"auto", "numpy", "numba"}, keyword-only
        As in :func:`forward_kinematics`.

    Returns
    -------
    q : ndarray, shape (..., 3)
        ``(q1, q2, q3)``, m; NaN where ``passive.valid`` is False.
    passive : PassiveJoints
        ``p``, ``u1..u5``, assembly mode, ``T_b_s``, residual, validity and reason.

    Raises
    ------
    SingularConfigurationError
        ``IK_SINGULAR``: a continuum of ``q`` (``cos u1 = 0`` or ``sin u1 sin u2 = 0``).
    OutOfWorkspaceError, StrokeLimitError
        The pose needs ``O_s`` where the parallel module cannot put it.

    Examples
    --------
    >>> import numpy as np, athenakin as ak
    >>> d = ak.Design.default()
    >>> T = ak.default_rcm_frame(d)
    >>> sol = ak.forward_kinematics([-0.10, 0.10, 0.45], T, d)
    >>> q, passive = ak.inverse_kinematics(T, sol.u[0, 2:], d)
    >>> np.allclose(q, [-0.10, 0.10, 0.45], atol=1e-12)
    True
    """
    if ("ik" in _WARM and _BACKEND["numba"]
            and (backend is OPTION_AUTO or _compiled_choice(backend))):
        res = _STATE["api"].lean_ik(T_b_e, u345, design, errors, singular_tol, closure_tol,
                                    fields)
        if res is not None:            # the lean single call: fast._api's one guard
            return res  # type: ignore[no-any-return]
        return _STATE["api"].inverse_kinematics(  # type: ignore[no-any-return]
            T_b_e, u345, design, errors=errors, singular_tol=singular_tol,
            closure_tol=closure_tol, fields=fields)
    if resolve_backend(backend):
        api = _api()
        return _first("ik", lambda: api.inverse_kinematics(
            T_b_e, u345, design, errors=errors, singular_tol=singular_tol,
            closure_tol=closure_tol, fields=fields))
    return _ref_ik.inverse_kinematics(T_b_e, u345, design, errors=errors,
                                      singular_tol=singular_tol, closure_tol=closure_tol,
                                      fields=fields)


def q_from_instrument(T_b_e: ArrayLike, direction_e: ArrayLike, p: ArrayLike,
                      design: Design | None = None, *, errors: ErrorPolicy = "auto",
                      backend: Backend = "auto") -> tuple[FloatArray, InstrumentIK]:
    """Actuator values for an instrument direction about the RCM and an insertion ``p``.

    ``O_s = RCM - p * d`` with ``d`` the instrument direction; the parallel
    module's IK then gives the unique ``q`` (the passive joints have 4
    solutions; :func:`~athenakin.forward_kinematics` lists them).

    Parameters
    ----------
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame.
    direction_e : array-like, shape (..., 3)
        Instrument direction in frame E (pointing from ``O_s`` through the RCM
        into the patient); normalised here. See :func:`athenakin.robot.direction_from_angles`.
    p : array-like, shape (...)
        Distance from ``O_s`` to the RCM along the direction, m.
    design : Design, optional
    errors : {"auto", "raise", "flag"}, keyword-only
        Failure policy, as in :func:`forward_kinematics`.
    backend : {"auto", "numpy", "numba"}, keyword-only
        As in :func:`forward_kinematics`.

    Returns
    -------
    q : ndarray, shape (..., 3)
        ``(q1, q2, q3)``, m; NaN where ``result.valid`` is False.
    result : InstrumentIK
        ``p``, the direction in the base frame, ``O_s``, assembly mode, validity,
        reason and the bound on the error of ``q``.
    """
    if ("line" in _WARM and _BACKEND["numba"]
            and (backend is OPTION_AUTO or _compiled_choice(backend))):
        res = _STATE["api"].lean_line(T_b_e, direction_e, p, design, errors)
        if res is not None:            # the lean single call: fast._api's one guard
            return res  # type: ignore[no-any-return]
    return _line(T_b_e, direction_e, p, design, errors, backend)


def q_from_tool_tip(T_b_e: ArrayLike, tip_e: ArrayLike, design: Design | None = None, *,
                    errors: ErrorPolicy = "auto", backend: Backend = "auto"
                    ) -> tuple[FloatArray, InstrumentIK]:
    """Actuator values that put the tool tip at a point, the instrument through the RCM.

    The tip is at ``O_s + L d`` (``L = design.tool_length``) and the instrument
    passes through the RCM, so ``d = tip / |tip|`` and ``p = L - |tip|`` (tip in
    frame E). The tip must be beyond the RCM (inserted), ``0 < |tip| < L``;
    otherwise the reason is ``INSERTION_RANGE`` (a tip exactly at the RCM leaves
    the direction undefined: ``IK_SINGULAR``).

    Parameters
    ----------
    T_b_e : array-like, shape (..., 4, 4)
        RCM frame E in the base frame.
    tip_e : array-like, shape (..., 3)
        Tool-tip position in the RCM frame E, m.
    design : Design, optional
    errors, backend : keyword-only
        As in :func:`q_from_instrument`.

    Returns
    -------
    q, result : ndarray (..., 3), InstrumentIK
        As in :func:`q_from_instrument`, with ``result.p = L - |tip|``.
    """
    if ("line" in _WARM and _BACKEND["numba"]
            and (backend is OPTION_AUTO or _compiled_choice(backend))):
        res = _STATE["api"].lean_line(T_b_e, tip_e, None, design, errors)
        if res is not None:            # the lean single call: fast._api's one guard
            return res  # type: ignore[no-any-return]
    return _line(T_b_e, tip_e, None, design, errors, backend)


def _line(T_b_e: ArrayLike, v: ArrayLike, p: ArrayLike | None, design: Design | None,
          errors: ErrorPolicy, backend: Backend) -> tuple[FloatArray, InstrumentIK]:
    """The controller forms on the chosen backend, after the lean single call.

    :func:`q_from_instrument` where ``p`` is given, :func:`q_from_tool_tip` where None.
    """
    def call(mod: Any) -> tuple[FloatArray, InstrumentIK]:
        if p is None:
            return mod.q_from_tool_tip(  # type: ignore[no-any-return]
                T_b_e, v, design, errors=errors)
        return mod.q_from_instrument(  # type: ignore[no-any-return]
            T_b_e, v, p, design, errors=errors)

    if ("line" in _WARM and _BACKEND["numba"]
            and (backend is OPTION_AUTO or _compiled_choice(backend))):
        return call(_STATE["api"])
    if resolve_backend(backend):
        api = _api()
        return _first("line", lambda: call(api))
    return call(_ref_ik)


# --- Jacobians -------------------------------------------------------------------------------
def _jacobian(name: str, backend: str, args: tuple[Any, ...], kw: dict[str, Any]
              ) -> FloatArray:
    if resolve_backend(backend):
        fn = getattr(_jac(), name)
        if name in _WARM:
            return fn(*args, **kw)  # type: ignore[no-any-return]
        return _first(name, lambda: fn(*args, **kw))
    return getattr(_ref_jac, name)(*args, **kw)  # type: ignore[no-any-return]


def parallel_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1, *,
                      backend: Backend = "auto") -> FloatArray:
    """Jacobian of the parallel module, ``d O_s / d q``, in the base frame (analytic).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    design : Design, optional
        Defaults to :meth:`~athenakin.Design.default`.
    mode : {1, -1} or array-like of them
        Assembly mode (slot 0 / 1 of :func:`~athenakin.parallel.parallel_forward_kinematics`).
    backend : {"auto", "numpy", "numba"}, keyword-only
        As in :func:`athenakin.forward_kinematics` (same result to 1e-12, same
        NaN / inf entries, same errors).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows: x, y, z of ``O_s`` (base frame); columns: ``q1, q2, q3``.
        Dimensionless (m/m). NaN where the module is not assembled; non-finite
        at the forward singularities (``w = 0``, ``|h| = l3``), rank 2 at ``h = 0``.
        Stroke limits and the A/B order are not checked (local geometry).

    See Also
    --------
    athenakin.robot._jacobians.parallel_jacobian : the numpy reference and its derivation.

    Examples
    --------
    >>> import athenakin as ak
    >>> J = ak.analysis.parallel_jacobian([-0.10, 0.10, 0.45], ak.Design.default(), mode=1)
    >>> J.shape
    (3, 3)
    """
    return _jacobian("parallel_jacobian", backend, (q, design, mode), {})


def parallel_inverse_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1,
                              *, backend: Backend = "auto") -> FloatArray:
    """Inverse Jacobian of the parallel module, ``d q / d O_s``, shape (..., 3, 3).

    Near a singular set the entries grow as the condition number of the forward
    Jacobian (``q2 - q1 = 1e-7`` m: about 6e6 m/m) while staying finite: flag such
    configurations with :func:`athenakin.analysis.condition_number` of the forward
    Jacobian against ``athenakin.motion.Margins().cond`` (100, the margin the tracker
    and teleop hold; :data:`athenakin.dynamics.COND_MARGIN` for the force figures).

    The numpy reference is :func:`athenakin.robot._jacobians.parallel_inverse_jacobian`
    (finite at the forward singularity ``w = 0``, infinite at ``h = 0``).

    Parameters
    ----------
    q, design, mode, backend : as in :func:`parallel_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns x, y, z of ``O_s`` (base frame); m/m.
    """
    return _jacobian("parallel_inverse_jacobian", backend, (q, design, mode), {})


def parallel_twist_jacobian(q: ArrayLike, design: Design | None = None, mode: ArrayLike = 1,
                            *, backend: Backend = "auto") -> FloatArray:
    """Twist ``(v, omega)`` of the frame ``O_s`` per actuator velocity, shape (..., 6, 3).

    The numpy reference is :func:`athenakin.robot._jacobians.parallel_twist_jacobian`.

    Parameters
    ----------
    q, design, mode, backend : as in :func:`parallel_jacobian`

    Returns
    -------
    ndarray, shape (..., 6, 3)
        Rows 0-2: velocity of ``O_s``, base frame, m/m (= :func:`parallel_jacobian`);
        rows 3-5: angular velocity ``(dtheta/dq, 0, 0)`` of ``R_b_s = Rx(theta)``, rad/m.
        Columns ``q1, q2, q3``.
    """
    return _jacobian("parallel_twist_jacobian", backend, (q, design, mode), {})


def instrument_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                        design: Design | None = None, *, mode: ArrayLike = 1,
                        frame: Frame = "rcm", backend: Backend = "auto") -> FloatArray:
    """Instrument direction angles and insertion per actuator velocity, shape (..., 3, 3).

    Parameters
    ----------
    q : array-like, shape (..., 3)
        Actuators ``(q1, q2, q3)``, m.
    T_b_e : array-like, shape (..., 4, 4), optional
        RCM frame (default: the reference set-up of the design).
    design : Design, optional
    mode : {1, -1} or array-like of them, keyword-only
        Assembly mode of the parallel module.
    frame : {"rcm", "base"}, keyword-only
        Frame whose z-axis the direction angles are measured about.
    backend : {"auto", "numpy", "numba"}, keyword-only
        As in :func:`parallel_jacobian`.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``azimuth`` (rad/m), ``polar`` (rad/m), ``p`` (m/m); columns ``q1, q2, q3``.

    See Also
    --------
    athenakin.robot._jacobians.instrument_jacobian : the numpy reference, with the details.
    """
    return _jacobian("instrument_jacobian", backend, (q, T_b_e, design),
                     {"mode": mode, "frame": frame})


def instrument_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                                design: Design | None = None, *, mode: ArrayLike = 1,
                                frame: Frame = "rcm", backend: Backend = "auto"
                                ) -> FloatArray:
    """Inverse of :func:`instrument_jacobian`: actuator rates per ``(azimuth, polar, p)`` rate.

    Near a singular set the entries grow as the condition number of the forward
    Jacobian (``q2 - q1 = 1e-7`` m: about 6e6 m/m) while staying finite: flag such
    configurations with :func:`athenakin.analysis.condition_number` of the forward
    Jacobian against ``athenakin.motion.Margins().cond`` (100, the margin the tracker
    and teleop hold; :data:`athenakin.dynamics.COND_MARGIN` for the force figures).

    Parameters
    ----------
    q, T_b_e, design, mode, frame, backend : as in :func:`instrument_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns ``azimuth``, ``polar`` (m/rad), ``p`` (m/m).
    """
    return _jacobian("instrument_inverse_jacobian", backend, (q, T_b_e, design),
                     {"mode": mode, "frame": frame})


def tool_tip_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                      design: Design | None = None, *, mode: ArrayLike = 1,
                      frame: Frame = "base", backend: Backend = "auto") -> FloatArray:
    """Tool-tip velocity per actuator velocity, shape (..., 3, 3).

    The numpy reference is :func:`athenakin.robot._jacobians.tool_tip_jacobian`
    (singular at ``p = L``, tip at the RCM; infinite at ``p = 0``).

    Parameters
    ----------
    q, T_b_e, design, mode, backend : as in :func:`instrument_jacobian`
    frame : {"base", "rcm"}, keyword-only
        Frame the tip velocity is expressed in (default ``"base"``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows: x, y, z of the tip velocity in ``frame``; columns ``q1, q2, q3``; m/m.
    """
    return _jacobian("tool_tip_jacobian", backend, (q, T_b_e, design),
                     {"mode": mode, "frame": frame})


def tool_tip_inverse_jacobian(q: ArrayLike, T_b_e: ArrayLike | None = None,
                              design: Design | None = None, *, mode: ArrayLike = 1,
                              frame: Frame = "base", backend: Backend = "auto"
                              ) -> FloatArray:
    """Inverse of :func:`tool_tip_jacobian`: actuator rates per tool-tip velocity.

    Near a singular set the entries grow as the condition number of the forward
    Jacobian (``q2 - q1 = 1e-7`` m: about 6e6 m/m) while staying finite: flag such
    configurations with :func:`athenakin.analysis.condition_number` of the forward
    Jacobian against ``athenakin.motion.Margins().cond`` (100, the margin the tracker
    and teleop hold; :data:`athenakin.dynamics.COND_MARGIN` for the force figures).

    Parameters
    ----------
    q, T_b_e, design, mode, frame, backend : as in :func:`tool_tip_jacobian`

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows ``q1, q2, q3``; columns: x, y, z of the tip velocity in ``frame``; m/m.
    """
    return _jacobian("tool_tip_inverse_jacobian", backend, (q, T_b_e, design),
                     {"mode": mode, "frame": frame})
