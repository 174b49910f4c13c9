"""The flipping robot's app (``python -m drake_sim.flip``): its recipe, its run and what the run
did (the report).

With a viewer the run goes on until Ctrl-C or ``--duration``; headless for
``HEADLESS_DURATION`` s. ``controller`` "teleop" turns the flip controller off for the Meshcat
keys.
"""

import dataclasses as dc
import math

import numpy as np

from diagrams.flip import make_flip_diagram
from diagrams.flip_scenario import FlipScenario, check_flip_scenario, load_flip_scenario
from drake_sim.base.report import RunReport, run_times
from drake_sim.base.resources import config_dir
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import RobotParams, load_robot_params, validate
from drake_sim.runs import recipe
from drake_sim.runs.loop import SimulationRun
from drake_sim.runs.recipe import AppRecipe, CliText, InputFile, Inputs
from drake_sim.systems.control.flip_controller import STATUS_FIELDS, FlipMode
from drake_sim.systems.viewer.teleop import BUTTONS

HEADLESS_DURATION = 20.0  # s, the default run length without a viewer.
PROGRESS_MIN_DURATION = 10.0  # s simulated: shorter headless runs show no progress bar.


@dc.dataclass(kw_only=True)
class FlipReport(RunReport):
    """What a run did. Distances in m, times in s. The keys are docs/flip.md's (The report)."""

    flips: int  # Completed half-turns over the axle.
    failed_flips: int  # Attempts that fell back or timed out (each then recovered or not).
    recoveries: int  # Times the controller rocked the robot free.
    max_lateral_deviation_m: float  # Largest distance from the line the robot started on.
    travel_extent_m: float  # Max minus min position along that line.
    distance_travelled_m: float  # True path length of the axle's midpoint.
    odometry_error_m: float  # Final distance between odometry and the true position.
    max_odometry_error_m: float
    naive_odometry_error_m: float  # The same for odometry that ignores flips.
    max_naive_odometry_error_m: float
    longest_time_without_flip_s: float  # Longest stretch between completed flips.
    stuck: bool  # True if the robot was still recovering at the end.
    finite: bool  # No NaN or infinity anywhere in the logged signals.
    end: str = "duration"  # Why the run ended: duration, stopped or failed.


def summarize(
    times: np.ndarray,
    true_pose: np.ndarray,
    odometry: np.ndarray,
    naive: np.ndarray,
    status: np.ndarray | None,
) -> dict:
    """Computes the report's motion figures from logged signals (one column per sample).

    ``true_pose``, ``odometry`` and ``naive`` are 3 x N ``[x, y, yaw]``; ``status`` the flip
    controller's status (``STATUS_FIELDS``) or None under teleop. The line is the one through
    the first true position along the first true heading.
    """
    p = true_pose[:2]
    direction = np.array([math.cos(true_pose[2, 0]), math.sin(true_pose[2, 0])])
    offset = p - p[:, :1]
    along = direction @ offset
    across = direction[0] * offset[1] - direction[1] * offset[0]
    odometry_error = np.linalg.norm(odometry[:2] - p, axis=0)
    naive_error = np.linalg.norm(naive[:2] - p, axis=0)
    figures = {
        "max_lateral_deviation_m": float(np.max(np.abs(across))),
        "travel_extent_m": float(np.ptp(along)),
        "distance_travelled_m": float(np.sum(np.linalg.norm(np.diff(p, axis=1), axis=0))),
        "odometry_error_m": float(odometry_error[-1]),
        "max_odometry_error_m": float(np.max(odometry_error)),
        "naive_odometry_error_m": float(naive_error[-1]),
        "max_naive_odometry_error_m": float(np.max(naive_error)),
        "flips": 0,
        "failed_flips": 0,
        "recoveries": 0,
        "longest_time_without_flip_s": 0.0,
        "stuck": False,
    }
    if status is not None:
        fields = dict(zip(STATUS_FIELDS, status, strict=True))
        flips = fields["flips"]
        flip_times = np.concatenate([[times[0]], times[1:][np.diff(flips) > 0], [times[-1]]])
        figures.update(
            flips=int(flips[-1]),
            failed_flips=int(fields["failed_flips"][-1]),
            recoveries=int(fields["recoveries"][-1]),
            longest_time_without_flip_s=float(np.max(np.diff(flip_times))),
            stuck=bool(fields["mode"][-1] == FlipMode.RECOVER),
        )
    return figures


class FlipRun(SimulationRun):
    """The flipping robot's diagram and simulator, ready to advance (a bar on headless runs of
    ``PROGRESS_MIN_DURATION`` s or more, on a terminal only).

    Args:
        scenario: world, sensors and controllers; its ``scene.random_seed`` seeds the IMU noise.
        robot: the robot's dimensions.
        realtime: pace the run with ``scenario.scene.simulator`` (its real-time rate); by
            default, when there is a ``meshcat``. Otherwise it runs flat out.
        diagram: ``make_flip_diagram``'s keywords: ``meshcat`` (draw there; None: headless)
            and ``controller``: "flip" (the default), "teleop" (Meshcat keys; needs
            ``meshcat``) or "cmd_vel" (fix or connect the diagram's ``cmd_vel`` input).
    """

    progress_from = PROGRESS_MIN_DURATION

    def __init__(self, scenario: FlipScenario, robot: RobotParams, *, realtime=None, **diagram):
        self.scenario = scenario
        self.controller = diagram.setdefault("controller", "flip")
        meshcat = diagram.get("meshcat")
        pacing = {"realtime": realtime, "config": scenario.scene.simulator, "meshcat": meshcat}
        diagram = make_flip_diagram(scenario, robot, **diagram)
        super().__init__(diagram, scenario.scene.random_seed, **pacing)

    def default_duration(self, *, viewer: bool = False) -> float:
        """Until Ctrl-C with a viewer, else ``HEADLESS_DURATION``."""
        return math.inf if viewer else HEADLESS_DURATION

    def set_up_viewer(self, meshcat) -> None:
        """Points Meshcat's camera at the robot and hides the grid (the street is the floor)."""
        pose = self.scenario.scene.robot_pose
        meshcat.SetCameraPose([pose.x - 0.6, pose.y - 2.0, 1.1], [pose.x + 0.4, pose.y, 0.15])
        meshcat.SetProperty("/Grid", "visible", False)
        if self.controller == "teleop":
            keys = ", ".join(label for label, _, _ in BUTTONS)
            print(f"teleop: click the Meshcat page, then use its buttons or keys: {keys}")

    def log(self, name: str):
        """The ``VectorLog`` of a logged signal (see ``diagrams.flip.LOGGED``)."""
        return self.diagram.GetSubsystemByName(f"log_{name}").FindLog(self.context)

    def report(self) -> FlipReport:
        """Summarises the run so far."""
        truth = self.log("true_pose")
        data = {name: self.log(name).data() for name in ("odometry_pose", "naive_pose")}
        status = self.log("status").data() if self.controller == "flip" else None
        figures = summarize(
            truth.sample_times(), truth.data(), data["odometry_pose"], data["naive_pose"], status
        )
        signals = [truth.data(), *data.values()] + ([status] if status is not None else [])
        sim_time = self.context.get_time()
        return FlipReport(
            **figures,
            finite=all(bool(np.all(np.isfinite(s))) for s in signals),
            end=self.end,
            **run_times(sim_time, self.wall_time, self.seed),
        )

    def summary(self, report: FlipReport) -> str:
        return (
            f"flips {report.flips} (failed {report.failed_flips}, recovered {report.recoveries}), "
            f"lateral deviation {report.max_lateral_deviation_m:.3f} m, "
            f"travel extent {report.travel_extent_m:.2f} m, "
            f"odometry error {report.odometry_error_m:.3f} m over "
            f"{report.distance_travelled_m:.1f} m, "
            f"{report.sim_time_s:.1f} s simulated at {report.real_time_factor:.1f}x real time"
        )


def make_run(inputs: Inputs, options, *, meshcat=None, realtime=None) -> FlipRun:
    """The recipe's run: ``options.teleop`` (or ``options["controller"]``) picks the
    controller."""
    if isinstance(options, dict):
        controller = options.get("controller", "flip")
    else:
        controller = "teleop" if getattr(options, "teleop", False) else "flip"
    return FlipRun(
        inputs.scenario, inputs.robot, meshcat=meshcat, realtime=realtime, controller=controller
    )


RECIPE = AppRecipe(
    name="flip",
    robot=InputFile(
        RobotParams, default_robot_file, validate, what="robot file", load=load_robot_params
    ),
    scenario=InputFile(
        FlipScenario,
        lambda: config_dir() / "flip.yaml",
        check_flip_scenario,
        load=load_flip_scenario,
    ),
    seed_key="scene.random_seed",
    make_run=make_run,
    flags=(recipe.switch("--teleop", "drive with Meshcat keys"),),
    cli=CliText(
        seed="random seed (IMU noise)",
        set_example="flip.drive_speed=1.0",
        duration="simulated seconds (default: until Ctrl-C with a viewer; "
        f"{HEADLESS_DURATION:g} when --headless)",
        headless="no Meshcat, no pacing",
    ),
)
"""``python -m drake_sim.flip``: robot ``config/ddrive.yaml``, scenario ``config/flip.yaml``."""


def report_keys() -> tuple[str, ...]:
    """The keys of the run's report (a sweep's metrics)."""
    return tuple(f.name for f in dc.fields(FlipReport))
