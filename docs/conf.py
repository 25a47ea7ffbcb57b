"""Sphinx configuration: the API reference from the docstrings, the Markdown pages, the tutorial.

Build with warnings as errors: ``bash scripts/docs.sh`` (``sphinx-build -W -b html docs
docs/_build/html``). The notebook ``examples/tutorial.ipynb`` is copied to
``docs/_generated/`` and executed during the build (myst-nb, through nbclient); an error in
a cell fails the build.
"""

import logging
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "src"))

import athenakin  # noqa: E402

project = "athenakin"
author = "the athenakin developers"
copyright = "2026, the athenakin developers"
release = version = athenakin.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "figures/*.md", "**.ipynb_checkpoints"]

# the notebook tutorial lives with the examples; build it from a copy
GENERATED = HERE / "_generated"
GENERATED.mkdir(exist_ok=True)
shutil.copy(ROOT / "examples" / "tutorial.ipynb", GENERATED / "tutorial.ipynb")

# ---- the API reference: one page per public subpackage, found, not listed ----------------
#: Order of the pages that exist today; a subpackage not named here (a new one: collision,
#: dynamics, ros, ...) gets its page too, after these, in alphabetical order.
API_ORDER = ["design", "errors", "study", "parallel", "chain", "robot", "analysis", "motion",
             "calibration", "certified", "synthesis", "sim", "plot", "app", "fast", "symbolic",
             "testing"]
#: Modules with no API page: the command line (documented by ``athenakin --help``).
API_SKIP = {"cli"}
#: Members documented elsewhere (full name of the module -> names), to avoid a second copy.
API_EXCLUDE = {"athenakin.robot": ["Design"]}


def public_modules() -> list[str]:
    """Every public subpackage and module of athenakin, in page order."""
    import pkgutil

    found = [m.name for m in pkgutil.iter_modules(athenakin.__path__)
             if not m.name.startswith("_") and m.name not in API_SKIP]
    return ([n for n in API_ORDER if n in found]
            + sorted(n for n in found if n not in API_ORDER))


def _title(module: str) -> str:
    import importlib

    doc = (importlib.import_module(module).__doc__ or "").strip()
    first = doc.splitlines()[0].rstrip(".") if doc else module
    return f"``{module}``: {first}"


#: The top-level names: ``__all__`` and the functions of optional subpackages that
#: ``athenakin`` resolves on first use (``ak.certified_forward_kinematics``).
TOP_NAMES = list(dict.fromkeys([*athenakin.__all__, *getattr(athenakin, "_LAZY_FUNCTIONS", {})]))


def _importable(name: str) -> bool:
    """Whether a top-level name resolves (a lazy one needs its extra installed)."""
    try:
        getattr(athenakin, name)
    except (ImportError, AttributeError):
        return False
    return True


def write_api_pages() -> list[str]:
    """Write ``_generated/api/<module>.rst`` for the top level and every subpackage."""
    out = GENERATED / "api"
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    names = []
    top = ["athenakin (top level)", "=" * 21, "",
           "The names every example calls, ``import athenakin as ak; ak.forward_kinematics(...)``:",
           "the compiled, dispatched functions (``backend=\"auto\"``), the design and set-up, the",
           "result types and the errors. Each subpackage has its own page.", "",
           ".. automodule:: athenakin", "   :no-members:", ""]
    # the functions first (what the examples call), then the data types, then the errors
    objs = [(n, getattr(athenakin, n)) for n in TOP_NAMES
            if not n.startswith("_") and _importable(n)]
    funcs = [n for n, o in objs if callable(o) and not isinstance(o, type)]
    errors = [n for n, o in objs if isinstance(o, type) and issubclass(o, BaseException)]
    classes = [n for n, o in objs if isinstance(o, type) and n not in errors]
    for heading, group, directive in (("Functions", funcs, "autofunction"),
                                      ("Data types", classes, "autoclass"),
                                      ("Errors", errors, "autoexception")):
        if group:
            top += [heading, "-" * len(heading), ""]
            for n in group:
                top += [f".. {directive}:: athenakin.{n}"]
                if directive == "autoclass":
                    top += ["   :members:"]
                top += [""]
    (out / "athenakin.rst").write_text("\n".join(top))
    names.append("athenakin")
    import importlib

    top_objects = {id(getattr(athenakin, n)): n for n in TOP_NAMES if _importable(n)}
    for short in public_modules():
        module = f"athenakin.{short}"
        mod = importlib.import_module(module)
        title = _title(module)
        # a name that is the very object of a top-level name is documented there, once
        shared = sorted(n for n in getattr(mod, "__all__", ())
                        if id(getattr(mod, n, None)) in top_objects)
        lines = [title, "=" * len(title), "", f".. automodule:: {module}", "   :members:"]
        excluded = sorted(set(shared) | set(API_EXCLUDE.get(module, ())))
        if excluded:
            lines.append(f"   :exclude-members: {', '.join(excluded)}")
        if shared:
            links = ", ".join(f":obj:`athenakin.{n}`" for n in shared)
            lines += ["", f"Also exported here, documented at the top level: {links}."]
        (out / f"{module}.rst").write_text("\n".join(lines) + "\n")
        names.append(module)
    toc = ["```{toctree}", ":maxdepth: 1", ""] + [f"_generated/api/{n}" for n in names] + ["```"]
    (out / "toc.txt").write_text("\n".join(toc) + "\n")
    return names


API_PAGES = write_api_pages()

# numpydoc-style docstrings
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_custom_sections = [("Attributes", "params_style")]
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "show-inheritance": False}

# MyST


class _NoConfigDump(logging.Filter):
    """Drop the configuration dump of myst-parser and myst-nb from the build log.

    Both log their whole configuration (``MdParserConfig(...)``, a screenful) at every
    build; the rest of the log stays.
    """

    def filter(self, record: logging.LogRecord) -> bool:
        return not any(type(a).__name__ in ("MdParserConfig", "NbParserConfig")
                       for a in (record.args if isinstance(record.args, tuple) else ()))


for _name in ("sphinx.myst_parser.sphinx_ext.main", "sphinx.myst_nb.sphinx_ext"):
    logging.getLogger(_name).addFilter(_NoConfigDump())

myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 300

# pydata-sphinx-theme: the theme of numpy, scipy, pandas, matplotlib; search built in
html_theme = "pydata_sphinx_theme"
html_title = f"athenakin {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 4,
    "secondary_sidebar_items": ["page-toc"],
}
html_sidebars = {"**": ["sidebar-nav-bs"]}
html_show_sourcelink = False
