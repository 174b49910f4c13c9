"""Shared set-up for the flipping-robot tests: scenarios on bare ground, short runs."""

import dataclasses as dc

from diagrams.flip_scenario import FlipScenario, load_flip_scenario
from drake_sim.base.resources import config_dir
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import RobotParams, load_robot_params
from drake_sim.runs.flip import FlipRun


def default_robot() -> RobotParams:
    return load_robot_params(default_robot_file())


def flip_scenario(*, world: bool = False, upside_down: bool = False) -> FlipScenario:
    """``config/flip.yaml``, on bare ground unless ``world`` (the street is slower to run)."""
    scenario = load_flip_scenario(config_dir() / "flip.yaml")
    scene = scenario.scene
    pose = dc.replace(scene.robot_pose, upside_down=upside_down)
    scene = dc.replace(scene, robot_pose=pose, world=scene.world if world else "")
    return dc.replace(scenario, scene=scene)


def seeded(scenario: FlipScenario, seed: int) -> FlipScenario:
    """``scenario`` with its seed (``scene.random_seed``: the IMU noise) set to ``seed``."""
    return dc.replace(scenario, scene=dc.replace(scenario.scene, random_seed=seed))


def run_for(seconds: float, *, robot=None, scenario=None, controller="flip", cmd_vel=None):
    """Simulates ``seconds`` headless with seed 1 and returns the ``FlipRun``; a simulation
    error fails the caller's test."""
    scenario = seeded(scenario or flip_scenario(), 1)
    run = FlipRun(scenario, robot or default_robot(), controller=controller)
    if cmd_vel is not None:
        run.diagram.GetInputPort("cmd_vel").FixValue(run.context, cmd_vel)
    assert run.run(seconds) == "duration", run.failure
    return run
