"""``python -m drake_sim.pickplace``: the Panda picks the object and places it beyond the obstacle.

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

import dataclasses as dc
import json
import sys
import time

from pydrake.geometry import StartMeshcat

from diagrams.panda_station import MODES, PandaStationConfig
from diagrams.pickplace_scenario import (
    PickPlaceScenario,
    dump_pickplace_scenario,
    load_pickplace_scenario,
)
from diagrams.planning_station import make_planning_station
from drake_sim.base import cli
from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from planning.errors import ErrorCode, PlanningError
from planning.task.pick_place import STEPS, PickPlaceTask, StepReport, TaskReport

BUTTON = "Pick"


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.pickplace", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--scenario",
        type=cli.input_file("scenario file"),
        default=config_dir() / "pickplace_scenario.yaml",
        help="scenario YAML (default config/pickplace_scenario.yaml)",
    )
    parser.add_argument(
        "--scene",
        type=cli.input_file("scene file"),
        help="scene YAML (replaces the scenario's scene)",
    )
    parser.add_argument(
        "--station",
        type=cli.input_file("station file"),
        help="YAML of the scenario's station section",
    )
    parser.add_argument("--mode", choices=MODES, help="default: the scenario's (physics)")
    parser.add_argument("--headless", action="store_true", help="no Meshcat, no pacing")
    parser.add_argument("--no-wait", action="store_true", help="with a viewer: start at once")
    parser.add_argument(
        "--record", type=cli.output_file("replay"), help="write a self-contained HTML replay"
    )
    parser.add_argument("--report", type=cli.output_file("report"), help="write the JSON report")
    parser.add_argument("--seed", type=cli.non_negative_int, help="planner random seed")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scenario value, e.g. --set task.lift_height=0.08 (repeatable)",
    )
    parser.add_argument(
        "--print-scenario", action="store_true", help="print the whole scenario as YAML and exit"
    )
    return parser.parse_args(argv)


def load_scenario(args) -> PickPlaceScenario:
    """The scenario of the command line: file, scene, station, --set, --mode and --seed."""
    overrides = list(args.set)
    if args.mode is not None:
        overrides.append(f"mode={args.mode}")
    if args.seed is not None:
        overrides.append(f"planner.seed={args.seed}")
    scenario = load_pickplace_scenario(args.scenario, scene_file=args.scene, overrides=overrides)
    if args.station is not None:
        station = load_typed(PandaStationConfig, filename=args.station, defaults=scenario.station)
        for key in ("model", "scene", "initial_q"):
            if getattr(station, key) != getattr(scenario.station, key):
                raise ConfigError(f"{args.station}: 'station.{key}' is set by the scenario")
        scenario = dc.replace(scenario, station=station)
    return scenario


def _print_step(step: StepReport) -> None:
    mark = "ok  " if step.success else "FAIL"
    print(
        f"[{mark}] {step.name:<18} t = {step.sim_time_s:6.2f} s  "
        f"planning {step.planning_time_s * 1000:6.1f} ms  {step.message}",
        flush=True,
    )


def _wait_for_button(mpi, meshcat) -> None:
    meshcat.AddButton(BUTTON)
    print(f"open {meshcat.web_url()} and press {BUTTON!r} (Ctrl-C quits)", flush=True)
    while meshcat.GetButtonClicks(BUTTON) == 0:
        mpi.advance(0.05)
    meshcat.DeleteButton(BUTTON)


def _run_task(mpi, meshcat, scenario, args):
    """Waits for the Pick button (with a viewer, unless ``--no-wait``) and runs the task.

    Returns:
        (the task's report, whether Ctrl-C or SIGTERM stopped it): a stopped task's report holds
        the steps done (a summary line says how far it got).
    """
    steps = []

    def on_step(step: StepReport) -> None:
        steps.append(step)
        _print_step(step)

    wall_start = time.perf_counter()
    try:
        if not args.headless:
            if args.no_wait:
                cli.announce(meshcat, "running the task")
            else:
                _wait_for_button(mpi, meshcat)
        return PickPlaceTask(mpi, scenario.task, on_step=on_step).run(), False
    except BaseException as e:  # a stop may surface as another error: see cli.is_stop
        if not cli.is_stop(e):
            raise
        wall = time.perf_counter() - wall_start
        print(
            f"stopped: {len(steps)} of {len(STEPS)} steps done, {mpi.time:.1f} s simulated "
            f"in {wall:.1f} s"
        )
        report = TaskReport(reason="stopped by the user", steps=steps, sim_time_s=mpi.time)
        report.wall_time_s = wall
        return report, True


def main(argv=None) -> int:
    args = _parse_args(argv)
    scenario = load_scenario(args)
    if args.print_scenario:
        print(dump_pickplace_scenario(scenario), end="")
        return cli.EXIT_OK
    viewer = not args.headless
    meshcat = StartMeshcat() if viewer or args.record else None
    setup_start = time.perf_counter()
    try:
        mpi = make_planning_station(scenario, meshcat=meshcat, realtime_rate=1.0 if viewer else 0.0)
    except PlanningError as e:
        if e.code is ErrorCode.INVALID_SCENE:
            raise ConfigError(e.message) from None
        raise
    setup_s = time.perf_counter() - setup_start  # the planner's kernels compiled or loaded
    if meshcat is not None:
        meshcat.SetCameraPose([1.6, -1.2, 0.9], [0.4, 0.0, 0.15])
        if args.record:
            meshcat.StartRecording()
    try:
        report, stopped = _run_task(mpi, meshcat, scenario, args)
    finally:
        if args.record:
            cli.write_replay(meshcat, args.record)
    end = "stopped" if stopped else "done" if report.success else "failed"
    data = {"end": end, "mode": scenario.mode, "setup_time_s": setup_s, **report.to_dict()}
    if args.report:
        cli.write_text(args.report, json.dumps(data, indent=2) + "\n", "report")
    if stopped:
        return cli.EXIT_OK  # a user stop
    error = "n/a" if report.place_error_m is None else f"{report.place_error_m:.4f} m"
    print(
        f"{'success' if report.success else 'failure'}: place error {error}, planning "
        f"{report.planning_time_s:.2f} s, {report.sim_time_s:.1f} s simulated in "
        f"{report.wall_time_s:.1f} s; set-up {setup_s:.1f} s (the planner's kernels "
        "compiled or loaded)",
        flush=True,
    )
    code = cli.EXIT_OK
    if not report.success:
        what = "impossible task" if report.impossible else f"step {report.failed_step} failed"
        reason = " ".join(report.reason.split())  # one line
        print(f"error: {what}: {reason}", file=sys.stderr, flush=True)
        code = cli.EXIT_FAILED
    if viewer:
        cli.announce(meshcat, "showing the result")
        try:
            while True:
                mpi.advance(0.1)
        except BaseException as e:
            if not cli.is_stop(e):
                raise
    return code


if __name__ == "__main__":
    cli.exit_at_once(cli.run(main))  # a stop does not wait for a planner thread to finish
