"""``camdyn sweep SPEC.toml``: a parameter sweep, locally or on a Dask cluster."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from camdyn.cli_tools import console
from camdyn.errors import ParameterError


def sweep(spec_path: Path = typer.Argument(..., metavar="SPEC.toml", help="Sweep specification (docs/sweeps.md)."),
          workers: Optional[int] = typer.Option(None, help="Worker processes (default: every core; 0 runs inline). "
                                                           "With --dask local, the number of Dask workers."),
          dask: Optional[str] = typer.Option(None, help="'local' for a Dask LocalCluster, or a scheduler address "
                                                        "tcp://HOST:PORT."),
          threads: int = typer.Option(1, help="Numba threads per worker (prange over the points of a chunk)."),
          out: Optional[Path] = typer.Option(None, help="Result file (.nc); default [output] path of the spec."),
          restart: bool = typer.Option(False, help="Discard this output's checkpoints instead of resuming."),
          keep_parts: bool = typer.Option(False, "--keep-parts", help="Keep the per-chunk checkpoint files."),
          plot: Optional[Path] = typer.Option(None, help="Figure path (default: the result's name with .png)."),
          no_plot: bool = typer.Option(False, "--no-plot", help="Write no figure."),
          quiet: bool = typer.Option(False, help="No progress bar.")):
    """Run a parameter sweep; resume it from its checkpoints if it was interrupted."""
    import dataclasses

    from camdyn.plotting import plot_sweep
    from camdyn.sweeps import load_spec, run_sweep

    spec = load_spec(spec_path)
    if out is not None:
        if out.suffix not in (".nc", ".h5"):
            raise ParameterError(f"--out must end in .nc, got {out.name!r}")
        spec = dataclasses.replace(spec, output=out)
    ds = run_sweep(spec, workers=workers, dask=dask, threads=threads, progress=not quiet, restart=restart,
                   keep_parts=keep_parts, echo=lambda msg: console.print(msg, highlight=False, soft_wrap=True))
    failed = int((ds["status"] != 0).sum())
    console.print(f"wrote {spec.output} ({spec.points} points, {failed} failed)", highlight=False, soft_wrap=True)
    if failed:
        reasons = sorted(set(str(r) for r in ds["failure"].values.ravel() if str(r)))
        for reason in reasons[:5]:
            console.print(f"  failed: {reason}", highlight=False, soft_wrap=True)
    if not no_plot:
        figure = plot or spec.output.with_suffix(".png")
        plot_sweep(ds, figure)
        console.print(f"wrote {figure}", highlight=False, soft_wrap=True)
    ds.close()
