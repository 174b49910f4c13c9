"""``python -m drake_sim.view``: look at the diff-drive robot in Meshcat (the RViz launch file).

Without options, the robot stands in the street world with its link frames drawn, simulated in
real time until Ctrl-C, with the odometry display (the odometry's arrow and trail in blue, the
true trail in green) and keyboard teleop: W/S faster forward/backward, A/D turn, Space stop.
``--view-only`` shows the robot alone with a slider per wheel joint, like
joint_state_publisher_gui, until Ctrl-C or its Stop button. Both stop on Ctrl-C or SIGTERM (or
after ``--duration``) with a one-line summary and exit code 0.
"""

import sys
import time

import numpy as np
from pydrake.geometry import StartMeshcat

from diagrams.ddrive_model import make_ddrive_model_diagram
from drake_sim.base import cli
from drake_sim.base.resources import config_dir
from drake_sim.runs.command import add_file_options
from drake_sim.runs.flip import RECIPE, FlipRun

STOP_BUTTON = "Stop"
"""The ``--view-only`` page's button that ends the run, like Ctrl-C."""
DRIVE_HELP = "drive: click the Meshcat page, then W/S faster forward/backward, A/D turn, Space stop"
SLIDER_POLL_PERIOD = 0.02  # s of wall time between reads of the sliders.


def _parse_args(argv):
    parser = cli.ArgumentParser(prog="python -m drake_sim.view", description=__doc__.split("\n")[0])
    add_file_options(parser, RECIPE, default_scenario=config_dir() / "view.yaml")
    parser.add_argument(
        "--view-only", action="store_true", help="the robot alone, with joint sliders"
    )
    parser.add_argument(
        "--duration",
        type=cli.positive_float,
        default=None,
        help="seconds to run (simulated, or wall time with --view-only); default: until Ctrl-C",
    )
    parser.add_argument(
        "--record", type=cli.output_file("replay"), help="write a self-contained HTML replay"
    )
    return parser.parse_args(argv)


def pose_with_sliders(diagram, meshcat, duration: float | None = None) -> tuple[np.ndarray, float]:
    """Poses the robot from its joint sliders until ``duration`` s of wall time pass (forever
    when None) or the page's ``STOP_BUTTON`` is pressed; Ctrl-C (``KeyboardInterrupt``) ends it
    too, between two reads. It says so on stdout (``cli.announce``) as it starts.

    ``JointSliders.Run`` does the same but waits in C++, where Ctrl-C cannot reach it.

    Args:
        diagram: a ``make_ddrive_model_diagram(..., joint_sliders=True)`` diagram.
        meshcat: the Meshcat of its sliders.
        duration: wall-time limit, s.

    Returns:
        The last joint positions (rad) and the wall time spent (s).
    """
    sliders = diagram.GetSubsystemByName("joint_sliders")
    plant = diagram.GetSubsystemByName("plant")
    context = diagram.CreateDefaultContext()
    diagram.ExecuteInitializationEvents(context)
    sliders_context = sliders.GetMyMutableContextFromRoot(context)
    plant_context = plant.GetMyMutableContextFromRoot(context)
    # Newer Drakes keep the slider values as discrete state, updated by a periodic event.
    stateful = sliders_context.num_discrete_state_groups() > 0
    start = time.monotonic()
    meshcat.AddButton(STOP_BUTTON)
    try:
        cli.announce(meshcat, f"posing the wheels with the sliders (or press {STOP_BUTTON!r})")
        q = None
        while duration is None or time.monotonic() - start < duration:
            if meshcat.GetButtonClicks(STOP_BUTTON) > 0:
                break
            if stateful:
                update = sliders.EvalUniquePeriodicDiscreteUpdate(sliders_context)
                sliders_context.SetDiscreteState(update)
            new_q = sliders.get_output_port().Eval(sliders_context)
            if q is None or not np.array_equal(new_q, q):
                q = np.array(new_q)
                plant.SetPositions(plant_context, q)
                diagram.ForcedPublish(context)
            time.sleep(SLIDER_POLL_PERIOD)
    except BaseException as e:
        if not cli.is_stop(e):
            raise
    finally:
        meshcat.DeleteButton(STOP_BUTTON)
    return plant.GetPositions(plant_context), time.monotonic() - start


def _view_only(args, robot) -> int:
    meshcat = StartMeshcat()
    diagram = make_ddrive_model_diagram(robot, meshcat=meshcat, joint_sliders=True)
    meshcat.SetCameraPose([1.0, -1.2, 0.6], [0.0, 0.0, robot.wheel.radius])
    q, elapsed = pose_with_sliders(diagram, meshcat, args.duration)
    if args.record:
        cli.write_replay(meshcat, args.record, recording=False)
    joints = ", ".join(f"{v:.2f}" for v in q)
    print(f"viewed for {elapsed:.1f} s wall time; wheel joints at [{joints}] rad")
    return cli.EXIT_OK


def main(argv=None) -> int:
    args = _parse_args(argv)
    inputs = RECIPE.load(scenario=args.scenario, robot=args.robot)
    if args.view_only:
        return _view_only(args, inputs.robot)

    meshcat = StartMeshcat()
    run = FlipRun(inputs.scenario, inputs.robot, meshcat=meshcat, controller="teleop")
    pose = inputs.scenario.scene.robot_pose
    meshcat.SetCameraPose([pose.x - 2.5, pose.y - 2.5, 1.5], [pose.x + 0.5, pose.y, 0.2])
    meshcat.SetProperty("/Grid", "visible", False)  # The street is the floor.
    try:
        if args.record:
            meshcat.StartRecording()
        print(DRIVE_HELP)
        cli.announce(meshcat, "running")
        run.run(args.duration if args.duration is not None else np.inf)  # until a stop
    except BaseException as e:  # a stop before the run's own loop caught it
        if not cli.is_stop(e):
            raise
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    print(f"simulated {run.context.get_time():.2f} s in {run.wall_time:.2f} s wall time")
    error = run.error(None)
    if error:
        print(f"error: {error}", file=sys.stderr)
        return cli.EXIT_FAILED
    return cli.EXIT_OK


def console_main() -> int:
    """The ``drake-sim-view`` script: ``main`` with one-line errors, exit codes and signals."""
    return cli.run(main)


if __name__ == "__main__":
    sys.exit(console_main())
