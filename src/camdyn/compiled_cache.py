"""numba's disk cache kept in step with camdyn's sources.

numba checks a cached function against its own source file only (time stamp and size).
camdyn's compiled code inlines functions of other modules and freezes their module-level
constants into the machine code, so a change to ``model/contact.py`` or to
``model/layout.py`` leaves the cached driver with the old contact law or the old slot
numbers: measured, a stale cached ``crossings.guard_at`` kept an old dense-output routine
and found 51 spurious events in 0.2 revolutions. A fresh install rewrites every file and
is not affected; a ``git pull`` or ``git checkout`` into an editable install, which
changes only some files, is.

:func:`refresh` (called once per process before anything compiled is loaded) keeps a
digest of every source file of the package beside the cache; where files changed since,
it removes the cache entries of those modules and of every module that imports them,
directly or not (:func:`importers`), so that numba compiles exactly the code that can
see the change. Where the package's folders are not writable (an installed package),
the same is done in numba's per-user cache folder, where numba then keeps its entries
(numba stamps a file by its content, so a reinstall that changes only a called module
leaves the caller's entry there too).
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
import tempfile
from pathlib import Path

__all__ = ["STAMP", "cache_folder", "digests", "importers", "refresh", "remove_entries", "write_stamp"]

#: The file, in the package's own cache folder, that holds the digests of the sources
#: the cache was compiled from.
STAMP = "camdyn-sources.json"
_PACKAGE = Path(os.path.abspath(__file__)).parent   # as numba names it: symbolic links kept


def digests(package: Path) -> dict[str, str]:
    """SHA-1 of every ``.py`` file under ``package``, keyed by its path relative to the
    package's parent folder (``camdyn/model/contact.py``)."""
    root = package.parent
    return {f.relative_to(root).as_posix(): hashlib.sha1(f.read_bytes()).hexdigest()
            for f in sorted(package.rglob("*.py"))}


def importers(src: Path, targets, package: Path | None = None) -> set[str]:
    """The files (relative to ``src``) of ``targets`` and of every module under ``src``
    (under ``package`` only, if given: an installed package's ``src`` is all of
    site-packages) that imports one of them, directly or through others (a target may be
    a file that no longer exists: its importers are found by its module's name)."""
    files = {f.relative_to(src).as_posix() for f in (package or src).rglob("*.py")}
    modules = {Path(path).with_suffix("").as_posix().replace("/", "."): path for path in files | set(targets)}
    modules.update({name.removesuffix(".__init__"): path for name, path in list(modules.items())
                    if name.endswith(".__init__")})
    imports: dict[str, set[str]] = {}
    for path in files:
        found = set()
        try:
            tree = ast.parse((src / path).read_text(encoding="utf-8"))
        except (OSError, SyntaxError, ValueError):   # its own import will say what is wrong
            tree = ast.Module(body=[], type_ignores=[])
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                found.add(node.module)
                found.update(f"{node.module}.{alias.name}" for alias in node.names)
        imports[path] = {modules[m] for m in found if m in modules}
    stale = set(targets)
    while True:
        more = {path for path, used in imports.items() if used & stale} - stale
        if not more:
            return stale
        stale |= more


def cache_folder(folder: Path, base: str | os.PathLike | None = None) -> Path | None:
    """The folder where numba caches the compiled functions of the sources in ``folder``:
    under ``base`` (default ``$NUMBA_CACHE_DIR``; the folder's name and the SHA-1 of its
    absolute path, as ``numba.core.caching`` names it) where that can be written, else
    ``folder/__pycache__`` where ``folder`` is writable, else numba's per-user cache
    folder (named as under ``base``), in numba's own order."""
    base = base or os.environ.get("NUMBA_CACHE_DIR")
    folder = Path(os.path.abspath(folder))
    named = "_".join([folder.name, hashlib.sha1(str(folder).encode()).hexdigest()])
    if base and _writable(Path(base) / named):
        return Path(base) / named
    if os.access(folder, os.W_OK):
        return folder / "__pycache__"
    # an installed package that cannot be written: numba's per-user cache folder
    from numba.misc.appdirs import AppDirs

    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir) / named


def _writable(folder: Path) -> bool:
    """Whether ``folder`` exists or can be made, and can be written (numba's own test
    before it uses a cache folder)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(folder, os.W_OK)


def remove_entries(src: Path, files) -> int:
    """Remove numba's cache entries (``.nbi``, ``.nbc``) of the modules ``files`` (paths
    relative to ``src``); returns how many were removed."""
    removed = 0
    for file in files:
        path = src / file
        folder = cache_folder(path.parent)
        if folder is None or not folder.is_dir():
            continue
        for entry in folder.iterdir():
            if entry.suffix in (".nbi", ".nbc") and entry.name.split(".")[0] == path.stem:
                try:
                    entry.unlink()
                    removed += 1
                except FileNotFoundError:   # a concurrent process removed it first
                    pass
    return removed


@functools.lru_cache(maxsize=1)
def refresh(package: Path = _PACKAGE) -> int:
    """Remove the cache entries that the sources' changes since the last call made stale
    (see the module's text); returns how many were removed. Once per process."""
    folder = cache_folder(package)
    if folder is None:
        return 0
    try:
        now = digests(package)
    except OSError:   # an unreadable source: its import fails with its own message
        return 0
    stamp = folder / STAMP
    try:
        before = json.loads(stamp.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        before = {}   # no record: any entry present may be stale
    if before == now:
        return 0
    changed = {f for f in set(now) | set(before) if now.get(f) != before.get(f)}
    src = package.parent
    try:
        removed = remove_entries(src, importers(src, changed, package))
    except OSError:   # entries that cannot be removed: left, and the record not updated
        return 0
    write_stamp(folder, now)
    return removed


def write_stamp(folder: Path, sources: dict[str, str]) -> None:
    """Record ``sources`` (:func:`digests`) as those the cache in ``folder`` holds,
    atomically; nothing where the folder cannot be written (numba will not write there
    either)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{STAMP}.", suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(sources, fh)
        os.replace(tmp, folder / STAMP)
    except OSError:
        pass
