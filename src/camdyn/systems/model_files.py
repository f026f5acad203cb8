"""Models in files: a :class:`~camdyn.systems.protocol.Model` named by the file that
defines it, ``"path/to/valve_train.py:VALVE_TRAIN"``, so that a sweep spec, a command
line or a worker process on the same machine can load it again.

The file is imported under its own name (``valve_train``), as the model's compiled
driver imports its functions by that name (:func:`camdyn.systems.protocol.adapter_source`).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from camdyn.errors import ParameterError
from camdyn.systems.protocol import BoundModel, Model

__all__ = ["is_model_reference", "load_model", "model_reference"]


def is_model_reference(source) -> bool:
    """Whether ``source`` names a model in a Python file (``FILE.py`` or ``FILE.py:NAME``)."""
    if not isinstance(source, str):
        return False
    path = source.rsplit(":", 1)[0] if ":" in source and not source.endswith(".py") else source
    return path.endswith(".py")


def _split(reference: str) -> tuple[str, str | None]:
    if reference.endswith(".py"):
        return reference, None
    path, _, name = reference.rpartition(":")
    return path, (name or None)


def load_model(reference: str, base_dir: str | Path | None = None) -> Model:
    """The model that ``reference`` names.

    Parameters
    ----------
    reference : str
        ``"FILE.py:NAME"`` (the module-level ``Model`` called ``NAME``) or ``"FILE.py"``
        (its one module-level ``Model``); a relative ``FILE`` is read from ``base_dir``.
    base_dir : str or Path, optional
        Folder of a relative file (default the working directory).

    Raises
    ------
    ParameterError
        No such file, a file that does not import, no model of that name, or another
        module of the same name already imported from another file.
    """
    if not is_model_reference(reference):
        raise ParameterError(f"a model is named as FILE.py:NAME, got {reference!r}")
    text, name = _split(reference)
    path = Path(text)
    if not path.is_absolute():
        path = Path(base_dir or ".") / path
    path = path.resolve()
    if not path.is_file():
        raise ParameterError(f"model file {str(path)!r} does not exist")
    module = _import(path)
    models = {key: value for key, value in vars(module).items() if isinstance(value, Model)}
    if name is None:
        if len(models) != 1:
            raise ParameterError(f"{path.name} defines {len(models)} models ({', '.join(models) or 'none'}); "
                                 f"name one as {path.name}:NAME")
        return next(iter(models.values()))
    if name not in models:
        raise ParameterError(f"{path.name} has no model {name!r}; its models: {', '.join(models) or 'none'}")
    return models[name]


def _import(path: Path):
    """The module of ``path``, imported once per process under the file's stem."""
    stem = path.stem
    known = sys.modules.get(stem)
    if known is not None:
        known_file = getattr(known, "__file__", None)
        if known_file and Path(known_file).resolve() == path:
            return known
        raise ParameterError(f"a module named {stem!r} is already imported from {known_file or 'elsewhere'}; "
                             f"rename the model file {path}")
    spec = importlib.util.spec_from_file_location(stem, path)
    if spec is None or spec.loader is None:
        raise ParameterError(f"cannot import the model file {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[stem] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:   # the user's file: any error in it is reported as the file's
        del sys.modules[stem]
        raise ParameterError(f"the model file {path.name} does not import: {type(exc).__name__}: {exc}") from None
    return module


def model_reference(model: Model | BoundModel) -> str:
    """``"FILE.py:NAME"`` of a model defined at the top level of a module file (the
    reference :func:`load_model` reads back)."""
    model = model.model if isinstance(model, BoundModel) else model
    if not isinstance(model, Model):
        raise ParameterError(f"expected a camdyn.Model, got {type(model).__name__}")
    rhs = model.functions["rhs"].py_func
    module = sys.modules.get(rhs.__module__)
    path = getattr(module, "__file__", None)
    names = [key for key, value in vars(module).items() if value is model] if module is not None else []
    if path is None or not names:
        raise ParameterError(f"model {model.name!r} must be a module-level name in the file that defines its "
                             "functions, so that other processes can load it")
    return f"{Path(path).resolve()}:{names[0]}"
