"""``camdyn continue PRESET --method harmonic-balance``: the cam-follower's frequency
response by harmonic balance, with the JSON, Dataset and figure of the shooting branches
(:mod:`camdyn.cli.continuation`)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from camdyn.cli.common import console
from camdyn.cli.outputs import announce, emit_json
from camdyn.errors import ParameterError, SimulationError

#: The methods of ``camdyn continue``.
METHODS = ("shooting", "harmonic-balance")

DoublingsOption = typer.Option(None, "--doublings",
                               help="Period doublings followed: at each one located, switch onto the period-2k "
                                    "branch and continue it (0: none, 2: their doublings too; default 1).")
MethodOption = typer.Option("shooting", "--method",
                            help="shooting, or harmonic-balance (the rocking cam-follower's period-1 orbits in "
                                 "sustained contact: a frequency response that ends where contact is lost).")
HarmonicsOption = typer.Option(None, "--harmonics",
                               help="Harmonic balance: H, or auto (the default: doubled where the top harmonics "
                                    "exceed 1e-8 of the largest). Shooting: cam harmonics per channel reported "
                                    "(default 8).")


def method_settings(method: str, harmonics: str | None, source: str, period: int, segments: int,
                    doublings: int | None) -> tuple[int | str, int]:
    """``(harmonics, doublings)`` of ``camdyn continue``'s ``--method`` (default 1 doubling
    followed), after :func:`harmonics_option` and, for harmonic balance,
    :func:`refuse_harmonic_balance`."""
    count = harmonics_option(harmonics, method)
    if method == "harmonic-balance":
        refuse_harmonic_balance(source, period, segments, doublings is not None)
    return count, 1 if doublings is None else doublings


def harmonics_option(text: str | None, method: str) -> int | str:
    """``--harmonics``: H (a positive integer) or ``auto`` for harmonic balance (default
    auto); the cam harmonics per channel reported by shooting (default 8)."""
    if method not in METHODS:
        raise ParameterError(f"--method must be one of {', '.join(METHODS)}, got {method!r:.60}")
    if text is None:
        return "auto" if method == "harmonic-balance" else 8
    if text == "auto" and method == "harmonic-balance":
        return "auto"
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 256:
        raise ParameterError(f"--harmonics must be a whole number from 1 to 256{' or auto' * (method != 'shooting')}, "
                             f"got {text!r:.60}")
    return value


def refuse_harmonic_balance(source: str, period: int, segments: int, doublings_given: bool) -> None:
    """Refuse, in one line, what harmonic balance cannot do: another family than the
    rocking cam-follower, a period-k orbit, multiple shooting, switching at doublings."""
    from camdyn.params.mechanism import is_mechanism
    from camdyn.params.profiles import is_translating
    from camdyn.systems.model_files import is_model_reference

    if is_translating(source) or is_mechanism(source) or is_model_reference(source):
        raise ParameterError("--method harmonic-balance takes the rocking cam-follower (a preset such as "
                             "sundar2014-friction, or its TOML); continue this one by shooting (leave out --method)")
    if period != 1 or segments != 1 or doublings_given:
        raise ParameterError("--method harmonic-balance follows period-1 orbits in sustained contact: leave out "
                             "--period, --segments and --doublings (shooting's)")


def continue_harmonic_command(system, parameter: str, unit: str, first: float, last: float, harmonics, step: float,
                              max_points: int, plot: Path | None, out: Path | None, diagram, bar, json_: bool) -> None:
    """Trace the frequency response and report it as ``camdyn continue`` reports branches
    (its JSON carries ``method`` and the highest ``harmonics`` used, and a gap from a
    contact loss to the range's end). ``diagram`` is a callable giving the brute-force
    diagram or None."""
    from camdyn.continuation.results import bifurcation_records, branches_dataset
    from camdyn.steady.tables import METHOD, harmonic_records, trace_harmonic

    with bar:
        bar.phase("the first orbit by harmonic balance, then its continuation")
        try:
            problem, curve = trace_harmonic(system, parameter, first, last, harmonics, step=step,
                                            max_points=max_points, progress=bar.orbit)
        except SimulationError as error:                   # only the first orbit raises: the range is wrong
            raise ParameterError(f"--method harmonic-balance found no orbit in sustained contact at --from "
                                 f"{first:.6g} {unit} ({str(error).rstrip('.')}); start where the follower keeps "
                                 "contact, or continue by shooting (leave out --method)") from error
    records = [harmonic_records(problem, curve)]
    bifurcations = bifurcation_records([curve.branch])
    reached = curve.parameters[-1]
    gaps = [] if math.isclose(reached, last, rel_tol=1e-9) or "points computed" in curve.branch.stopped else \
        [{"start": min(reached, last), "stop": max(reached, last), "reason": curve.branch.stopped}]
    files = []
    if out is not None:
        from camdyn.io.netcdf import save_netcdf
        files.append(announce(save_netcdf(branches_dataset(problem, records, bifurcations, METHOD), out), json_))
    if plot is not None:
        from camdyn.plotting.branches import plot_branches
        files.append(announce(plot_branches(branches_dataset(problem, records, bifurcations, METHOD), plot,
                                            diagram()), json_))
    orbits = curve.branch.orbits
    if json_:
        summary = {"parameter": parameter, "units": unit, "method": "harmonic-balance",
                   "harmonics": max(h.harmonics for h in curve.harmonic_orbits),
                   "tail": max(h.tail for h in curve.harmonic_orbits), "points": len(orbits),
                   "stable_points": sum(o.stable for o in orbits), "stopped": curve.branch.stopped,
                   "branch_count": 1, "covering_branch_count": 1, "gap_count": len(gaps),
                   "bifurcation_count": len(bifurcations)}
        emit_json("continue", summary, branches=records, bifurcations=bifurcations, gaps=gaps, files=files)
        return
    console.print(f"frequency response by harmonic balance: {len(orbits)} orbits over {parameter} = "
                  f"{min(curve.parameters):.6g} to {max(curve.parameters):.6g} {unit}, "
                  f"{sum(o.stable for o in orbits)} stable (Hill), H up to "
                  f"{max(h.harmonics for h in curve.harmonic_orbits)}; {curve.branch.stopped}",
                  highlight=False, soft_wrap=True)
    for item in bifurcations:
        console.print(f"  {item['kind']} at {parameter} = {item['parameter']:.9g} {unit}", highlight=False,
                      soft_wrap=True)
    for gap in gaps:
        console.print(f"gap from {parameter} = {gap['start']:.6g} to {gap['stop']:.6g} {unit}: {gap['reason']}",
                      highlight=False, soft_wrap=True)
