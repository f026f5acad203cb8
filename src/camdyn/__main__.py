"""``python -m camdyn``: the command line (the same as the ``camdyn`` script)."""

from camdyn.cli import run

if __name__ == "__main__":
    run()
