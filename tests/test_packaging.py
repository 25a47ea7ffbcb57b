"""Packaging and project files (issue 12.1-12.3): versions, licence, citation, extras, docs."""

import ast
import re
import sys
from importlib import metadata
from pathlib import Path

import pytest
from packaging.version import Version

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
PROJECT = PYPROJECT["project"]


def _requirement(reqs, name):
    return next(r for r in reqs if re.split(r"[<>=!~; \[]", r, maxsplit=1)[0] == name)


def test_stdlib_modules_newer_than_the_oldest_python_are_guarded():
    """`import tomllib` (3.11+) only under a version check: Python 3.10 is declared."""
    for path in (ROOT / "src" / "athenakin").rglob("*.py"):
        tree = ast.parse(path.read_text())
        guarded = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.If) and "version_info" in ast.unparse(node.test):
                guarded |= {id(n) for n in ast.walk(node)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) and any(a.name == "tomllib" for a in node.names):
                assert id(node) in guarded, f"{path}:{node.lineno}: unguarded import tomllib"
    assert "tomli>=2.0; python_version < '3.11'" in PROJECT["dependencies"]


def test_declared_python_versions_are_the_tested_ones():
    declared = sorted(re.findall(r"Programming Language :: Python :: (3\.\d+)$",
                                 "\n".join(PROJECT["classifiers"]), flags=re.M))
    script = (ROOT / "scripts" / "test_matrix.sh").read_text()
    matrix = re.search(r'^VERSIONS="\$\{ATHENAKIN_PYTHONS:-(.*)\}"$', script, flags=re.M)
    assert matrix, "scripts/test_matrix.sh: no VERSIONS line"
    tested = {v.rsplit(".", 1)[0] for v in matrix.group(1).split()}
    main = re.search(r'^MAIN_PYTHON="(3\.\d+)"', script, flags=re.M).group(1)
    assert sorted(tested | {main}, key=lambda v: tuple(map(int, v.split(".")))) == sorted(
        declared, key=lambda v: tuple(map(int, v.split("."))))
    assert PROJECT["requires-python"] == f">={min(declared, key=lambda v: int(v[2:]))}"


def test_licence_file_is_declared_and_shipped():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "Copyright (c) 2026 the athenakin developers" in text
    assert PROJECT["license"] == "BSD-3-Clause" and PROJECT["license-files"] == ["LICENSE"]
    meta = metadata.metadata("athenakin")
    assert "LICENSE" in (meta.get_all("License-File") or [])


def test_changelog_and_citation():
    log = (ROOT / "CHANGELOG.md").read_text()
    assert "## [Unreleased]" in log and f"## [{PROJECT['version']}]" in log
    cff = (ROOT / "CITATION.cff").read_text()
    assert "cff-version: 1.2.0" in cff and f"version: {PROJECT['version']}" in cff
    assert "Kinematics of ATHENA, a Robot for Pancreas Surgery" in cff
    assert "doi:" not in cff.lower()          # the paper text gives none: none is invented
    assert "## Citing" in (ROOT / "README.md").read_text()


def test_no_reference_to_files_outside_the_repository():
    """Docstrings, docs and tests cite docs/conventions.md, not MODEL.md or shared fixtures."""
    paths = [*(ROOT / "src").rglob("*.py"), *(ROOT / "docs").glob("*.md"),
             *(ROOT / "tests").rglob("*.py"), *(ROOT / "tests" / "data").glob("*.json"),
             ROOT / "README.md"]
    bad = [str(p.relative_to(ROOT)) for p in paths
           if p != Path(__file__) and re.search(r"MODEL\.md|shared/fixtures", p.read_text())]
    assert bad == []


def test_extras_lower_bounds():
    extras = PROJECT["optional-dependencies"]
    # scipy.integrate.cumulative_simpson (motion/_path.py) is new in scipy 1.12
    assert _requirement(extras["motion"], "scipy") == "scipy>=1.12"
    # toppra: only the tests compare with it
    assert not any(r.startswith("toppra") for reqs in extras.values() for r in reqs)
    assert any(r.startswith("toppra") for r in PYPROJECT["dependency-groups"]["test"])
    src = "\n".join(p.read_text() for p in (ROOT / "src").rglob("*.py"))
    assert "import toppra" not in src


def test_min_deps_constraints_match_the_declared_lower_bounds():
    """scripts/test_min_deps.sh pins every declared lower bound it installs."""
    script = (ROOT / "scripts" / "test_min_deps.sh").read_text()
    pins = {}
    for name, version in re.findall(r"^([A-Za-z0-9_.-]+)==([0-9][^\s]*)$", script, flags=re.M):
        pins.setdefault(name, set()).add(Version(version))
    reqs = list(PROJECT["dependencies"])
    for name in ("analysis", "motion", "symbolic", "certified", "calibration", "synthesis",
                 "plot", "sim", "app", "progress"):
        reqs += PROJECT["optional-dependencies"][name]
    for r in reqs:
        if r.startswith("athenakin["):                 # another extra, checked on its own line
            continue
        m = re.match(r"^([A-Za-z0-9_.-]+)>=([0-9.]+)(,<[0-9.]+)?(;.*)?$", r)
        assert m, r
        if m.group(4):
            continue                                   # a marker for another Python
        assert Version(m.group(2)) in pins.get(m.group(1), set()), r


@pytest.mark.parametrize("name", ["README.md", "docs/conventions.md", "docs/ros.md"])
def test_docs_link_existing_files(name):
    text = (ROOT / name).read_text()
    base = (ROOT / name).parent
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text):
        assert (base / target).exists(), f"{name} links to missing {target}"


def test_mujoco_agreement_claim_states_its_gravity_condition():
    """README's 1e-12 agreement holds only without gravity, and the default export has gravity."""
    from athenakin.sim import mjcf_from_design

    readme = (ROOT / "README.md").read_text()
    i = readme.index("1e-12 m / rad")
    claim = readme[max(0, i - 300):i + 300]
    assert "gravity off" in claim and "--no-gravity" in claim
    assert 'gravity="0 0 -9.81"' in mjcf_from_design()
    assert 'gravity="0 0 0"' in mjcf_from_design(gravity=False)


def test_sphinx_tree_lists_every_page_once():
    """docs/index.md's toctrees hold every docs page, and api.md documents each module once
    (a page left out or a module twice fails the -W build of scripts/docs.sh)."""
    index = (ROOT / "docs" / "index.md").read_text()
    listed = re.findall(r"^([A-Za-z0-9_/]+)$", index, flags=re.M)
    pages = sorted(p.stem for p in (ROOT / "docs").glob("*.md") if p.stem != "index")
    assert sorted(x for x in listed if not x.startswith("_generated")) == pages
    mods = re.findall(r"^\.\. automodule:: (\S+)$", (ROOT / "docs" / "api.md").read_text(),
                      flags=re.M)
    assert len(mods) == len(set(mods))


def test_every_public_subpackage_is_an_attribute_of_the_package():
    """``import athenakin as ak; ak.<sub>`` works for every public subpackage (issue 23)."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1] / "src" / "athenakin"
    subs = sorted(p.name for p in root.iterdir()
                  if p.is_dir() and not p.name.startswith("_") and (p / "__init__.py").exists()
                  and p.name != "cli")                   # the command line, not an API
    subs += ["testing"]
    # athenakin.fast is the compiled kernels themselves: where the backend policy says
    # numpy (or numba is missing) importing it is the policy's named ImportError
    code = ("import athenakin as ak\n"
            "from athenakin import _backend\n"
            f"for s in {subs!r}:\n"
            "    if s == 'fast' and not _backend.numba_available():\n"
            "        try:\n"
            "            ak.fast\n"
            "        except ImportError as e:\n"
            "            assert 'ATHENAKIN_BACKEND' in str(e), e\n"
            "            continue\n"
            "        raise AssertionError('athenakin.fast imported without numba')\n"
            "    assert getattr(ak, s).__name__ == 'athenakin.' + s, s\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]


def test_dir_lists_the_lazy_names_without_importing_them():
    """``dir(ak)`` shows every lazy subpackage and ``Robot``, and listing imports none of them."""
    import subprocess
    import sys

    code = ("import sys, athenakin as ak\n"
            "names = dir(ak)\n"
            "lazy = set(ak._LAZY_SUBPACKAGES) | set(ak._LAZY_FUNCTIONS)\n"
            "assert lazy <= set(names), sorted(lazy - set(names))\n"
            "assert set(ak.__all__) <= set(names), sorted(set(ak.__all__) - set(names))\n"
            "assert names == sorted(names)\n"
            "assert 'athenakin.dynamics' not in sys.modules\n"
            "assert 'athenakin.teleop' not in sys.modules\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]


def test_no_issue_numbers_in_src():
    """Comments say what the code does; issue numbers belong in the CHANGELOG."""
    bad = [f"{p.relative_to(ROOT)}:{i}" for p in (ROOT / "src").rglob("*.py")
           for i, line in enumerate(p.read_text().splitlines(), 1)
           if re.search(r"\bissues? \d+", line)]
    assert bad == []
