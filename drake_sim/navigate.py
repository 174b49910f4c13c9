"""``python -m drake_sim.navigate``: the lidar robot localises on a saved map and drives to goals.

AMCL localises the robot on ``--map`` (map_server's ``.yaml``) from a first guess
(``--initial-pose``, default the true start) or from nothing (``--global-localization``), and
the navigator (a global costmap from the map and the live scans, A* on it, a DWA local planner
on a rolling local costmap, recoveries) drives it to each goal in turn: ``--goal X Y YAW`` or
``--goals FILE`` (``goals: [{x, y, yaw}]``, metres and degrees). Without either, with a viewer,
goals and pose estimates are given in the Meshcat page (sliders and buttons standing in for
RViz's "2D Nav Goal" and "2D Pose Estimate") until Ctrl-C; headless, the arena's goals file in
``config/goals/`` is driven. The robot really drives in ``--arena`` (default the scenario's),
which may hold obstacles the map does not (``extra_obstacles`` in the scenario). Exit codes: 0
when every goal was reached, 1 when one was not (one line says which and why), 2 for bad input.
"""

import sys

from drake_sim.base import cli
from drake_sim.runs import command
from drake_sim.runs.navigate import RECIPE


def main(argv=None) -> int:
    return command.main(RECIPE, __doc__, argv)


if __name__ == "__main__":
    sys.exit(cli.run(main))
