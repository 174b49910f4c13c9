"""``python -m drake_sim.flip``: the robot shuttles along a line by flipping over its axle.

With a viewer (the default) it runs in real time in Meshcat, drawing the robot, its odometry
trail and its true trail, until Ctrl-C (or SIGTERM) or ``--duration``; a stop still prints the
summary and writes the report. ``--headless`` runs flat out for 20 s (or ``--duration``).
``--teleop`` turns the flip controller off: drive with the W/A/S/D keys and Space to stop, in
the Meshcat page. ``--report`` writes the JSON report (docs/flip.md, The report).
Exit codes: 0 for a completed run, 1 if the simulation failed, 2 for bad input.
"""

import sys

from drake_sim.base import cli
from drake_sim.runs import command
from drake_sim.runs.flip import RECIPE


def main(argv=None) -> int:
    return command.main(RECIPE, __doc__, argv)


if __name__ == "__main__":
    sys.exit(cli.run(main))
