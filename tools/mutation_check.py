"""Mutation check: deliberate mistakes in the physics must make the tests fail.

For the unmutated source and for each mutant, the script copies ``src/`` to a temporary
folder, applies the mutant's exact text replacements to the copy (a replacement whose
text is not found the expected number of times stops the check: it cannot rot
silently when the code changes), and runs a fast subset of the tests against the copy
(``PYTHONPATH`` = the copy, its own ``NUMBA_CACHE_DIR`` per variant: numba checks only a
compiled function's own file for changes, so a shared cache would hand one variant
another's machine code). The unmutated copy starts from the checkout's own cache (what
the test suite compiled, where its sources are unchanged); each mutant's cache then
starts as a copy of its cache without the entries of the mutated module and of every
module that imports it, directly or not (found from the copy's import statements), so
that only code that can see the mistake is compiled again. A stale entry could only hide
a mistake (a survivor, which fails the check), never fake a kill. The subprocess reports
which ``camdyn`` it imported; a run that imported anything but its copy is an error.

The unmutated copy must pass the whole subset and every mutant must fail it; a mutant's
run stops at its first failing test (``pytest -x``), so the cheapest tests, listed first
in :data:`TESTS`, spare it the slow ones (its "tests failed" column counts the tests it
ran). The script
prints a table (mutant, tests failed, time, verdict) and exits with status 1 if any
mutant survives or the unmutated copy fails, 2 on a broken set-up.

Usage::

    python tools/mutation_check.py [--jobs N] [--only NAME ...] [--keep]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from camdyn.compiled_cache import cache_folder, digests, importers, write_stamp

ROOT = Path(__file__).resolve().parents[1]

#: The fast subset (node ids relative to the repository root), cheapest first: the
#: compiled right-hand side against the oracle's state by state (friction, the spring's arm
#: and tilt, adhesion clipping, the laws D and Flores; it compiles only the right-hand side,
#: so a mutant of a model module costs seconds, not a recompiled integrator), then the
#: Newton-Euler checks of the pivot reaction and of the acceleration (whole simulations:
#: the mistakes in outputs.py). The whole-simulation oracle comparisons of
#: tests/test_oracle_laws.py kill the same mutants of the model modules but recompile the
#: integrator for each; they stay in the test suite, not here.
TESTS = [
    "tests/test_oracle_rhs.py",
    "tests/test_pivot_reaction.py",
]


@dataclass(frozen=True)
class Mutant:
    """A deliberate mistake: ``(old, new, count)`` replacements in ``path`` (under ``src/``)."""

    name: str
    path: str
    edits: tuple = field(default_factory=tuple)


OUT = "camdyn/model/outputs.py"
DYN = "camdyn/model/dynamics.py"
#: The mutants, those of modules that the integrator compiles first (they compile from
#: nothing, or nearly), then those of outputs.py (their caches start from the unmutated one).
MUTANTS = [
    Mutant("friction moment sign flipped in the equation of motion", DYN, (
        ("moment += fn * chi + ff * p[L.OFFSET]", "moment += fn * chi - ff * p[L.OFFSET]", 2),
    )),
    Mutant("spring arm dx measured along the bar (dx sec alpha)", DYN, (
        ("        return -fs * p[L.DX]\n", "        return -fs * p[L.DX] / ca\n", 1),
    )),
    Mutant("tilted spring: the arm's depth * sin(sigma) part dropped", DYN, (
        ("return -fs * (p[L.DX] * math.cos(p[L.TILT]) + depth * math.sin(p[L.TILT]))",
         "return -fs * p[L.DX] * math.cos(p[L.TILT])", 1),
    )),
    Mutant("law D: branches swapped (viscous while compressing)", "camdyn/model/contact.py", (
        ("c = beta * kd * ad if delta_dot > 0.0 else viscous",
         "c = beta * kd * ad if delta_dot < 0.0 else viscous", 1),
    )),
    Mutant("Flores factor 8(1-e)/(5e) replaced by 3(1-e)/(2e)", "camdyn/params/laws.py", (
        ("    return 1.6 * (1.0 - e) / e\n", "    return 1.5 * (1.0 - e) / e\n", 1),
    )),
    Mutant("adhesion clipping ignored", "camdyn/model/contact.py", (
        ("p[L.V_REFERENCE], p[L.CLIP] > 0.5)", "p[L.V_REFERENCE], p[L.CLIP] > 1.5)", 1),
    )),
    Mutant("inertia dropped from the pivot reaction and its inverse", OUT, (
        ("nx = m * agx + fn * sa", "nx = fn * sa", 1),
        ("ny = m * agy + fn * ca", "ny = fn * ca", 1),
        ("a = nx[i] - m * agx + fs * st", "a = nx[i] + fs * st", 1),
        ("b = ny[i] - m * agy + fs * ct", "b = ny[i] + fs * ct", 1),
    )),
    Mutant("centripetal term dropped from the pivot reaction and its inverse", OUT, (
        ("(alpha_ddot * sa + alpha_dot * alpha_dot * ca)", "(alpha_ddot * sa)", 1),
        ("(alpha_ddot * ca - alpha_dot * alpha_dot * sa)", "(alpha_ddot * ca)", 1),
        ("(alpha_ddot[i] * sa + ad2 * ca)", "(alpha_ddot[i] * sa)", 1),
        ("(alpha_ddot[i] * ca - ad2 * sa)", "(alpha_ddot[i] * ca)", 1),
    )),
    Mutant("friction sign flipped in the pivot reaction and its inverse", OUT, (
        ("+ fn * sa - ff * ca - fs * st", "+ fn * sa + ff * ca - fs * st", 1),
        ("+ fn * ca + ff * sa - fs * ct", "+ fn * ca - ff * sa - fs * ct", 1),
        ("ff[i] = -a * ca + b * sa", "ff[i] = a * ca - b * sa", 1),
    )),
]

#: Runs in the subprocess: report the camdyn imported, run pytest, report it again.
BOOT = """
import sys
import camdyn
print("CAMDYN_FILE=" + camdyn.__file__, flush=True)
import pytest
rc = pytest.main(sys.argv[1:])
print("CAMDYN_FILE=" + sys.modules["camdyn"].__file__, flush=True)
sys.exit(int(rc))
"""


class SetupError(RuntimeError):
    """The check itself is broken (a replacement not found, the wrong camdyn imported)."""


def make_copy(work: Path, mutant: Mutant | None) -> Path:
    """Copy ``src/`` under ``work`` without compiled caches and apply ``mutant``; returns the copy's src."""
    dest = work / "src"
    shutil.copytree(ROOT / "src", dest, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc", "*.egg-info"))
    if mutant is not None:
        target = dest / mutant.path
        text = target.read_text()
        for old, new, count in mutant.edits:
            found = text.count(old)
            if found != count:
                raise SetupError(f"mutant {mutant.name!r}: {old!r} occurs {found} times in src/{mutant.path}, "
                                 f"expected {count}; update tools/mutation_check.py to the current code")
            text = text.replace(old, new)
        target.write_text(text)
    return dest


def seed_cache(seed: tuple[Path, Path], src: Path, cache: Path, mutant: Mutant) -> int:
    """Copy the unmutated copy's cache (``seed`` = its src and cache) into ``cache`` for
    the copy ``src``, leaving out the entries of the modules that can see the mutant;
    returns the number of entries copied."""
    seed_src, seed_cache_dir = seed
    stale = importers(src, {mutant.path})
    copied = 0
    for package in sorted({Path(f).parent.as_posix() for f in (p.relative_to(src).as_posix()
                                                               for p in src.rglob("*.py"))}):
        old = cache_folder(seed_src / package, seed_cache_dir)
        if not old.is_dir():
            continue
        fresh = {Path(f).stem for f in stale if Path(f).parent.as_posix() == package}
        new = cache_folder(src / package, cache)
        new.mkdir(parents=True, exist_ok=True)
        for entry in old.iterdir():
            if entry.name.split(".")[0] not in fresh:
                shutil.copy2(entry, new / entry.name)
                copied += 1
    return copied


def seed_from_checkout(src: Path, cache: Path) -> int:
    """Copy the checkout's own numba cache (``src/**/__pycache__``, written by the test
    suite, which runs first in CI) into ``cache`` for the unmutated copy ``src``; returns
    the number of entries copied. numba keeps an entry only where the copied source file's
    time stamp and size match it, and the copy keeps the time stamps."""
    copied = 0
    for folder in (ROOT / "src").rglob("__pycache__"):
        package = folder.parent.relative_to(ROOT / "src").as_posix()
        entries = [e for e in folder.iterdir() if e.suffix in (".nbi", ".nbc")]
        if not entries:
            continue
        new = cache_folder(src / package, cache)
        new.mkdir(parents=True, exist_ok=True)
        for entry in entries:
            shutil.copy2(entry, new / entry.name)
            copied += 1
    return copied


def run_variant(mutant: Mutant | None, keep: bool, seed: tuple[Path, Path] | None = None) -> dict:
    """Copy, mutate, run the subset (a mutant's cache seeded from ``seed``, the unmutated
    copy's src and cache, when given); returns name, counts, seconds and the output tail."""
    name = "(unmutated)" if mutant is None else mutant.name
    work = Path(tempfile.mkdtemp(prefix="camdyn-mutant-"))
    start = time.perf_counter()
    try:
        src = make_copy(work, mutant)
        if seed is not None and mutant is not None:
            seed_cache(seed, src, work / "numba-cache", mutant)
        elif mutant is None:
            seed_from_checkout(src, work / "numba-cache")
        # the entries seeded are those of these sources (camdyn.compiled_cache keeps the rest)
        write_stamp(cache_folder(src / "camdyn", work / "numba-cache"), digests(src / "camdyn"))
        env = dict(os.environ, PYTHONPATH=str(src), NUMBA_CACHE_DIR=str(work / "numba-cache"),
                   PYTHONDONTWRITEBYTECODE="1")
        report = work / "report.xml"
        # a mutant stops at its first failure (-x): the cheap tests come first, and one
        # failure kills it; the unmutated copy runs them all
        first = ["-x"] if mutant is not None else []
        cmd = [sys.executable, "-c", BOOT, "-q", "-p", "no:cacheprovider", *first, f"--junitxml={report}", *TESTS]
        proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        out = proc.stdout + proc.stderr
        imported = [line.split("=", 1)[1] for line in out.splitlines() if line.startswith("CAMDYN_FILE=")]
        if not imported or any(not Path(f).resolve().is_relative_to(src.resolve()) for f in imported):
            raise SetupError(f"{name}: the test run imported camdyn from {imported or 'nowhere'}, not {src}\n"
                             + out[-3000:])
        if not report.exists():
            raise SetupError(f"{name}: pytest wrote no report (exit {proc.returncode})\n{out[-3000:]}")
        suite = ET.parse(report).getroot()
        suite = suite if suite.tag == "testsuite" else suite.find("testsuite")
        counts = {k: int(suite.get(k, 0)) for k in ("tests", "failures", "errors", "skipped")}
        failed = [case.get("name") for case in suite.iter("testcase")
                  if case.find("failure") is not None or case.find("error") is not None]
        if counts["tests"] == 0:
            raise SetupError(f"{name}: no tests ran\n{out[-3000:]}")
        row = {"name": name, "mutant": mutant is not None, "rc": proc.returncode, **counts, "failed": failed,
               "seconds": time.perf_counter() - start, "tail": out[-2000:], "camdyn": imported[0],
               "work": work}
        print(f"  {verdict(row):8s} {row['seconds']:4.0f} s  {name}", flush=True)
        return row
    finally:
        if not keep and mutant is not None:
            shutil.rmtree(work, ignore_errors=True)


def verdict(row: dict) -> str:
    """KILLED / SURVIVED for a mutant, PASS / FAIL for the unmutated copy."""
    bad = row["failures"] + row["errors"]
    if row["mutant"]:
        return "killed" if bad > 0 and row["rc"] != 0 else "SURVIVED"
    return "pass" if bad == 0 and row["rc"] == 0 else "FAIL"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2, help="variants run at once (default 2)")
    parser.add_argument("--only", nargs="*", default=None, help="run only mutants whose name contains one of these")
    parser.add_argument("--keep", action="store_true", help="keep the temporary copies")
    args = parser.parse_args(argv)
    mutants = [m for m in MUTANTS if not args.only or any(s in m.name for s in args.only)]
    start = time.perf_counter()
    # check every replacement before spending minutes on compilation
    for m in mutants:
        with tempfile.TemporaryDirectory() as tmp:
            make_copy(Path(tmp), m)
    variants = [None, *mutants]
    print(f"{len(variants)} variants x {len(TESTS)} test selections, {args.jobs} at a time", flush=True)
    # the mutants start from the unmutated copy's cache, so they wait for it; where the
    # checkout has no compiled cache (no test run yet) the unmutated copy compiles from
    # nothing, and the first mutant compiles beside it rather than wait
    warm = any((ROOT / "src").rglob("__pycache__/*.nbi"))
    unmutated_done = threading.Event()
    seed: list = []

    def run(index_and_mutant):
        index, mutant = index_and_mutant
        if mutant is None:
            try:
                row = run_variant(None, True)
                seed.append((row["work"] / "src", row["work"] / "numba-cache"))
                return row
            finally:
                unmutated_done.set()
        if index > 1 or warm:
            unmutated_done.wait()
        return run_variant(mutant, args.keep, seed[0] if seed else None)

    try:
        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            rows = list(pool.map(run, enumerate(variants)))
    finally:
        if seed and not args.keep:
            shutil.rmtree(seed[0][0].parent, ignore_errors=True)
    width = max(len(r["name"]) for r in rows)
    print(f"\n{'mutant':<{width}}  {'tests failed':>12}  {'time':>6}  verdict   first failures")
    for r in rows:
        failed = f"{r['failures'] + r['errors']}/{r['tests']}"
        bases = dict.fromkeys(name.split("[")[0].removeprefix("test_")[:40] for name in r["failed"])
        first = ", ".join(list(bases)[:2])
        print(f"{r['name']:<{width}}  {failed:>12}  {r['seconds']:5.0f}s  {verdict(r):8s}  {first}")
    print(f"\nimported camdyn from the copies (e.g. {rows[0]['camdyn']}); "
          f"total {time.perf_counter() - start:.0f} s, {args.jobs} job(s)")
    broken = [r for r in rows if verdict(r) in ("SURVIVED", "FAIL")]
    for r in broken:
        print(f"\n--- {r['name']}: {verdict(r)} ---\n{r['tail']}")
    return 1 if broken else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except SetupError as exc:
        print(f"mutation check set-up error: {exc}", file=sys.stderr)
        sys.exit(2)
