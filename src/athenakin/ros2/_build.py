"""CRTK's ``crtk_msgs`` built with the rosidl generator wheels (private).

No wheel of ``crtk_msgs`` exists; its two messages the nodes use
(``OperatingState``, ``StringStamped``, as the CRTK specification defines them) are
in ``crtk_msgs/`` beside this file, an ament package that :func:`build_crtk_msgs`
configures with CMake, compiles and installs into this Python's prefix (the
wheels' own prefix: ``lib/``, ``share/``, ``site-packages``), where rclpy finds
it like any interface package of the wheels.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["build_crtk_msgs", "CRTK_MSGS_DIR", "BUILD_TOOLS"]

#: The ament package of CRTK's messages shipped with athenakin.
CRTK_MSGS_DIR = Path(__file__).resolve().parent / "crtk_msgs"
#: Programs the build runs (a C and C++ compiler are found by CMake).
BUILD_TOOLS = ("cmake",)


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
        The installed Python package's folder (``.../site-packages/crtk_msgs``).

    Raises
    ------
    FileNotFoundError
        CMake, or a package of the extra ``ros2-msgs``, is missing (named).
    RuntimeError
        The configuration or the compilation failed (the tail of its output).
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or not 1 <= jobs <= 64:
        raise ValueError(f"jobs: expected an integer from 1 to 64, got {jobs!r}")
    root = Path(sys.prefix if prefix is None else prefix).resolve()
    cmake = shutil.which("cmake")
    if cmake is None:
        raise FileNotFoundError("cmake: not found on PATH (install CMake >= 3.16, e.g. "
                                "'pip install cmake' or the system's package)")
    share = Path(sys.prefix) / "share"
    for pkg in ("ament_cmake", "rosidl_default_generators", "std_msgs"):
        if not (share / pkg).is_dir():
            raise FileNotFoundError(f"{pkg}: not installed in {sys.prefix} (install the extra "
                                    f"with  pip install 'athenakin[ros2,ros2-msgs]')")
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["AMENT_PREFIX_PATH"] = os.pathsep.join(
        p for p in (sys.prefix, env.get("AMENT_PREFIX_PATH", "")) if p)
    env["CMAKE_PREFIX_PATH"] = os.pathsep.join(
        p for p in (sys.prefix, env.get("CMAKE_PREFIX_PATH", "")) if p)
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
    py = f"python{sys.version_info.major}.{sys.version_info.minor}"
    return root / "lib" / py / "site-packages" / "crtk_msgs"
