"""Wall-E's measured motion and a headless balance run: ``walle_track`` reads the ground truth
that a Wall-E diagram logged (``diagrams.walle_balance``'s ``log_state``) as the axle's path,
heading and lean; ``run_walle`` builds the flat-floor diagram, simulates it flat out and
measures what the robot did (the balance tests and ``benchmarks/walle_balance_benchmark.py``).
"""

import dataclasses as dc
import math
import time

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Diagram

from diagrams.walle_balance import ROBOT_NAME, make_walle_diagram
from diagrams.walle_balance_scenario import WalleBalanceScenario
from drake_sim.robots.walle import BODY_LINK
from drake_sim.robots.walle_params import WalleParams
from drake_sim.systems.axle import axle_yaw_and_pitch
from drake_sim.systems.sensors.imu import rotation_from_quaternion


@dc.dataclass
class WalleTrack:
    """The robot's true motion, sampled every log period: one entry per sample."""

    t: np.ndarray  # s.
    p_WA: np.ndarray  # 2 x N, the axle's midpoint on the floor, m.
    yaw: np.ndarray  # rad, heading of the axle frame, unwrapped.
    pitch: np.ndarray  # rad, lean about the axle, positive forward.


def walle_track(diagram: Diagram, context, robot: WalleParams) -> WalleTrack:
    """Reads the logged ground truth of a diagram from ``make_walle_diagram``."""
    plant = diagram.GetSubsystemByName("plant")
    instance = plant.GetModelInstanceByName(ROBOT_NAME)
    body = plant.GetBodyByName(BODY_LINK, instance)
    log = diagram.GetSubsystemByName("log_state").FindLog(context)
    state = log.data()
    # Where the body's quaternion and position sit in the instance's state.
    indices = plant.GetPositionsFromArray(instance, np.arange(plant.num_positions()))
    start = list(indices).index(body.floating_positions_start())
    p_BA = np.array([0.0, 0.0, robot.axle_z])
    points, yaws, pitches = [], [], []
    for column in state.T:
        R_WB = rotation_from_quaternion(column[start : start + 4])
        points.append(column[start + 4 : start + 6] + (R_WB @ p_BA)[:2])
        yaw, pitch = axle_yaw_and_pitch(R_WB)
        yaws.append(yaw)
        pitches.append(pitch)
    return WalleTrack(log.sample_times(), np.array(points).T, np.unwrap(yaws), np.array(pitches))


@dc.dataclass
class WalleRun:
    """What a headless run did, measured on the ground truth after ``settle_time``."""

    fell: bool  # The lean passed the controller's fallen pitch.
    max_abs_pitch_deg: float  # After settle_time.
    max_drift_m: float  # Largest distance of the axle from where it started, after settle_time.
    track: WalleTrack
    sim_time_s: float
    wall_time_s: float
    real_time_factor: float


def run_walle(
    scenario: WalleBalanceScenario,
    robot: WalleParams,
    duration: float,
    *,
    cmd_vel=(0.0, 0.0),
    settle_time: float = 1.0,
    seed: int | None = None,
) -> WalleRun:
    """Builds the diagram, simulates ``duration`` s headless (flat out) with ``cmd_vel``
    fixed, and measures the run. ``seed`` (default ``scenario.random_seed``) seeds the IMU."""
    diagram = make_walle_diagram(scenario, robot)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.random_seed if seed is None else seed)
    )
    if diagram.HasInputPort("cmd_vel"):
        diagram.GetInputPort("cmd_vel").FixValue(context, np.asarray(cmd_vel, float))
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    wall = time.perf_counter() - start
    track = walle_track(diagram, context, robot)
    after = track.t >= settle_time
    fallen = math.radians(scenario.balance.fallen_pitch)
    drift = np.linalg.norm(track.p_WA - track.p_WA[:, :1], axis=0)
    return WalleRun(
        fell=bool(np.any(np.abs(track.pitch) > fallen)),
        max_abs_pitch_deg=float(np.degrees(np.max(np.abs(track.pitch[after]), initial=0.0))),
        max_drift_m=float(np.max(drift[after], initial=0.0)),
        track=track,
        sim_time_s=duration,
        wall_time_s=wall,
        real_time_factor=duration / wall if wall > 0 else math.inf,
    )
