"""``python -m drake_sim.view``: look at the diff-drive robot in Meshcat (the RViz launch file).

Without options, the robot stands in the street world with its link frames drawn, simulated in
real time until Ctrl-C, with the odometry display (the odometry's arrow and trail in blue, the
true trail in green) and keyboard teleop: W/S faster forward/backward, A/D turn, Space stop.
``--view-only`` shows the robot alone with a slider per wheel joint, like
joint_state_publisher_gui.
"""

import sys
from pathlib import Path

import numpy as np
from pydrake.geometry import StartMeshcat

from diagrams.ddrive_model import make_ddrive_model_diagram
from diagrams.flip_scenario import load_flip_scenario
from drake_sim.base import cli
from drake_sim.base.resources import config_dir
from drake_sim.flip_run import FlipRun
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import load_robot_params


def _parse_args(argv):
    parser = cli.ArgumentParser(prog="python -m drake_sim.view", description=__doc__.split("\n")[0])
    cli.add_robot_and_config_options(
        parser, default_robot=default_robot_file(), default_config=config_dir() / "view.yaml"
    )
    parser.add_argument(
        "--view-only", action="store_true", help="the robot alone, with joint sliders"
    )
    parser.add_argument(
        "--duration",
        type=cli.positive_float,
        default=None,
        help="seconds to run (simulated, or wall time with --view-only); default: until Ctrl-C",
    )
    parser.add_argument("--record", type=Path, help="write a self-contained HTML replay")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = _parse_args(argv)
    robot = load_robot_params(args.robot)
    if args.view_only:
        meshcat = StartMeshcat()
        diagram = make_ddrive_model_diagram(robot, meshcat=meshcat, joint_sliders=True)
        sliders = diagram.GetSubsystemByName("joint_sliders")
        meshcat.SetCameraPose([1.0, -1.2, 0.6], [0.0, 0.0, robot.wheel.radius])
        sliders.Run(diagram, timeout=args.duration)
        if args.record:
            cli.write_replay(meshcat, args.record, recording=False)
        return cli.EXIT_OK

    scenario = load_flip_scenario(args.config)
    meshcat = StartMeshcat()
    run = FlipRun(scenario, robot, meshcat=meshcat, controller="teleop")
    pose = scenario.scene.robot_pose
    meshcat.SetCameraPose([pose.x - 2.5, pose.y - 2.5, 1.5], [pose.x + 0.5, pose.y, 0.2])
    meshcat.SetProperty("/Grid", "visible", False)  # The street is the floor.
    print("drive: click the Meshcat page, then W/S faster forward/backward, A/D turn, Space stop")
    if args.record:
        meshcat.StartRecording()
    try:
        run.advance_to(args.duration if args.duration is not None else np.inf)
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    print(f"simulated {run.context.get_time():.2f} s in {run.wall_time:.2f} s wall time")
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
