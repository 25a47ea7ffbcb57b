"""CRTK's ``crtk_msgs`` built with the rosidl generator wheels (private).

No wheel of ``crtk_msgs`` exists; its two messages the nodes use
(``OperatingState``, ``StringStamped``, as the CRTK specification defines them) are
in ``crtk_msgs/`` beside this file, an ament package that :func:`build_crtk_msgs`
configures with CMake, compiles and installs into this Python's prefix (the
wheels' own prefix: ``lib/``, ``share/``, ``site-packages``), where rclpy finds
it like any interface package of the wheels. The build records what it was made from
(:func:`build_key`) in the installed package; :func:`crtk_msgs_current` compares, so that
``athenakin ros2 build-msgs`` run again on an unchanged environment does nothing.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from .._validation import check_path

__all__ = ["build_crtk_msgs", "crtk_msgs_current", "build_key", "installed_path",
           "CRTK_MSGS_DIR", "BUILD_TOOLS", "STAMP_NAME"]

#: The ament package of CRTK's messages shipped with athenakin.
CRTK_MSGS_DIR = Path(__file__).resolve().parent / "crtk_msgs"
#: Programs the build runs (a C and C++ compiler are found by CMake).
BUILD_TOOLS = ("cmake",)
#: The file, in the installed Python package's folder, holding the :func:`build_key` of
#: the build that installed it.
STAMP_NAME = ".athenakin-build"


def build_key(source: str | os.PathLike[str] = CRTK_MSGS_DIR) -> str:
    """What a build of ``crtk_msgs`` is made from, as one SHA-256 (hex).

    The package's files (names and contents), this Python's version and executable, and
    the name and version of every installed distribution named ``ros-*`` (the rosidl
    generators, ament and the interfaces that the messages use).

    Parameters
    ----------
    source : path, optional
        The ament package (default :data:`CRTK_MSGS_DIR`).

    Returns
    -------
    str
        64 hex digits.

    Raises
    ------
    TypeError
        ``source`` is not a path (str or ``os.PathLike``).
    """
    root = check_path(source, "source")
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*")
                       if p.is_file() and "__pycache__" not in p.relative_to(root).parts):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    h.update(f"{sys.version}\0{sys.executable}\0".encode())
    ros = sorted({f"{d.metadata['Name']}=={d.version}" for d in importlib.metadata.distributions()
                  if (d.metadata["Name"] or "").lower().startswith("ros-")})
    h.update("\n".join(ros).encode())
    return h.hexdigest()


def _prefix(prefix: object) -> Path:
    """The install prefix: ``prefix`` checked (a path), or ``sys.prefix``; resolved."""
    return (Path(sys.prefix) if prefix is None else check_path(prefix, "prefix")).resolve()


def installed_path(prefix: str | os.PathLike[str] | None = None) -> Path:
    """The folder of the Python package ``crtk_msgs`` under ``prefix`` (default ``sys.prefix``).

    Raises
    ------
    TypeError
        ``prefix`` is not a path (str or ``os.PathLike``).
    """
    root = _prefix(prefix)
    py = f"python{sys.version_info.major}.{sys.version_info.minor}"
    return root / "lib" / py / "site-packages" / "crtk_msgs"


def crtk_msgs_current(prefix: str | os.PathLike[str] | None = None) -> bool:
    """Whether ``crtk_msgs`` under ``prefix`` is built from what is here now.

    True where :func:`build_crtk_msgs` installed it and recorded today's :func:`build_key`.

    Parameters
    ----------
    prefix : path, optional
        Install prefix (default ``sys.prefix``).

    Returns
    -------
    bool
        False where it is not installed, was installed otherwise, or from other sources
        or other generator versions.

    Raises
    ------
    TypeError
        ``prefix`` is not a path (str or ``os.PathLike``).
    """
    path = installed_path(prefix)
    try:
        recorded = (path / STAMP_NAME).read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return False
    return (path / "__init__.py").is_file() and recorded == build_key()


def _build_env() -> dict[str, str]:
    """The environment of the build: this Python's tools first, its prefix for ament and CMake."""
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    for var in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH"):
        env[var] = os.pathsep.join(p for p in (sys.prefix, env.get(var, "")) if p)
    return env


def build_crtk_msgs(*, prefix: str | os.PathLike[str] | None = None,
                    build_dir: str | os.PathLike[str] | None = None, jobs: int = 2,
                    verbose: bool = False) -> Path:
    """Build and install ``crtk_msgs`` (CRTK's ``OperatingState``, ``StringStamped``).

    Needs the extra ``ros2-msgs`` (ament_cmake and the rosidl generators as wheels),
    CMake and a C/C++ compiler; takes about half a minute on two cores.

    Parameters
    ----------
    prefix : path, optional, keyword-only
        Install prefix (default ``sys.prefix``: the virtual environment whose rclpy
        wheels the nodes use; rclpy then imports ``crtk_msgs`` with no further set-up).
    build_dir : path, optional, keyword-only
        Where to build (default a temporary folder, removed afterwards).
    jobs : int, keyword-only
        Parallel compile jobs (2).
    verbose : bool, keyword-only
        Show CMake's output.

    Returns
    -------
    Path
        The installed Python package's folder (``.../site-packages/crtk_msgs``), with
        the build's :func:`build_key` in its :data:`STAMP_NAME`.

    Raises
    ------
    TypeError
        ``prefix`` is not a path (str or ``os.PathLike``).
    FileNotFoundError
        CMake, or a package of the extra ``ros2-msgs``, is missing (named).
    RuntimeError
        The configuration or the compilation failed (the tail of its output).
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or not 1 <= jobs <= 64:
        raise ValueError(f"jobs: expected an integer from 1 to 64, got {jobs!r}")
    root = _prefix(prefix)
    key = build_key()
    cmake = shutil.which("cmake")
    if cmake is None:
        raise FileNotFoundError("cmake: not found on PATH (install CMake >= 3.16, e.g. "
                                "'pip install cmake' or the system's package)")
    share = Path(sys.prefix) / "share"
    for pkg in ("ament_cmake", "rosidl_default_generators", "std_msgs"):
        if not (share / pkg).is_dir():
            raise FileNotFoundError(f"{pkg}: not installed in {sys.prefix} (install the extra "
                                    f"with  pip install 'athenakin[ros2,ros2-msgs]')")
    env = _build_env()
    tmp = None
    if build_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="crtk_msgs_build_")
        build = Path(tmp.name)
    else:
        build = Path(build_dir)
        build.mkdir(parents=True, exist_ok=True)
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    steps = [
        [cmake, str(CRTK_MSGS_DIR), *generator, f"-DCMAKE_INSTALL_PREFIX={root}",
         f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF"],
        [cmake, "--build", ".", "--parallel", str(jobs)],
        [cmake, "--install", "."],
    ]
    try:
        for cmd in steps:
            r = subprocess.run(cmd, cwd=build, env=env, text=True, check=False,
                               stdout=None if verbose else subprocess.PIPE,
                               stderr=subprocess.STDOUT if not verbose else None)
            if r.returncode != 0:
                tail = "\n".join((r.stdout or "").splitlines()[-25:])
                raise RuntimeError(f"crtk_msgs: {' '.join(cmd[:3])} failed (exit "
                                   f"{r.returncode}):\n{tail}")
    finally:
        if tmp is not None:
            tmp.cleanup()
    path = installed_path(root)
    (path / STAMP_NAME).write_text(key + "\n", encoding="ascii")
    return path
