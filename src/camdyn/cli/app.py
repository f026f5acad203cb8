"""The ``camdyn`` command line: the one place where every command is registered.

Every input error prints one line, ``error: ...``, on standard error and exits with
status 2 (no traceback).
"""

from __future__ import annotations

import sys

import typer

from camdyn.cli import analysis, impact, records, simulate, sweep
from camdyn.errors import CamdynError

try:  # recent typer vendors click
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover
    from click import exceptions as click_exceptions

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Nonlinear dynamics of cam-follower systems with rolling-sliding contact.")
presets_app = typer.Typer(help="List and show bundled parameter presets.", invoke_without_command=True)
identify_app = typer.Typer(help="Estimate model parameters from measured records.", no_args_is_help=True)

presets_app.callback()(simulate.presets_list)
presets_app.command("show")(simulate.presets_show)
presets_app.command("keys")(simulate.presets_keys)
app.add_typer(presets_app, name="presets")
app.command("equilibrium")(simulate.equilibrium)
app.command("simulate")(simulate.simulate)
app.command("demo")(simulate.demo)
app.command("synthesize")(records.synthesize)
app.command("synthesize-impulse")(records.synthesize_impulse)
identify_app.command("friction")(records.identify_friction)
identify_app.command("modal-damping")(records.identify_modal)
identify_app.command("impact-damping")(impact.identify_impact_damping)
identify_app.command("restitution")(impact.identify_restitution)
app.add_typer(identify_app, name="identify")
app.command("tribology")(records.tribology)
app.command("design")(records.design)
app.command("sweep")(sweep.sweep)
app.command("bifurcation")(sweep.bifurcation)
app.command("lyapunov")(sweep.lyapunov)
app.command("map")(analysis.regime_map_command)
app.command("spectrum")(analysis.spectrum)


def main(argv=None) -> int:
    """Entry point: run the app, turning input errors into one line and exit status 2."""
    try:
        app(args=argv, standalone_mode=False, prog_name="camdyn")
    except CamdynError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except click_exceptions.UsageError as exc:
        print(f"error: {exc.format_message()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("aborted", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())


def run() -> None:  # console-script entry point
    sys.exit(main())
