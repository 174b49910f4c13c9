"""``python -m drake_sim.pickplace``: the Panda (or the scenario's arm: ``--scenario
config/pickplace_ur5.yaml``) picks the object and places it beyond the obstacle.

With a viewer (the default) the station runs in real time in Meshcat: open the page, press
"Pick" (or pass ``--no-wait``), watch, and press Ctrl-C to quit. Ctrl-C or SIGTERM stop a run at
any point, with a summary line (``stopped: ...`` before the task's end; its report says
``"end": "stopped"``).
``--headless`` runs the task at once, flat out. ``--mode physics`` (default) simulates contact
and grasps the object by friction; ``--mode kinematic`` plays the planned motions back (Franka's
fake hardware). Everything else comes from one scenario (``--scenario FILE``, default
``config/pickplace_scenario.yaml``; ``diagrams.pickplace_scenario``), with ``--scene FILE`` and
``--set key=value`` on top.
Exit codes: 0 on success, 1 when the task is impossible or a step failed (one stderr line names
the step and the reason), 2 on bad input.
"""

from diagrams.pickplace_scenario import dump_pickplace_scenario
from drake_sim.base import cli
from drake_sim.runs import command
from drake_sim.runs.pickplace import RECIPE


def main(argv=None) -> int:
    parser = command.parser(RECIPE, __doc__)
    parser.add_argument(
        "--print-scenario", action="store_true", help="print the whole scenario as YAML and exit"
    )
    args = parser.parse_args(argv)
    if args.print_scenario:
        print(dump_pickplace_scenario(command.load_from_args(RECIPE, args).scenario), end="")
        return cli.EXIT_OK
    return command.run_app(RECIPE, args)


if __name__ == "__main__":
    cli.exit_at_once(cli.run(main))  # a stop does not wait for a planner thread to finish
