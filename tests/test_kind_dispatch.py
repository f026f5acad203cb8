"""Dispatch on a model's kind or id outside the model registry, counted by an AST scan.

The aim is none: every consumer (simulate, continuation, sweeps, the command line) calls
a model through its descriptor, and only ``camdyn/systems/`` tells models apart. Today's
count is :data:`BASELINE`, module by module; this test fails when a module gains a
dispatch (write it into the model's descriptor or family instead) and when one loses
some (lower its baseline, so that the count only goes down).

A dispatch is:

- a comparison with a system id of the registry (``system == CAM_FOLLOWER``);
- a comparison of a ``kind`` with a kind's name (``spec.kind == "driven-cam"``);
- a call of a kind predicate (``is_mechanism(source)``, ``declared_kind(...)``, ...);
- ``isinstance`` on a rig, follower or mechanism class.

A check whose only consequence is an error (``if not isinstance(rig, Rig): raise ...``)
validates an argument; it is not counted.
"""

from __future__ import annotations

import ast
import collections
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "camdyn"
KIND_PREDICATES = {"is_mechanism", "is_translating", "declared_kind", "is_autonomous", "is_rocking",
                   "is_model_reference"}
KIND_NAMES = {"translating", "rocking", "driven-cam", "flexible-pivot", "two-followers", "prescribed"}
CLASS_SUFFIXES = ("Rig", "Follower", "Mechanism")

#: dispatches per module (relative to src/camdyn), measured when this test was written
BASELINE = {
    "cli/analysis.py": 3, "cli/continuation.py": 5, "cli/mechanism.py": 2, "cli/simulate.py": 6, "cli/sweep.py": 1,
    "continuation/autonomous.py": 4, "continuation/margins.py": 2, "continuation/mechanisms.py": 3,
    "continuation/problem.py": 1, "io/mechanism_config.py": 8, "sweeps/families.py": 2,
    "sweeps/mechanism_metrics.py": 4,
}


def registry_ids() -> set[str]:
    """The names of the registry's system ids (``NAME = integer`` in the systems modules)."""
    text = "".join((SRC / "systems" / name).read_text() for name in ("models.py", "mechanisms.py"))
    return set(re.findall(r"^([A-Z][A-Z0-9_]+)\s*=\s*\d+\s*$", text, re.M))


def _name(node) -> str:
    return node.attr if isinstance(node, ast.Attribute) else (node.id if isinstance(node, ast.Name) else "")


def _is_dispatch(node, ids: set[str]) -> bool:
    if isinstance(node, ast.Compare):
        operands = [node.left, *node.comparators]
        if any(_name(n) in ids for n in operands):
            return True
        names = {n.value for n in operands if isinstance(n, ast.Constant) and isinstance(n.value, str)}
        return bool(names & KIND_NAMES) and any(_name(n) == "kind" for n in operands)
    if isinstance(node, ast.Call):
        if _name(node.func) in KIND_PREDICATES:
            return True
        if _name(node.func) == "isinstance" and len(node.args) == 2:
            classes = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
            return any(_name(c).endswith(CLASS_SUFFIXES) for c in classes)
    return False


def dispatches(source: str, ids: set[str]) -> int:
    """The dispatches in one module's ``source`` (not those of a check that only raises)."""
    tree = ast.parse(source)
    validating = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and node.body and all(isinstance(s, ast.Raise) for s in node.body) \
                and not node.orelse:
            validating |= {id(n) for n in ast.walk(node.test)}
    return sum(1 for node in ast.walk(tree) if id(node) not in validating and _is_dispatch(node, ids))


def scan() -> dict[str, int]:
    ids = registry_ids()
    counts = collections.Counter()
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel.startswith("systems/"):
            continue
        n = dispatches(path.read_text(encoding="utf-8"), ids)
        if n:
            counts[rel] = n
    return dict(counts)


def test_no_module_gains_a_dispatch_on_a_models_kind():
    found = scan()
    more = {m: (BASELINE.get(m, 0), n) for m, n in found.items() if n > BASELINE.get(m, 0)}
    fewer = {m: (b, found.get(m, 0)) for m, b in BASELINE.items() if found.get(m, 0) < b}
    assert not more, f"modules that gained a dispatch on a model's kind (baseline, now): {more}"
    assert not fewer, f"modules that lost dispatches: lower BASELINE to the new counts (baseline, now): {fewer}"


def test_the_registry_ids_are_found():
    assert {"CAM_FOLLOWER", "TRANSLATING_FOLLOWER", "FLEXIBLE_PIVOT"} <= registry_ids()


@pytest.mark.parametrize("source, expected", [
    ("if system == registry.CAM_FOLLOWER:\n    x = 1\n", 1),
    ("y = 2 if spec.kind == 'driven-cam' else 3\n", 1),
    ("if is_mechanism(source):\n    run()\n", 1),
    ("if isinstance(rig, FlexiblePivotRig):\n    run()\n", 1),
    ("if not isinstance(rig, FlexiblePivotRig):\n    raise ParameterError('no')\n", 0),   # a check, not a dispatch
    ("if kind == 'linear':\n    run()\n", 0),                                          # not a model's kind
    ("if isinstance(x, (int, float)):\n    run()\n", 0),
])
def test_the_scan_tells_a_dispatch(source, expected):
    assert dispatches(source, {"CAM_FOLLOWER"}) == expected
