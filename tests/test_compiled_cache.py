"""numba's disk cache kept in step with the sources (camdyn.compiled_cache).

numba checks a cached function against its own file only; a function that inlines one
of another module keeps the old machine code when only that other module changes. The
first test shows the defect on numba itself, and the fix; the others check which
entries the fix removes.
"""

import hashlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from camdyn import compiled_cache

RUN = """
import sys
sys.path.insert(0, {src!r})
from pathlib import Path
from camdyn.compiled_cache import refresh
if {guarded}:
    refresh.__wrapped__(Path({src!r}) / "pkg")
from pkg.caller import value
print(value())
"""


def _write_callee(src: Path, constant: str) -> None:
    (src / "pkg" / "callee.py").write_text(textwrap.dedent(f"""
        import numba

        @numba.njit(cache=True)
        def constant():
            return {constant}
    """))


def _write_package(src: Path, constant: str) -> None:
    (src / "pkg").mkdir(exist_ok=True)
    (src / "pkg" / "__init__.py").write_text("")
    _write_callee(src, constant)
    (src / "pkg" / "caller.py").write_text(textwrap.dedent("""
        import numba
        from pkg.callee import constant

        @numba.njit(cache=True)
        def value():
            return constant() + 1.0
    """))


def _value(src: Path, guarded: bool) -> str:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    proc = subprocess.run([sys.executable, "-c", RUN.format(src=str(src), guarded=guarded)],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip()


@pytest.mark.parametrize("guarded", [False, True])
def test_a_change_in_a_called_module_reaches_the_cached_caller_only_with_refresh(tmp_path, guarded):
    _write_package(tmp_path, "1.0")
    assert _value(tmp_path, guarded) == "2.0"
    _write_callee(tmp_path, "41.0")           # only the callee's file changes
    seen = _value(tmp_path, guarded)
    if guarded:
        assert seen == "42.0"
    else:                                     # numba alone: the caller's stale machine code
        assert seen == "2.0"


def _package(root: Path) -> Path:
    pkg = root / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("A = 1\n")
    (pkg / "b.py").write_text("from pkg.a import A\n")
    (pkg / "c.py").write_text("C = 3\n")
    (pkg / "ab.py").write_text("AB = 4\n")
    (pkg / "sub" / "d.py").write_text("from pkg import b\n")
    return pkg


ENTRIES = {"": ["a.f-1.py311.nbi", "a.f-1.py311.1.nbc", "b.g-3.py311.nbi", "c.h-1.py311.nbi",
                "ab.x-1.py311.nbi", "notes.txt"],
           "sub": ["d.k-1.py311.nbi"]}


def _entries(folder_of, pkg: Path) -> None:
    for sub, names in ENTRIES.items():
        folder = folder_of(pkg / sub if sub else pkg)
        folder.mkdir(parents=True, exist_ok=True)
        for name in names:
            (folder / name).write_text("x")


def _left(folder_of, pkg: Path) -> set[str]:
    return {e.name for sub in ENTRIES for e in folder_of(pkg / sub if sub else pkg).iterdir()
            if not e.name.startswith(compiled_cache.STAMP)}


@pytest.mark.parametrize("numba_cache_dir", [False, True])
def test_entries_of_a_changed_module_and_of_its_importers_are_removed(tmp_path, monkeypatch, numba_cache_dir):
    if numba_cache_dir:
        base = tmp_path / "numba-cache"
        monkeypatch.setenv("NUMBA_CACHE_DIR", str(base))

        def folder_of(folder):   # numba.core.caching's layout, written out here
            folder = os.path.abspath(folder)
            return base / f"{os.path.basename(folder)}_{hashlib.sha1(folder.encode()).hexdigest()}"
    else:
        monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)

        def folder_of(folder):
            return Path(folder) / "__pycache__"
    pkg = _package(tmp_path / "src")
    refresh = compiled_cache.refresh.__wrapped__
    _entries(folder_of, pkg)
    # no record of the sources: every entry may be stale
    assert refresh(pkg) == 6
    assert _left(folder_of, pkg) == {"notes.txt"}
    _entries(folder_of, pkg)
    assert refresh(pkg) == 0                 # nothing changed
    (pkg / "a.py").write_text("A = 2\n")     # a, and b that imports it, and d that imports b
    assert refresh(pkg) == 4
    assert _left(folder_of, pkg) == {"c.h-1.py311.nbi", "ab.x-1.py311.nbi", "notes.txt"}
    _entries(folder_of, pkg)
    (pkg / "sub" / "d.py").write_text("from pkg import b, c\n")   # d only
    assert refresh(pkg) == 1
    assert "d.k-1.py311.nbi" not in _left(folder_of, pkg)
    _entries(folder_of, pkg)
    (pkg / "c.py").unlink()                  # a module removed: those importing it
    assert refresh(pkg) == 2                 # d (imports c) and c's own entry
    assert _left(folder_of, pkg) == {"a.f-1.py311.nbi", "a.f-1.py311.1.nbc", "b.g-3.py311.nbi",
                                     "ab.x-1.py311.nbi", "notes.txt"}


def test_the_installed_package_is_recorded_after_import():
    import json

    folder = compiled_cache.cache_folder(Path(compiled_cache.__file__).parent)
    if folder is None:
        pytest.skip("camdyn's folder is not writable here: numba caches elsewhere")
    recorded = json.loads((folder / compiled_cache.STAMP).read_text())
    assert recorded == compiled_cache.digests(Path(compiled_cache.__file__).parent)
