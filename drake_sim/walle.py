"""``python -m drake_sim.walle``: Wall-E balances, follows a line, or both, on a course.

With a viewer (the default) it runs in real time in Meshcat until the run ends (one lap, the
open course's end, a fall, the line lost for good, ``--duration``) or Ctrl-C; ``--headless``
runs flat out. ``--mode balance`` holds position on the course's start (``--teleop``: drive
with the W/A/S/D keys and Space in the Meshcat page); ``follow`` is the statically stable
variant on casters; ``both`` balances while following the line. ``--report`` writes the JSON
report (DESIGN.md, Wall-E course). Exit codes: 0 for a completed run, 1 if the robot fell or
lost the line for good (or the simulation failed), 2 for bad input.
"""

import sys

from drake_sim.base import cli
from drake_sim.runs import command
from drake_sim.runs.walle import RECIPE


def main(argv=None) -> int:
    return command.main(RECIPE, __doc__, argv)


if __name__ == "__main__":
    sys.exit(cli.run(main))
