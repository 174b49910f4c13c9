"""``python -m drake_sim.explore``: the lidar robot maps an unknown place by itself, driving
from frontier to frontier (explore_lite's method on the live SLAM and the navigator).

The robot starts at the arena's start (``--arena``; or ``--world MAP.yaml --start X Y YAW``, a
map_server map's world) knowing nothing, maps with the live SLAM, picks the frontiers (known
free cells beside unknown ones) by the path's length less the frontier's size, drives to them
with the costmaps and planners of ``navigate``, and stops when no reachable frontier is left
or at ``--time-limit`` (600 simulated s). The map is saved as map_server files (``--out``).
With a viewer, Meshcat shows the robot, the costmap, the frontiers and the chosen goal. Exit
codes: 0 when the place was explored (or Ctrl-C), 1 when it was not, 2 for bad input.
"""

import sys

from drake_sim.base import cli
from drake_sim.runs import command
from drake_sim.runs.explore import RECIPE


def main(argv=None) -> int:
    return command.main(RECIPE, __doc__, argv)


if __name__ == "__main__":
    sys.exit(cli.run(main))
