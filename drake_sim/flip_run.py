"""Run the flipping robot and summarise what it did (the report of ``python -m drake_sim.flip``)."""

import dataclasses as dc
import math
import time

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import ApplySimulatorConfig
from tqdm import tqdm

from diagrams.flip import make_flip_diagram
from diagrams.flip_scenario import FlipScenario
from drake_sim.base.report import RunReport, run_times
from drake_sim.base.simulation import start_simulator
from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.control.flip_controller import STATUS_FIELDS, FlipMode


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


PROGRESS_STEP = 0.5  # s simulated between progress-bar updates.


class FlipRun:
    """The flipping robot's diagram and simulator, ready to advance.

    Args:
        scenario: world, sensors and controllers.
        robot: the robot's dimensions.
        seed: the random seed (IMU noise); ``scenario.scene.random_seed`` when None.
        meshcat: draw there, or None to run headless.
        realtime: pace the run with ``scenario.scene.simulator`` (its real-time rate); by
            default, when there is a ``meshcat``. Otherwise it runs flat out.
        controller: "flip", "teleop" (Meshcat keys; needs ``meshcat``) or "cmd_vel" (fix or
            connect the diagram's ``cmd_vel`` input); see ``diagrams.flip.CONTROLLERS``.
    """

    def __init__(
        self,
        scenario: FlipScenario,
        robot: RobotParams,
        *,
        seed: int | None = None,
        meshcat: Meshcat | None = None,
        realtime: bool | None = None,
        controller: str = "flip",
    ):
        self.seed = scenario.scene.random_seed if seed is None else seed
        self.controller = controller
        self.diagram = make_flip_diagram(scenario, robot, meshcat=meshcat, controller=controller)
        if realtime is None:
            realtime = meshcat is not None
        config = scenario.scene.simulator
        self.simulator, self.context = start_simulator(
            self.diagram,
            self.seed,
            (lambda s: ApplySimulatorConfig(config, s)) if realtime else None,
        )
        self.wall_time = 0.0

    def advance_to(self, t: float, *, progress: bool = False) -> None:
        """Simulates until time ``t`` (s); wall time spent is added to ``wall_time``.

        With ``progress``, advances in ``PROGRESS_STEP`` chunks under a progress bar on
        stderr, shown only when stderr is a terminal (the result is the same).
        """
        start = time.perf_counter()
        try:
            if progress and math.isfinite(t):
                self._advance_with_bar(t)
            else:
                self.simulator.AdvanceTo(t)
        finally:
            self.wall_time += time.perf_counter() - start

    def _advance_with_bar(self, t: float) -> None:
        now = self.context.get_time()
        bar_format = "{l_bar}{bar}| {n:.1f}/{total:.1f} simulated s [{elapsed}<{remaining}]"
        with tqdm(total=t - now, leave=False, disable=None, bar_format=bar_format) as bar:
            while now < t:
                step_end = min(t, now + PROGRESS_STEP)
                self.simulator.AdvanceTo(step_end)
                bar.update(step_end - now)
                now = step_end

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
            **run_times(sim_time, self.wall_time, self.seed),
        )
