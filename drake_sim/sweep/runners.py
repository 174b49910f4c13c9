"""What a sweep can run: one ``Runner`` per app, and ``run_rollout``, the function a worker calls.

A rollout reaches its worker as plain data (the job: runner name, scenario file, options; the
rollout: index, seed, overrides) and its diagram is built there, because Drake systems do not
pickle. Its result comes back as a plain dict. Any exception inside a rollout (a bad value that
only the scenario's own checks catch, a simulation that diverges) becomes a row with
``status: failed`` and the reason, so that one bad rollout never ends a sweep.
"""

import dataclasses as dc
import json
import logging
import os
import socket
import time
from pathlib import Path

from drake_sim.base import config
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir


def resolve(value, path: str, where: str):
    """The value at ``path`` (a ``--set`` key: ``a.b[2]``, ``m[1][0]``) inside dataclass
    ``value``.

    Raises:
        ConfigError: naming the first part of the path that does not exist.
    """
    steps = config.parse_key_path(path, f"{where}: parameter path")
    walked = []
    for step in steps:
        if isinstance(step, int):
            here = config.format_key_path(walked)
            if not isinstance(value, list | tuple) or step >= len(value):
                raise ConfigError(f"{where}: parameter path '{path}': {here} has no item {step}")
            value = value[step]
        elif not dc.is_dataclass(value) or step not in {f.name for f in dc.fields(value)}:
            known = ", ".join(f.name for f in dc.fields(value)) if dc.is_dataclass(value) else ""
            here = config.format_key_path(walked) or "the scenario"
            hint = f" (known in {here}: {known})" if known else ""
            raise ConfigError(f"{where}: unknown parameter path '{path}'{hint}")
        else:
            value = getattr(value, step)
        walked.append(step)
    if dc.is_dataclass(value):
        raise ConfigError(f"{where}: parameter path '{path}' is a section, not a value")
    return value


def override_strings(overrides: dict) -> list[str]:
    """``--set``-style ``KEY=VALUE`` strings for ``overrides`` (path -> value), in order.

    Values are written as JSON (which YAML reads), so strings stay strings; an indexed path
    (``scene.object.position[1]``) sets that one item (``config.apply_overrides``).
    """
    return [f"{path}={json.dumps(value)}" for path, value in overrides.items()]


class RobotRunner:
    """A runner of an app made of a robot file and a scenario file (flip, Wall-E).

    Paths under ``robot.`` vary the robot file (``options.robot``, default the app's robot);
    every other path varies the scenario. Subclasses name the app's loaders and checks.
    """

    file_options = ("robot",)

    def parts(self):
        """(robot schema, load robot file, validate robot, default robot file, scenario
        schema, load scenario file, check scenario)."""
        raise NotImplementedError

    def load(self, scenario: str, options: dict, overrides: dict):
        """The robot and scenario of one rollout, overridden and checked."""
        robot_schema, load_robot, validate, default_robot, schema, load_scenario, check = (
            self.parts()
        )
        robot = load_robot(options.get("robot") or default_robot())
        loaded = load_scenario(scenario)
        on_robot = {k[len("robot.") :]: v for k, v in overrides.items() if k.startswith("robot.")}
        on_scenario = {k: v for k, v in overrides.items() if not k.startswith("robot.")}
        robot = config.apply_overrides(robot_schema, robot, override_strings(on_robot))
        validate(robot, "robot override")
        strings = override_strings(on_scenario)
        loaded = config.apply_overrides(schema, loaded, strings)
        check(loaded, "override")
        return robot, loaded

    def check_paths(self, scenario: str, options: dict, paths, where: str) -> None:
        robot, loaded = self.load(scenario, options, {})
        for path in paths:
            if path.startswith("robot."):
                resolve(robot, path[len("robot.") :], where)
            else:
                resolve(loaded, path, where)


class FlipRunner(RobotRunner):
    """The flipping robot (``drake_sim.flip_run``) for ``options.duration`` simulated seconds;
    robot ``config/ddrive.yaml``, scenario ``config/flip.yaml``."""

    name = "flip"
    options = {"duration": 6.0, "robot": None}  # s simulated; robot YAML (None: the default).

    def default_scenario(self) -> Path:
        return config_dir() / "flip.yaml"

    def parts(self):
        from diagrams.flip_scenario import FlipScenario, check_flip_scenario, load_flip_scenario
        from drake_sim.robots.ddrive import default_robot_file
        from drake_sim.robots.ddrive_params import RobotParams, load_robot_params, validate

        return (
            RobotParams,
            load_robot_params,
            validate,
            default_robot_file,
            FlipScenario,
            load_flip_scenario,
            check_flip_scenario,
        )

    def metric_keys(self) -> tuple[str, ...]:
        from drake_sim.flip_run import FlipReport

        return tuple(f.name for f in dc.fields(FlipReport))

    def run(self, scenario: str, options: dict, overrides: dict, seed: int) -> dict:
        from drake_sim.flip_run import FlipRun

        robot, flip = self.load(scenario, options, overrides)
        run = FlipRun(flip, robot, seed=seed)
        run.advance_to(float(options["duration"]))
        return run.report().to_dict()


class WalleRunner(RobotRunner):
    """Wall-E balancing and following its course (``drake_sim.walle_run``), headless; robot
    ``config/walle.yaml``, scenario ``config/walle_scenario.yaml`` (``mode``, ``course``,
    ...). ``options.duration`` (s) defaults to the app's own (a lap's worth when following). A
    simulation error ends the rollout as failed, with the error as its reason."""

    name = "walle"
    options = {"duration": None, "robot": None}

    def default_scenario(self) -> Path:
        from diagrams.walle_scenario import default_scenario_file

        return default_scenario_file()

    def parts(self):
        from diagrams.walle_scenario import (
            WalleScenario,
            check_walle_scenario,
            load_walle_scenario,
        )
        from drake_sim.robots.walle import default_robot_file
        from drake_sim.robots.walle_params import WalleParams, load_walle_params, validate

        return (
            WalleParams,
            load_walle_params,
            validate,
            default_robot_file,
            WalleScenario,
            load_walle_scenario,
            check_walle_scenario,
        )

    def metric_keys(self) -> tuple[str, ...]:
        from drake_sim.walle_run import WalleReport

        return tuple(f.name for f in dc.fields(WalleReport))

    def run(self, scenario: str, options: dict, overrides: dict, seed: int) -> dict:
        from diagrams.walle_scenario import course_path
        from drake_sim.walle_run import WalleCourseRun
        from drake_sim.worlds.course import load_course

        robot, walle = self.load(scenario, options, overrides)
        run = WalleCourseRun(walle, robot, load_course(course_path(walle)), seed=seed)
        duration = options["duration"] or run.default_duration(viewer=False)
        if run.run(float(duration)) == "failed":
            raise RuntimeError(run.failure)
        return run.report().to_dict()


class PickPlaceRunner:
    """The Panda's pick-and-place task (``planning.task.PickPlaceTask``), headless.

    Paths are keys of ``PickPlaceScenario`` (``mode``, ``scene.object.position[0]``,
    ``task.lift_height``, ...). The rollout's seed is the planner's seed unless the sweep varies
    ``planner.seed`` itself.
    """

    name = "pickplace"
    options = {}
    file_options = ()
    # ``scene: {random: N}``: scene k is ``random_scene`` drawn from ``default_rng(k)`` on the
    # scenario's table (the same scene k in every sweep).
    generated = ("scene",)

    def default_scenario(self) -> Path:
        return config_dir() / "pickplace_scenario.yaml"

    def metric_keys(self) -> tuple[str, ...]:
        from planning.task.pick_place import TaskReport

        return ("mode", *TaskReport().to_dict())

    def load(self, scenario: str, overrides: dict, seed: int | None = None):
        import numpy as np

        from diagrams.pickplace_scenario import check_scenario, load_pickplace_scenario
        from planning.task.scene_generator import random_scene

        overrides = dict(overrides)
        scene_number = overrides.pop("scene", None)
        strings = override_strings(overrides)
        if seed is not None and "planner.seed" not in overrides:
            strings.append(f"planner.seed={seed}")
        loaded = load_pickplace_scenario(scenario, overrides=strings)
        if scene_number is not None:
            scene = random_scene(np.random.default_rng(int(scene_number)), loaded.scene)
            loaded = dc.replace(loaded, scene=scene)
            check_scenario(loaded, f"random scene {scene_number}")
        return loaded

    def check_paths(self, scenario: str, options: dict, paths, where: str) -> None:
        base = self.load(scenario, {})
        for path in paths:
            resolve(base, path, where)

    def run(self, scenario: str, options: dict, overrides: dict, seed: int) -> dict:
        from diagrams.planning_station import make_planning_station
        from planning.task.pick_place import PickPlaceTask

        loaded = self.load(scenario, overrides, seed)
        mpi = make_planning_station(loaded)
        return {"mode": loaded.mode, **PickPlaceTask(mpi, loaded.task).run().to_dict()}


class NavigationRunner(RobotRunner):
    """The lidar robot localising with AMCL and driving to goals (``drake_sim.navigation_run``),
    headless; robot ``config/turtlebot3.yaml``, scenario ``config/navigation_scenario.yaml``
    (``arena``, ``amcl.*``, ``navigator.*``, ...).

    Options: ``goals``, random goals drawn in the arena with the rollout's seed (a different
    set per seed); ``map``, a map_server YAML (default: the arena's ground truth at the
    lidar's height, what a perfect mapping run saves); ``global_localization``, start AMCL
    with particles over the whole map. The report's per-goal list is summed up in
    ``goals_reached``, ``max_position_error_m`` and ``max_yaw_error_deg``.
    """

    name = "navigation"
    options = {"goals": 3, "map": None, "global_localization": False, "robot": None}
    file_options = ("robot", "map")
    summary_keys = ("goals_reached", "max_position_error_m", "max_yaw_error_deg")

    def default_scenario(self) -> Path:
        from diagrams.navigation_scenario import default_scenario_file

        return default_scenario_file()

    def parts(self):
        from diagrams.navigation_scenario import (
            NavigationScenario,
            check_navigation_scenario,
            load_navigation_scenario,
        )
        from drake_sim.robots.turtlebot3 import default_turtlebot3_file
        from drake_sim.robots.turtlebot3_params import (
            Turtlebot3Params,
            load_turtlebot3_params,
            validate,
        )

        return (
            Turtlebot3Params,
            load_turtlebot3_params,
            validate,
            default_turtlebot3_file,
            NavigationScenario,
            load_navigation_scenario,
            check_navigation_scenario,
        )

    def metric_keys(self) -> tuple[str, ...]:
        from drake_sim.navigation_run import NavigationReport

        fields = tuple(f.name for f in dc.fields(NavigationReport) if f.name != "goals")
        return (*fields, *self.summary_keys)

    def run(self, scenario: str, options: dict, overrides: dict, seed: int) -> dict:
        from diagrams.mapping_scenario import config_path
        from diagrams.navigation_scenario import world_arena
        from drake_sim.base.map_files import load_map
        from drake_sim.navigation_run import NavigationRun
        from drake_sim.worlds.arena import arena_grid, load_arena
        from drake_sim.worlds.route import random_goals

        robot, navigation = self.load(scenario, options, overrides)
        arena = load_arena(config_path(navigation.arena))
        if options["map"]:
            occupancy_map = load_map(options["map"])
        else:
            occupancy_map = arena_grid(arena, 0.05, height=robot.scan_height)
        run = NavigationRun(
            navigation,
            robot,
            world_arena(navigation, arena),
            occupancy_map,
            start=arena.start_pose(),
            goals=random_goals(arena, int(options["goals"]), seed),
            global_localization=bool(options["global_localization"]),
            seed=seed,
        )
        if run.run(run.default_duration()) == "failed":
            raise RuntimeError(run.failure)
        report = run.report().to_dict()
        goals = report.pop("goals")
        reached = [g for g in goals if g["reached"]]
        worst = {
            key: max((g[key] for g in reached), default=None)
            for key in ("position_error_m", "yaw_error_deg")
        }
        return {
            **report,
            "goals_reached": len(reached),
            "max_position_error_m": worst["position_error_m"],
            "max_yaw_error_deg": worst["yaw_error_deg"],
        }


RUNNERS = {r.name: r for r in (FlipRunner(), PickPlaceRunner(), WalleRunner(), NavigationRunner())}


def get_runner(name: str, where: str = "sweep"):
    """The runner called ``name``.

    Raises:
        ConfigError: for an unknown name, listing the known ones.
    """
    if name not in RUNNERS:
        raise ConfigError(f"{where}: unknown runner {name!r} (known: {', '.join(RUNNERS)})")
    return RUNNERS[name]


def make_job(spec) -> dict:
    """The plain-data job of a ``SweepSpec``, checked before anything runs: the runner exists,
    its options are known, each parameter path names a value of its scenario, and each metric
    and success key is one of its report's.

    Raises:
        ConfigError: naming the sweep file and what is wrong.
    """
    where = spec.source
    runner = get_runner(spec.runner, where)
    options = dict(runner.options)
    for key, value in spec.options.items():
        if key not in runner.options:
            known = ", ".join(runner.options) or "none"
            raise ConfigError(f"{where}: unknown option '{key}' for {runner.name} (known: {known})")
        if key in runner.file_options and value is not None:
            path = Path(str(value))
            value = str(path if path.is_absolute() else (Path(where).parent / path).resolve())
        options[key] = value
    scenario = spec.scenario or str(runner.default_scenario())
    generated = getattr(runner, "generated", ())
    for p in spec.parameters:
        if p.kind == "random" and p.path not in generated:
            names = ", ".join(generated) or "nothing"
            raise ConfigError(
                f"{where}: parameter '{p.path}': random draws values the runner generates, "
                f"and {runner.name} generates {names}"
            )
    if any(p.kind == "random" for p in spec.parameters):
        clash = [
            p.path
            for p in spec.parameters
            if p.kind != "random"
            and p.path.split(".")[0] in {q.path for q in spec.parameters if q.kind == "random"}
        ]
        if clash:
            raise ConfigError(
                f"{where}: parameter '{clash[0]}' is inside a generated value (random)"
            )
    plain = [p.path for p in spec.parameters if p.kind != "random"]
    runner.check_paths(scenario, options, plain, where)
    known = runner.metric_keys()
    for key in (*spec.metrics, *(c.key for c in spec.success)):
        if key not in known:
            raise ConfigError(
                f"{where}: '{key}' is not a {runner.name} report key (known: {', '.join(known)})"
            )
    return {"runner": runner.name, "scenario": scenario, "options": options}


def worker_id() -> str:
    """Which worker ran a rollout: host and process id."""
    return f"{socket.gethostname()}:{os.getpid()}"


def run_rollout(job: dict, rollout: dict) -> dict:
    """Builds and runs one rollout; the function every backend sends to its workers.

    Returns:
        A row: ``index``, ``seed``, ``overrides``, ``status`` ("ok" or "failed"), ``reason``,
        ``report`` (the runner's report dict, empty if it failed), ``wall_time_s``, ``worker``.
    """
    logging.getLogger("drake").setLevel(logging.WARNING)  # stderr is for errors only
    start = time.perf_counter()
    report, status, reason = {}, "ok", ""
    try:
        runner = get_runner(job["runner"])
        report = runner.run(job["scenario"], job["options"], rollout["overrides"], rollout["seed"])
    except Exception as e:  # noqa: BLE001 (any failure of one rollout is that rollout's row)
        lines = str(e).strip().splitlines()
        status, reason = "failed", f"{type(e).__name__}: {lines[0] if lines else ''}".strip()
    return {
        "index": rollout["index"],
        "seed": rollout["seed"],
        "overrides": rollout["overrides"],
        "status": status,
        "reason": reason,
        "report": report,
        "wall_time_s": time.perf_counter() - start,
        "worker": worker_id(),
    }
