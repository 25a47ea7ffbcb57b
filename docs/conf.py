"""Sphinx configuration: the API reference from the docstrings, the Markdown pages, the tutorial.

Build with warnings as errors: ``bash scripts/docs.sh`` (``sphinx-build -W -b html docs
docs/_build/html``). The notebook ``examples/tutorial.ipynb`` is copied to
``docs/_generated/`` and executed during the build (myst-nb, through nbclient); an error in
a cell fails the build.
"""

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
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "figures/*.md", "**.ipynb_checkpoints"]

# the notebook tutorial lives with the examples; build it from a copy
(HERE / "_generated").mkdir(exist_ok=True)
shutil.copy(ROOT / "examples" / "tutorial.ipynb", HERE / "_generated" / "tutorial.ipynb")

# numpydoc-style docstrings
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_custom_sections = [("Attributes", "params_style")]
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "show-inheritance": False}

# MyST
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 300

html_theme = "alabaster"
html_title = f"athenakin {release}"
html_static_path: list[str] = []
