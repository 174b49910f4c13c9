import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

import diagrams.lidar_robot as mut
from diagrams.mapping_scenario import MappingScenario
from drake_sim.worlds.arena import load_arena
from tests import navigation_helpers as nh


def test_the_robot_drives_on_cmd_vel_and_reports_truth_odometry_and_scans():
    arena = load_arena(nh.arena_file("room"))
    scenario = MappingScenario()
    start = np.array(arena.start_pose())
    builder = DiagramBuilder()
    scenario.random_seed = 1
    dut = mut.add_lidar_robot(builder, scenario, robot=nh.robot(), world=arena, start=start)
    command = builder.AddSystem(ConstantVectorSource(np.array([0.2, 0.0])))
    builder.Connect(command.get_output_port(), dut.cmd_vel)
    for name, port in (
        ("truth", dut.true_pose),
        ("odometry", dut.odometry_pose),
        ("scan", dut.scan),
    ):
        builder.ExportOutput(port, name)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(2.01)
    context = simulator.get_context()
    truth = diagram.GetOutputPort("truth").Eval(context)
    assert truth[0] - start[0] == pytest.approx(0.35, abs=0.06)  # 0.2 m/s after the ramp
    assert diagram.GetOutputPort("odometry").Eval(context)[:2] == pytest.approx(truth[:2], abs=0.02)
    scan = diagram.GetOutputPort("scan").Eval(context)
    assert scan.time == pytest.approx(2.0) and len(scan.ranges) == 360
    assert dut.X_base_sensor == (nh.robot().lidar.x, nh.robot().lidar.y, 0.0)
    assert dut.plant.GetModelInstanceByName(mut.ROBOT_NAME)
