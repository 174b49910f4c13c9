"""Entry point of ``python -m drake_sim.sweep``: the command (``drake_sim.sweep.command``) under
the project's exit-code contract (``drake_sim.base.cli.run``)."""

import sys

from drake_sim.base import cli
from drake_sim.sweep.command import main

if __name__ == "__main__":
    sys.exit(cli.run(main))
