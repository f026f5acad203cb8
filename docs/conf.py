"""Sphinx configuration of the camdyn documentation.

The Markdown pages in this folder are read in place by MyST; the API reference is written
at build time from the packages' public names (``__all__``, or every name a module defines
without a leading underscore) into ``api/`` (not tracked); the gallery is built by
sphinx-gallery from ``examples/gallery/plot_*.py`` into ``auto_examples/`` (not tracked).

Build: ``make docs`` (quick: runs the gallery scripts only) or ``make docs-full`` (first
regenerates ``docs/figures`` with the long scripts in ``examples/``).
"""

from __future__ import annotations

import ast
import importlib
import inspect
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))  # the checkout, even without an editable install
sys.path.insert(0, str(DOCS / "_ext"))  # gallery_order

import camdyn  # noqa: E402

# -- project -------------------------------------------------------------------------------

project = "camdyn"
author = "the camdyn developers"
copyright = "the camdyn developers"
release = camdyn.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build", "_ext", "**/.ipynb_checkpoints", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.md5"]
nitpicky = False
toc_object_entries = False  # the "on this page" column lists sections, not every constant
# every warning is an error in `make docs` (-W); none is silenced here

# -- MyST: the Markdown pages of docs/ --------------------------------------------------------

myst_enable_extensions = ["colon_fence", "deflist", "dollarmath", "amsmath"]
# "## 1. Frames and conventions" gets the anchor #1-frames-and-conventions, as on GitHub,
# so the pages' intra-document links resolve in both places
myst_heading_anchors = 4
# a page that links to a file outside docs/ (../README.md, ../examples/x.py) fails the build
# (the site holds no such file): name such files as literal paths, `examples/x.py`

# pages written by scripts without a title of their own: given one when read (the files
# stay as the scripts write them)
GENERATED_PAGE_TITLES = {
    "friction-errors-tables": "Friction identification: error tables (thesis tables 4.5-4.7, section 4.8)",
}


def _add_title(app, docname, source):
    """Give a generated page its title, and raise its headings to sections under it."""
    title = GENERATED_PAGE_TITLES.get(docname)
    if not title or source[0].lstrip().startswith("# "):
        return
    lines = source[0].split("\n")
    fence = False
    levels = []
    for line in lines:
        fence ^= line.startswith("```")
        if not fence and line.startswith("#"):
            levels.append(len(line) - len(line.lstrip("#")))
    shift = min(levels, default=2) - 2
    fence = False
    for i, line in enumerate(lines):
        fence ^= line.startswith("```")
        if not fence and line.startswith("#") and shift > 0:
            lines[i] = line[shift:]
    source[0] = f"# {title}\n\n" + "\n".join(lines)


# -- API reference -------------------------------------------------------------------------

#: The packages (and modules) whose public names the API reference lists, in the order of
#: the layers from the parameters up.
API_PACKAGES = [
    "camdyn.params", "camdyn.model", "camdyn.simulation", "camdyn.analysis", "camdyn.identification",
    "camdyn.tribology", "camdyn.continuation", "camdyn.steady", "camdyn.records", "camdyn.io", "camdyn.sweeps",
    "camdyn.plotting",
    "camdyn.errors",
]
API_DIR = DOCS / "api"
_STUBS: set[str] = set()  # the names that get a page of their own (autosummary stubs)


def _defined_names(path: Path) -> list[str]:
    """Names a module's source defines at top level (functions, classes, assignments)."""
    names = []
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.append(node.name)
        elif isinstance(node, ast.Assign):
            names += [t.id for t in node.targets if isinstance(t, ast.Name)]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.append(node.target.id)
    return list(dict.fromkeys(names))


def public_names(module) -> list[str]:
    """The public names of a module: its ``__all__``, or every name its source defines
    without a leading underscore."""
    if hasattr(module, "__all__"):
        return list(module.__all__)
    if module.__file__ is None:
        return []
    return [n for n in _defined_names(Path(module.__file__)) if not n.startswith("_")]


def _kind(obj) -> str:
    if isinstance(obj, type):
        return "exception" if issubclass(obj, BaseException) else "class"
    if callable(obj):
        inner = getattr(obj, "py_func", None) or inspect.unwrap(obj)  # numba dispatchers, lru_cache
        if inspect.isfunction(inner) or inspect.isbuiltin(inner):
            return "function"
    return "data"


def _submodules(package) -> list[str]:
    if not hasattr(package, "__path__"):
        return []
    found = []
    for path in sorted(Path(package.__path__[0]).iterdir()):
        if path.suffix == ".py" and not path.name.startswith("_"):
            found.append(f"{package.__name__}.{path.stem}")
        elif path.is_dir() and (path / "__init__.py").exists() and not path.name.startswith("_"):
            sub = importlib.import_module(f"{package.__name__}.{path.name}")
            if public_names(sub) or _submodules(sub):
                found.append(sub.__name__)
    return found


def _heading(text: str, char: str) -> str:
    return f"{text}\n{char * len(text)}\n"


def _first_line(obj) -> str:
    doc = (getattr(obj, "__doc__", None) or "").strip()
    return doc.split("\n\n")[0].replace("\n", " ") if doc else ""


def _module_section(name: str, char: str) -> str:
    """The reST of one module: its docstring, then its functions and classes (a summary
    table, each on its own page) and its constants (listed in place)."""
    module = importlib.import_module(name)
    names = public_names(module)
    out = [_heading(name, char), f".. automodule:: {name}\n   :no-members:\n"]
    groups: dict[str, list[str]] = {"function": [], "class": [], "exception": [], "data": []}
    for n in names:
        groups[_kind(getattr(module, n))].append(n)
    titles = {"class": "Classes", "exception": "Exceptions", "function": "Functions"}
    for kind in ("class", "exception", "function"):
        _STUBS.update(f"{name}.{n}" for n in groups[kind])
        if groups[kind]:
            out.append(f".. rubric:: {titles[kind]}\n\n.. autosummary::\n   :toctree: generated\n"
                       f"   :nosignatures:\n\n" + "".join(f"   {n}\n" for n in groups[kind]))
    if groups["data"]:
        out.append(".. rubric:: Constants\n")
        for n in groups["data"]:
            value = getattr(module, n)
            short = len(repr(value)) <= 70
            out.append(f".. autodata:: {name}.{n}\n" + ("" if short else "   :no-value:\n"))
    return "\n".join(out) + "\n"


def write_api_pages() -> None:
    """Write ``api/<package>.rst`` for every entry of :data:`API_PACKAGES` and ``api/camdyn.rst``
    for the names importable from ``camdyn`` itself."""
    API_DIR.mkdir(exist_ok=True)
    pages = {}
    top = ["camdyn", "======", "", ".. module:: camdyn", "", camdyn.__doc__.split("\n\n")[0].strip(), "",
           "The names below are importable from ``camdyn`` directly (``camdyn.simulate``, ...); each is "
           "documented in full where it is defined.", ""]
    for n in camdyn.__all__:
        obj = getattr(camdyn, n)
        home = f"{obj.__module__}.{n}"
        if isinstance(obj, type):
            kind = "exception" if issubclass(obj, BaseException) else "class"
            top += [f".. py:{kind}:: {n}", "", f"   {_first_line(obj)} See :class:`{home}`.", ""]
        else:
            signature = inspect.signature(obj).replace(return_annotation=inspect.Signature.empty)
            signature = signature.replace(parameters=[p.replace(annotation=inspect.Parameter.empty)
                                                      for p in signature.parameters.values()])
            top += [f".. py:function:: {n}{signature}", "", f"   {_first_line(obj)} See :func:`{home}`.", ""]
    pages["camdyn"] = "\n".join(top) + "\n"
    for package_name in API_PACKAGES:
        package = importlib.import_module(package_name)
        submodules = _submodules(package)
        text = [_heading(package_name, "=")]
        if submodules:
            text.append(f".. automodule:: {package_name}\n   :no-members:\n")
            exported = public_names(package)
            if exported:
                text.append(f"The names below are importable from ``{package_name}`` directly; each is documented "
                            "where it is defined.\n")
                text.append("".join(f"- :obj:`{package_name}.{n} <{getattr(package, n).__module__}.{n}>`\n"
                                    if hasattr(getattr(package, n), "__module__")
                                    and not isinstance(getattr(package, n), (tuple, dict, list))
                                    else f"- ``{package_name}.{n}``\n" for n in exported))
            for sub in submodules:
                text.append(_module_section(sub, "-"))
        else:
            text = [_module_section(package_name, "=")]
        pages[package_name] = "\n".join(text)
    for name, text in pages.items():
        path = API_DIR / f"{name}.rst"
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
    # pages of names that are gone (renamed, moved, made private) would be orphans
    for path in API_DIR.glob("*.rst"):
        if path.stem not in pages:
            path.unlink()
    for path in (API_DIR / "generated").glob("*.rst"):
        if path.stem not in _STUBS:
            path.unlink()


write_api_pages()

autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types and units
autodoc_preserve_defaults = True
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# -- gallery -------------------------------------------------------------------------------

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    # every build runs every script again: the figures show what the current code does
    "run_stale_examples": True,
    "within_subsection_order": "gallery_order.GalleryOrder",
    "download_all_examples": False,
    "write_computation_times": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "abort_on_example_error": True,
    "show_memory": False,
    "min_reported_time": 1,
}

# -- HTML ----------------------------------------------------------------------------------

html_theme = "pydata_sphinx_theme"
html_title = f"camdyn {release}"
html_static_path = ["_static"]
html_css_files = ["camdyn.css"]
html_show_sourcelink = False
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_sidebars = {"index": [], "getting-started": []}
html_context = {"default_mode": "light"}


def setup(app):
    app.connect("source-read", _add_title)
