"""The one backend policy of athenakin: numba kernels or the numpy reference (private).

Every compiled path of the package asks this module, and only this module, whether to
run its numba kernel: the kinematics of :mod:`athenakin._dispatch` and
:mod:`athenakin.fast`, the dynamics, the design-study reductions, the tracker and its
clearance, the collision pairs, the ``/tf`` frames and the MCAP reader and writer.

Policy
------
``ATHENAKIN_BACKEND`` in the environment (read once per process, on the first question):

- unset, empty or ``auto``: the compiled kernels where numba imports, else the numpy
  reference (a platform without numba wheels);
- ``numpy``: the numpy reference everywhere, and numba is never imported (as on a
  platform without numba); ``backend="numba"`` then raises :class:`ImportError`;
- ``numba``: the compiled kernels, an :class:`ImportError` where numba does not import.

A function's ``backend=`` argument (``"auto" | "numpy" | "numba"``) is resolved by
:func:`resolve_backend`; ``"auto"`` follows the environment. Both paths give the same
results to 1e-12 (``tests/test_backend_policy.py`` runs every subpackage without numba).

Kernels
-------
A kernel module imports numba only through this module (``from .._backend import njit``,
resolved lazily by the module ``__getattr__`` below): importing one where the policy
says numpy raises :class:`ImportError` instead of loading numba behind the policy's back.
Where kernels live is stated in ``docs/architecture.md`` ("Compiled kernels").
"""

from __future__ import annotations

import os
import sys
from types import ModuleType
from typing import Any, Literal

__all__ = ["Backend", "BACKENDS", "ENV_VAR", "environment_backend", "numba_available",
           "resolve_backend", "numba_module", "user_cache_dir"]

#: ``"auto"``: compiled where numba imports, else numpy; ``"numpy"``: the reference;
#: ``"numba"``: the compiled kernels (ImportError without numba).
Backend = Literal["auto", "numpy", "numba"]
BACKENDS = ("auto", "numpy", "numba")
#: The environment variable of the policy.
ENV_VAR = "ATHENAKIN_BACKEND"

#: The names of numba that kernel modules take from here (``from .._backend import njit``).
NUMBA_NAMES = ("njit", "prange", "threading_layer")

_STATE: dict[str, Any] = {}     # "numba": bool, the answer of numba_available()


def environment_backend() -> str:
    """The backend that ``ATHENAKIN_BACKEND`` asks for: ``"auto"``, ``"numpy"`` or ``"numba"``.

    Raises
    ------
    ValueError
        The variable holds anything else (case and surrounding blanks are ignored).
    """
    raw = os.environ.get(ENV_VAR, "")
    value = raw.strip().lower() or "auto"
    if value not in BACKENDS:
        raise ValueError(f"{ENV_VAR}={raw!r}: expected one of {BACKENDS} (or unset)")
    return value


def single_call_backend() -> Backend:
    """The backend of a process that makes one small call and exits (a one-pose CLI command).

    ``"numpy"`` (the reference: the same results to 1e-12, tested; loading numba and the
    kernels costs about 1 s of CPU for a call the reference answers in a millisecond)
    unless ``ATHENAKIN_BACKEND`` is set (then ``"auto"``: the policy decides as for every
    call) or numba is loaded in this process already.

    Returns
    -------
    {"auto", "numpy"}
    """
    if os.environ.get(ENV_VAR, "").strip() or "numba" in sys.modules:
        return "auto"
    return "numpy"


def user_cache_dir() -> str:
    """The per-user cache directory of athenakin's compiled kernels.

    Returns
    -------
    str
        ``$XDG_CACHE_HOME/athenakin/numba`` (default ``~/.cache/athenakin/numba``) on
        Linux, ``~/Library/Caches/athenakin/numba`` on macOS,
        ``%LOCALAPPDATA%/athenakin/numba`` on Windows.
    """
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or os.path.expanduser("~")
    elif sys.platform == "darwin":
        base = os.path.expanduser("~/Library/Caches")
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return os.path.join(base, "athenakin", "numba")


def _configure_numba_cache() -> None:
    """Point numba's cache at the user cache directory if the package one is read-only.

    Only before numba is imported and only when ``NUMBA_CACHE_DIR`` is unset: a
    site-packages that the user cannot write (system install, container image) then
    caches the kernels under :func:`user_cache_dir` instead of recompiling each time.
    """
    if "NUMBA_CACHE_DIR" in os.environ or "numba" in sys.modules:
        return
    here = os.path.dirname(os.path.abspath(__file__))
    pyc = os.path.join(here, "__pycache__")
    if os.access(pyc if os.path.isdir(pyc) else here, os.W_OK):
        return
    os.environ["NUMBA_CACHE_DIR"] = user_cache_dir()


def numba_available() -> bool:
    """Whether the compiled kernels run here (decided once per process).

    Returns
    -------
    bool
        False with ``ATHENAKIN_BACKEND=numpy`` (numba is then not imported) or where
        numba does not import; True otherwise.

    Raises
    ------
    ImportError
        ``ATHENAKIN_BACKEND=numba`` where numba does not import.
    ValueError
        ``ATHENAKIN_BACKEND`` holds an unknown value.
    """
    ok = _STATE.get("numba")
    if ok is None:
        wanted = environment_backend()
        if wanted == "numpy":
            ok = False
        else:
            _configure_numba_cache()
            try:
                import numba  # noqa: F401
                ok = True
            except ImportError:
                if wanted == "numba":
                    raise ImportError(f"{ENV_VAR}=numba, but numba cannot be imported here; "
                                      "install numba (a dependency of athenakin) or unset "
                                      f"{ENV_VAR}") from None
                ok = False
        _STATE["numba"] = ok
    return bool(ok)


def resolve_backend(backend: object) -> bool:
    """True when ``backend`` runs the compiled kernels here, False for the numpy reference.

    Parameters
    ----------
    backend : {"auto", "numpy", "numba"}
        ``"auto"``: as :func:`numba_available`.

    Returns
    -------
    bool

    Raises
    ------
    ValueError
        ``backend`` is not one of :data:`BACKENDS`.
    ImportError
        ``backend="numba"`` where numba cannot be imported (or ``ATHENAKIN_BACKEND=numpy``).
    """
    if not isinstance(backend, str):
        raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")
    if backend == "auto":
        return numba_available()
    if backend == "numpy":
        return False
    if backend == "numba":
        if not numba_available():
            raise ImportError("backend='numba': numba cannot be imported here (or "
                              f"{ENV_VAR}=numpy is set); install numba (a dependency of "
                              "athenakin) or use backend='auto' / 'numpy'")
        return True
    raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")


def numba_module() -> ModuleType:
    """The numba module, for the kernel modules (the one place that imports it).

    Returns
    -------
    module

    Raises
    ------
    ImportError
        The policy says numpy (:func:`numba_available` is False): a compiled path was
        taken without asking :func:`resolve_backend`.
    """
    if not numba_available():
        raise ImportError(f"numba is off here (not importable, or {ENV_VAR}=numpy): a "
                          "compiled kernel was imported without asking athenakin._backend")
    import numba

    if "announcer" not in _STATE:
        _STATE["announcer"] = _announce_compiles(numba)
    return numba


#: The start of every compile notice (a filter of the tests and scripts matches it).
COMPILE_NOTICE = "athenakin: compiling the numba kernels"
#: The modules whose kernels are announced (those of this package).
ANNOUNCED_PREFIX = "athenakin."


def _announce_compiles(numba: ModuleType) -> Any:
    """Print one line on stderr before the first uncached compile of each kernel area.

    numba broadcasts ``"numba:compile"`` (its documented event API, ``numba.core.event``)
    only where a kernel is not in its cache, before the compile: the notice is then
    exact, one line per area (``athenakin.dynamics``, ``athenakin.fast``, ...) and per
    process, and nothing is printed where the kernels load from the cache. A kernel
    compiled inside another's compile (a callee) belongs to the outer notice.
    """
    import threading

    import numba.core.event as event  # numba's documented Event API ("numba:compile")

    announced: set[str] = set()
    local = threading.local()

    class _Announcer(event.Listener):  # type: ignore[misc]
        def on_start(self, ev: Any) -> None:
            depth = getattr(local, "depth", 0)
            local.depth = depth + 1
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            module = getattr(func, "__module__", "") or ""
            if depth or not module.startswith(ANNOUNCED_PREFIX):
                return
            area = ".".join(part for part in module.split(".")[:2] if not part.startswith("_"))
            if area in announced:
                return
            announced.add(area)
            where = os.environ.get("NUMBA_CACHE_DIR") or "the package's __pycache__"
            print(f"{COMPILE_NOTICE} of {area} (first use, not in the cache: up to tens of "
                  f"seconds; later runs load them from {where}) ...", file=sys.stderr,
                  flush=True)

        def on_end(self, ev: Any) -> None:
            local.depth = max(getattr(local, "depth", 1) - 1, 0)

    listener = _Announcer()
    event.register("numba:compile", listener)
    return listener


def __getattr__(name: str) -> Any:
    """``from athenakin._backend import njit`` (and :data:`NUMBA_NAMES`): numba's, lazily."""
    if name in NUMBA_NAMES:
        return getattr(numba_module(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
