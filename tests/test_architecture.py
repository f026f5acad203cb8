"""House rules on the code's shape, checked on the sources' text and syntax trees (no
import of camdyn, nothing compiled):

- no module under ``src/camdyn`` over 500 lines, no function over 100 lines;
- no private name (leading underscore) imported from another camdyn module;
- no import cycle between camdyn modules (module-level imports);
- no file of the repository names the retired planning files, the shared folder or an
  issue number.

Each checker is a function of source text, tested on synthetic sources below, so that
every rule is shown to be able to fail.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = "camdyn"
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 100
#: Where the text rules apply: folders searched recursively, and single files.
TEXT_FOLDERS = ("src", "tests", "docs", "examples", "benchmarks")
TEXT_FILES = ("README.md",)
#: Names no file may mention (written as patterns so that this file does not match).
FORBIDDEN_MENTIONS = {
    "the retired model spec file": re.compile(r"\bMODEL[.]md\b"),
    "the retired performance notes file": re.compile(r"\bPERFORMANCE[.]md\b"),
    "the shared folder": re.compile(r"\bshared[/]"),
    "an issue number": re.compile(r"\bissues?\s*(?:no[.]?\s*|number\s*)?#?\d+", re.IGNORECASE),
}


# --- checkers (pure functions of source text) -----------------------------------------


def module_name(path: Path, src: Path = SRC) -> str:
    """Dotted module name of a source file under ``src``."""
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def long_modules(sources: dict[str, str], limit: int = MAX_MODULE_LINES) -> dict[str, int]:
    """Modules (name: source) longer than ``limit`` lines: ``{name: lines}``."""
    return {name: len(text.splitlines()) for name, text in sources.items() if len(text.splitlines()) > limit}


def long_functions(source: str, limit: int = MAX_FUNCTION_LINES) -> list[tuple[str, int]]:
    """Functions and methods (nested ones included) longer than ``limit`` lines, from the
    ``def`` line to the last line of the body: ``[(qualified name, lines)]``."""
    found = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = f"{prefix}{child.name}"
                if not isinstance(child, ast.ClassDef):
                    lines = child.end_lineno - child.lineno + 1
                    if lines > limit:
                        found.append((name, lines))
                visit(child, name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return found


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str | None:
    """Absolute module of a ``from ... import`` statement in ``module``."""
    if node.level == 0:
        return node.module
    base = module.split(".") if is_package else module.split(".")[:-1]
    if node.level > 1:
        base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def private_imports(source: str, module: str, is_package: bool = False) -> list[str]:
    """Private names (one leading underscore) that ``module`` imports from another camdyn
    module: ``["camdyn.x._y", ...]``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            origin = _resolve(module, is_package, node)
            if origin is None or not (origin == PACKAGE or origin.startswith(PACKAGE + ".")) or origin == module:
                continue
            found += [f"{origin}.{alias.name}" for alias in node.names
                      if alias.name.startswith("_") and not alias.name.startswith("__")]
        elif isinstance(node, ast.Import):
            found += [alias.name for alias in node.names
                      if alias.name.startswith(PACKAGE + ".")
                      and any(part.startswith("_") and not part.startswith("__")
                              for part in alias.name.split("."))]
    return found


def _module_level(body):
    """Statements run at import: the module body, into ``if``/``try``/``with`` blocks,
    not into functions, classes or ``if TYPE_CHECKING:``."""
    for node in body:
        if isinstance(node, ast.If):
            test = ast.unparse(node.test)
            if "TYPE_CHECKING" not in test:
                yield from _module_level(node.body)
            yield from _module_level(node.orelse)
        elif isinstance(node, ast.Try):
            for part in (node.body, node.orelse, node.finalbody, *[h.body for h in node.handlers]):
                yield from _module_level(part)
        elif isinstance(node, ast.With):
            yield from _module_level(node.body)
        else:
            yield node


def imported_modules(source: str, module: str, modules: set[str], is_package: bool = False) -> set[str]:
    """The camdyn modules (of ``modules``) that ``module`` imports at module level: for
    ``from a import b``, ``a.b`` when it is a module, else ``a``."""
    found = set()
    for node in _module_level(ast.parse(source).body):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name in modules}
        elif isinstance(node, ast.ImportFrom):
            origin = _resolve(module, is_package, node)
            for alias in node.names:
                if f"{origin}.{alias.name}" in modules:
                    found.add(f"{origin}.{alias.name}")
                elif origin in modules:
                    found.add(origin)
    found.discard(module)
    return found


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of a directed graph as ``[a, b, ..., a]``, or None."""
    state = {}
    stack = []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                cycle = visit(nxt)
                if cycle:
                    return cycle
        stack.pop()
        state[node] = "done"
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def forbidden_mentions(text: str) -> list[tuple[int, str, str]]:
    """``[(line number, what, line)]`` for each line naming something of
    :data:`FORBIDDEN_MENTIONS`."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for what, pattern in FORBIDDEN_MENTIONS.items():
            if pattern.search(line):
                found.append((number, what, line.strip()))
    return found


# --- the repository ---------------------------------------------------------------------


def _sources() -> dict[str, tuple[Path, str]]:
    return {module_name(path): (path, path.read_text(encoding="utf-8"))
            for path in sorted((SRC / PACKAGE).rglob("*.py"))}


def _text_files():
    paths = [ROOT / name for name in TEXT_FILES]
    for folder in TEXT_FOLDERS:
        paths += sorted(p for p in (ROOT / folder).rglob("*")
                        if p.is_file() and "__pycache__" not in p.parts and ".egg-info" not in str(p))
    for path in paths:
        if not path.is_file():
            continue
        try:
            yield path, path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue   # images, compiled caches


def test_no_long_modules():
    long = long_modules({name: text for name, (_, text) in _sources().items()})
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def test_no_long_functions():
    long = {f"{name}.{func}": lines for name, (_, text) in _sources().items()
            for func, lines in long_functions(text)}
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


def test_no_private_names_cross_modules():
    found = {name: private for name, (path, text) in _sources().items()
             if (private := private_imports(text, name, path.name == "__init__.py"))}
    assert not found, f"private names imported from other modules: {found}"


def test_no_import_cycles():
    sources = _sources()
    modules = set(sources)
    graph = {name: imported_modules(text, name, modules, path.name == "__init__.py")
             for name, (path, text) in sources.items()}
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_no_forbidden_mentions():
    found = [f"{path.relative_to(ROOT)}:{number}: {what}: {line}"
             for path, text in _text_files() for number, what, line in forbidden_mentions(text)]
    assert not found, "forbidden mentions:\n" + "\n".join(found)


# --- the checkers can fail ----------------------------------------------------------------


def _function(lines: int) -> str:
    body = "".join(f"    x{i} = {i}\n" for i in range(lines - 1))
    return f"def f():\n{body}"


@pytest.mark.parametrize("lines, flagged", [(100, False), (101, True)])
def test_checker_long_functions(lines, flagged):
    assert bool(long_functions(_function(lines))) == flagged
    method = "class A:\n" + "".join("    " + line + "\n" for line in _function(lines).splitlines())
    assert long_functions(method) == ([("A.f", lines)] if flagged else [])
    nested = "def outer():\n" + "".join("    " + line + "\n" for line in _function(lines).splitlines())
    assert [name for name, _ in long_functions(nested)] == (["outer", "outer.f"] if flagged else ["outer"])


@pytest.mark.parametrize("source, module, expected", [
    ("from camdyn.model.layout import _pack\n", "camdyn.io.netcdf", ["camdyn.model.layout._pack"]),
    ("from camdyn.model.layout import pack, _x as y\n", "camdyn.sweeps.kernel", ["camdyn.model.layout._x"]),
    ("from .geometry import _helper\n", "camdyn.model.outputs", ["camdyn.model.geometry._helper"]),
    ("import camdyn.model._private\n", "camdyn.io.netcdf", ["camdyn.model._private"]),
    ("def f():\n    from camdyn.model.layout import _late\n", "camdyn.io.netcdf", ["camdyn.model.layout._late"]),
    ("from camdyn.model.layout import pack, __version__\n", "camdyn.io.netcdf", []),
    ("from numpy import _core\n", "camdyn.io.netcdf", []),
])
def test_checker_private_imports(source, module, expected):
    assert private_imports(source, module) == expected


MODULES = {"camdyn", "camdyn.a", "camdyn.b", "camdyn.c", "camdyn.pkg", "camdyn.pkg.d"}


@pytest.mark.parametrize("sources, cycle", [
    ({"camdyn.a": "from camdyn.b import x\n", "camdyn.b": "from camdyn import c\n", "camdyn.c": "import camdyn.a\n"},
     ["camdyn.a", "camdyn.b", "camdyn.c", "camdyn.a"]),
    ({"camdyn.a": "from camdyn.b import x\n", "camdyn.b": "from camdyn.a import y\n"},
     ["camdyn.a", "camdyn.b", "camdyn.a"]),
    ({"camdyn.a": "from camdyn.b import x\n", "camdyn.b": "def f():\n    from camdyn.a import y\n"}, None),
    ({"camdyn.a": "from camdyn.b import x\n",
      "camdyn.b": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from camdyn.a import y\n"}, None),
    ({"camdyn.pkg": "from camdyn.pkg.d import x\n", "camdyn.pkg.d": "from . import y\n"},
     ["camdyn.pkg", "camdyn.pkg.d", "camdyn.pkg"]),
    ({"camdyn.a": "try:\n    import camdyn.b\nexcept ImportError:\n    pass\n", "camdyn.b": "import camdyn.a\n"},
     ["camdyn.a", "camdyn.b", "camdyn.a"]),
])
def test_checker_import_cycles(sources, cycle):
    graph = {name: imported_modules(text, name, MODULES, is_package=name == "camdyn.pkg")
             for name, text in sources.items()}
    assert find_cycle(graph) == cycle


@pytest.mark.parametrize("text, flagged", [
    ("see " + "MODEL" + ".md section 5", True),
    ("numbers in " + "PERFORMANCE" + ".md", True),
    ("copied from " + "shared" + "/notes.txt", True),
    ("fixes " + "issue" + " 5", True),
    ("as asked in " + "Issue" + " #12", True),
    ("docs/model.md section 5", False),
    ("a non-issue, 5 times", False),
    ("shared memory", False),
])
def test_checker_forbidden_mentions(text, flagged):
    assert bool(forbidden_mentions("first line\n" + text)) == flagged


@pytest.mark.parametrize("lines, flagged", [(MAX_MODULE_LINES, False), (MAX_MODULE_LINES + 1, True)])
def test_checker_long_modules(lines, flagged):
    sources = {"camdyn.short": "x = 1\n", "camdyn.long": "x = 1\n" * lines}
    assert long_modules(sources) == ({"camdyn.long": lines} if flagged else {})


def test_module_names():
    assert module_name(SRC / PACKAGE / "integrator" / "driver.py") == "camdyn.integrator.driver"
    assert module_name(SRC / PACKAGE / "integrator" / "__init__.py") == "camdyn.integrator"


# --- leftovers and the architecture page against the tree -------------------------------

#: A merge-conflict marker at the start of a line (written as a pattern so that this file
#: does not match itself).
CONFLICT_MARKER = re.compile(r"^(?:<{7}|>{7})(?: .*)?$|^={7}$", re.MULTILINE)
ARCHITECTURE = ROOT / "docs" / "architecture.md"


def conflict_markers(text: str) -> list[int]:
    """Line numbers (1-based) of merge-conflict markers in ``text``."""
    return [text.count("\n", 0, match.start()) + 1 for match in CONFLICT_MARKER.finditer(text)]


def undocumented_modules(page: str, tree: dict[str, list[str]]) -> list[str]:
    """Modules of ``tree`` (``{folder: [module file names]}``) that the architecture
    ``page`` does not name in its folder's table row (the row that starts ``| `folder/` |``),
    and folders that have no row."""
    missing = []
    for folder, names in sorted(tree.items()):
        row = next((line for line in page.splitlines() if line.startswith(f"| `{folder}/` |")), None)
        if row is None:
            missing.append(f"{folder}/ (no row)")
            continue
        missing += [f"{folder}/{name}" for name in names if f"`{name}`" not in row]
    return missing


def _tracked_text_files() -> list[Path]:
    import subprocess

    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=False)
    if listed.returncode != 0:   # not a git checkout (an sdist): every file under the root
        return [p for p in ROOT.rglob("*") if p.is_file() and ".git" not in p.parts and ".venv" not in p.parts]
    return [ROOT / name for name in listed.stdout.decode().split("\0") if name]


def test_no_conflict_markers():
    found = {}
    for path in _tracked_text_files():
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue   # binary files (figures, records)
        lines = conflict_markers(text)
        if lines:
            found[str(path.relative_to(ROOT))] = lines
    assert not found, f"merge-conflict markers left in {found}"


def test_architecture_page_names_every_module():
    tree = {}
    for folder in sorted(p for p in (SRC / PACKAGE).iterdir() if p.is_dir() and p.name != "__pycache__"):
        tree[folder.name] = sorted(f.name for f in folder.glob("*.py") if f.name != "__init__.py")
    assert undocumented_modules(ARCHITECTURE.read_text(encoding="utf-8"), tree) == []


@pytest.mark.parametrize(("text", "lines"), [
    ("a\n" + "<" * 7 + " HEAD\nb\n" + "=" * 7 + "\nc\n" + ">" * 7 + " branch\n", [2, 4, 6]),
    ("a\n" + "=" * 8 + "\n" + "<" * 6 + " x\n", []),     # a rule of 8, a quote of 6: not markers
    ("x " + "<" * 7 + " HEAD\n", []),                     # not at the start of a line
])
def test_checker_conflict_markers(text, lines):
    assert conflict_markers(text) == lines


@pytest.mark.parametrize(("page", "missing"), [
    ("| `io/` | files: `netcdf.py` and `atomic.py` | x |\n", []),
    ("| `io/` | files: `netcdf.py` | x |\n", ["io/atomic.py"]),
    ("| `cli/` | `atomic.py` `netcdf.py` |\n", ["io/ (no row)"]),
])
def test_checker_undocumented_modules(page, missing):
    assert undocumented_modules(page, {"io": ["atomic.py", "netcdf.py"]}) == missing


def layout_missing_folders(page: str, folders: list[str]) -> list[str]:
    """Folders of the package that the architecture page's layout table has no row for
    (a row starts ``| `folder/` |``)."""
    return [folder for folder in folders if f"\n| `{folder}/` |" not in page]


def test_layout_table_names_every_folder():
    folders = sorted(p.name for p in (SRC / PACKAGE).iterdir() if p.is_dir() and p.name != "__pycache__")
    assert layout_missing_folders((ROOT / "docs" / "architecture.md").read_text(encoding="utf-8"), folders) == []


def test_checker_layout_missing_folders():
    assert layout_missing_folders("x\n| `io/` | files |\n", ["io", "cli"]) == ["cli"]
