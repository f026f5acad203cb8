"""The driver compiled for one model: the integrator's source instantiated per model.

The bundled driver (:mod:`camdyn.integrator.driver`) reaches its models through
:mod:`camdyn.systems.registry`, a switch on integer ids compiled as a whole. A model
described by a :class:`camdyn.systems.protocol.Model` (a user's model, written as numba
functions outside the package) gets a driver of its own instead: the integrator's
modules that call a model (:data:`MODEL_MODULES`), the registry and the variational
system (:data:`SYSTEM_MODULES`) are written, unchanged but for their imports, into a
package in camdyn's cache folder, beside a generated adapter module that stands for
:mod:`camdyn.systems.models` with that one model
(:func:`camdyn.systems.protocol.adapter_source`); the model's variational system
(state-transition matrix, saltation at events, parameter sensitivities) comes with it.
numba compiles only that model's code, inlines it as it inlines the bundled models', and caches it on disk: a second
process loads it without compiling.

The package's name is a hash of the integrator's source, the adapter and the model's
own module sources, so a change to any of them compiles a new driver instead of loading
a stale one (numba's cache does not follow changes in called functions' modules).

Measured (docs/design-notes/compiled-driver.md): numba caches neither a closure over the model's
functions nor a driver that takes them as arguments across processes (the dispatcher
types are keyed by object identity), which is why the driver is instantiated from
source.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import os
import re
import shutil
import sys
import tempfile
import threading
from pathlib import Path
from types import ModuleType

from camdyn.compiled_cache import digests
from camdyn.errors import ParameterError

__all__ = ["MODEL_MODULES", "cache_root", "instance", "instance_key"]

#: The integrator's modules that call a model (through ``systems``), written again per
#: model; the others (counters, tableaus, linear algebra, tolerances, the inlining pass,
#: the Ctrl-C poll) are shared.
MODEL_MODULES = ("nordsieck", "steppers", "sampling", "crossings", "events", "multistep", "implicit", "driver")
#: The registry and the variational system (:mod:`camdyn.systems`), written again per
#: model over the adapter, so that the model's variational system (state-transition
#: matrix, saltation at events, parameter sensitivities) comes with its driver.
SYSTEM_MODULES = ("variational", "registry")
_HERE = Path(__file__).resolve().parent
_SYSTEMS = _HERE.parent / "systems"
#: An import left pointing at the bundled registry, models or model-calling modules.
_STALE_IMPORT = re.compile(r"^\s*(?:from|import)\s+camdyn\.(?:systems|integrator\.(?:"
                           + "|".join(MODEL_MODULES) + r"))\b", re.MULTILINE)
_LOCK = threading.Lock()
_LOADED: dict[str, ModuleType] = {}


def cache_root() -> Path:
    """The folder of the generated drivers: ``$CAMDYN_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/camdyn`` (``~/.cache/camdyn``), each under ``models/``."""
    base = os.environ.get("CAMDYN_CACHE_DIR")
    if not base:
        base = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "camdyn")
    return Path(base) / "models"


@functools.lru_cache(maxsize=1)
def _integrator_sources() -> dict[str, str]:
    """The sources written again per model, read once per process (every run hashes them)."""
    sources = {name: (_HERE / f"{name}.py").read_text(encoding="utf-8") for name in MODEL_MODULES}
    sources.update({name: (_SYSTEMS / f"{name}.py").read_text(encoding="utf-8") for name in SYSTEM_MODULES})
    return sources


@functools.lru_cache(maxsize=1)
def _shared_sources() -> str:
    """The digests of the compiled packages the generated driver imports from
    (integrator, systems, model: its shared steppers, linear algebra and physics; params:
    the law constants the model's code freezes in)."""
    shared = ("camdyn/integrator/", "camdyn/systems/", "camdyn/model/", "camdyn/params/")
    return "".join(f"{name}:{sha}\n" for name, sha in digests(_HERE.parent).items() if name.startswith(shared))


def instance_key(adapter: str, dependencies: tuple[str, ...] = ()) -> str:
    """The hash that names one model's driver package: of the integrator's model-calling
    modules, the compiled modules it imports from (:func:`_shared_sources`), the adapter's
    source and the sources of ``dependencies`` (the model's own modules, as file paths)."""
    digest = hashlib.sha256()
    for name, text in sorted(_integrator_sources().items()):
        digest.update(name.encode())
        digest.update(text.encode())
    digest.update(_shared_sources().encode())
    digest.update(adapter.encode())
    for path in dependencies:
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:20]


def _rewrite(text: str, package: str) -> str:
    """A module's source with its imports pointed at the instance package: the model's
    adapter as the registry's ``models``, the package's own registry, variational system
    and model-calling modules."""
    text = text.replace("from camdyn.systems import registry as systems", f"from {package} import registry as systems")
    text = text.replace("from camdyn.systems import models, variational",
                        f"from {package} import adapter as models\nfrom {package} import variational")
    text = text.replace("from camdyn.systems import models", f"from {package} import adapter as models")
    text = text.replace("from camdyn.systems.models import", f"from {package}.adapter import")
    text = text.replace("from camdyn.systems.variational import", f"from {package}.variational import")
    for name in MODEL_MODULES:
        text = re.sub(rf"\bfrom camdyn\.integrator\.{name} import\b", f"from {package}.{name} import", text)
    return text


def _write_package(folder: Path, package: str, adapter: str) -> None:
    """Write the package atomically: into a fresh temporary folder beside it, renamed
    into place (a concurrent writer's identical package wins and ours is dropped)."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{package}.", dir=folder.parent))
    try:
        (staging / "__init__.py").write_text(f'"""camdyn: a driver generated for one model ({package})."""\n')
        (staging / "adapter.py").write_text(adapter)
        for name, text in _integrator_sources().items():
            rewritten = _rewrite(text, package)
            if re.search(_STALE_IMPORT, rewritten):
                raise RuntimeError(f"{name}.py imports the bundled models in a way instances.py does not rewrite")
            (staging / f"{name}.py").write_text(rewritten)
        try:
            os.rename(staging, folder)
        except OSError:
            if not (folder / "driver.py").exists():
                raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def instance(adapter: str, dependencies: tuple[str, ...] = ()) -> ModuleType:
    """The driver module (its ``integrate`` has the bundled driver's signature) compiled
    for the model that ``adapter`` (a module's source) describes.

    Raises
    ------
    ParameterError
        The cache folder cannot be written.
    """
    key = instance_key(adapter, dependencies)
    package = f"camdyn_model_{key}"
    with _LOCK:
        if package in _LOADED:
            return _LOADED[package]
        root = cache_root()
        folder = root / package
        if not (folder / "driver.py").exists():
            try:
                _write_package(folder, package, adapter)
            except OSError as exc:
                raise ParameterError(f"cannot write the model's compiled driver into {root}: {exc.strerror or exc}; "
                                     "set CAMDYN_CACHE_DIR to a writable folder") from None
        if str(root) not in sys.path:
            sys.path.append(str(root))
        driver = importlib.import_module(f"{package}.driver")
        _compile_once(driver, root / f".{package}.lock")
        _LOADED[package] = driver
        return driver


#: The argument types of ``integrate`` as every caller passes them (one tolerance for
#: every component): compiled, or loaded from the cache, when the driver is first asked for.
SIGNATURE = "(int64, float64[::1], float64[::1], float64, float64, float64[::1], float64, float64, float64, int64, " \
            "int64, int64, boolean, float64)"


def _compile_once(driver: ModuleType, lock: Path) -> None:
    """Compile (or load from numba's cache) the driver's usual signature while holding
    ``lock``, so that processes that ask for the same new driver at once (workers, test
    processes) compile it once: the others wait, then load it from the cache."""
    import fcntl

    try:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
    except OSError:   # a read-only cache folder, or something planted at the lock's name
        driver.integrate.compile(SIGNATURE)
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        driver.integrate.compile(SIGNATURE)
    finally:
        os.close(fd)
