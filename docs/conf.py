"""Sphinx configuration: the Markdown pages of docs/ (MyST) and the API reference of ``ngfrac``
and ``estimators`` from their numpydoc docstrings (autodoc + autosummary + napoleon).

    python3 dev.py docs        # builds docs/_build/html

tests/test_docs.py builds it with warnings as errors.
"""
from __future__ import annotations

import inspect
import re
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # the packages of this checkout, installed or not

from ngfrac.io.output import ngfrac_version  # noqa: E402

project = "ngfrac"
author = "the ngfrac authors"
release = version = ngfrac_version()

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build"]
# generated/: autosummary's stub pages, one per module (not in git). Written afresh by every
# build, so a module that was renamed or removed leaves no stale page behind.
shutil.rmtree(HERE / "generated", ignore_errors=True)

# -- API reference -----------------------------------------------------------------------------
autosummary_generate = True
# autosummary_ignore_module_all stays True: a package's page lists all its public submodules,
# not only those named in its __all__
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# -- Markdown ----------------------------------------------------------------------------------
myst_heading_anchors = 3  # links to a page's #headings resolve

html_theme = "alabaster"
html_title = f"ngfrac {release}"


def list_exports(app, what, name, obj, options, lines) -> None:
    """A package's page (documented without members, see _templates/) lists its ``__all__``,
    each linked to the module that defines and documents it: one object, one entry."""
    if what != "module" or not hasattr(obj, "__path__"):
        return
    exports = getattr(obj, "__all__", ())
    if exports:
        lines += ["", ".. rubric:: Exported here", ""]
    for export in exports:
        member = getattr(obj, export)
        home, qualname = getattr(member, "__module__", None), getattr(member, "__qualname__", None)
        lines.append(f"- :obj:`~{home}.{qualname}`" if home and qualname
                     else f"- :obj:`~{name}.{export}`")


def name_sentinels(app, what, name, obj, options, signature, return_annotation):
    """A default that is a bare ``object()`` bound to a module-level name (``scene.REQUIRED``)
    shows as that name, not as ``<object object>``; dataclass signatures have no source text for
    ``autodoc_preserve_defaults`` to keep."""
    module = sys.modules.get(getattr(obj, "__module__", None) or "")
    if not signature or "<object object>" not in signature or module is None:
        return None
    sentinels = {id(value): key for key, value in vars(module).items() if type(value) is object}
    try:
        parameters = inspect.signature(obj).parameters.values()
    except (TypeError, ValueError):
        return None
    for parameter in parameters:
        if id(parameter.default) in sentinels:
            signature = re.sub(rf"(\b{parameter.name}(?::[^=]*?)? ?= ?)<object object>",
                               rf"\g<1>{sentinels[id(parameter.default)]}", signature)
    return signature, return_annotation


def setup(app) -> None:
    app.connect("autodoc-process-docstring", list_exports)
    app.connect("autodoc-process-signature", name_sentinels)

