"""``python -m drake_sim.mapping``: the lidar robot maps an arena with scan-matching SLAM and saves
the map as map_server files.

It drives a route (``--route FILE``, else the arena's default route in ``config/routes/``) or,
with ``--teleop``, the W/A/S/D keys in the Meshcat page, while the SLAM builds the map from the
lidar's scans and the wheel odometry. Meshcat shows the robot (the truth), the scan, the map as
it grows and the SLAM pose's trail against the true one. At the end the map is written as
``--out``'s ``.pgm`` and ``.yaml`` (map_saver's format) and scored against the arena; a run that
ends before its route does (Ctrl-C, SIGTERM, ``--duration``, a failure) keeps any map already at
``--out`` and writes ``NAME.partial.pgm`` / ``.yaml`` beside it instead. Exit
codes: 0 for a completed run, 1 if the route was not completed (or the simulation failed),
2 for bad input.

With ``--log FILE`` (a ROS 1 or ROS 2 bag, or a CARMEN log) it maps a recorded log instead,
offline, with the same SLAM: ``--out``, ``--trajectory`` (TUM) and ``--report`` are written at
the end (``drake_sim.runs.log_mapping``).
"""

import sys

from drake_sim.base import cli
from drake_sim.runs import command, log_mapping
from drake_sim.runs.mapping import RECIPE


def main(argv=None) -> int:
    parser = command.parser(RECIPE, __doc__)
    log_mapping.add_flags(parser)
    args = parser.parse_args(argv)
    log_mapping.check_flags(args)
    if args.log is not None:
        return log_mapping.run(RECIPE, args)
    return command.run_app(RECIPE, args)


if __name__ == "__main__":
    sys.exit(cli.run(main))
