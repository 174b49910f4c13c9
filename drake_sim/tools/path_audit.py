"""``python -m drake_sim.tools.path_audit REPORT.json``: checks a benchmark report's paths between
the planner's own samples, with Drake's exact geometry.

Usage::

    python -m drake_sim.tools.path_audit report.json [--dataset DIR] [--step 0.01] [--offsets 4]

The planner validates every path it returns at samples ``validation.resolution`` apart; a motion
can still touch an obstacle between two of them. This audit does not trust the planner's models
(its sphere covers, its exact-shape proofs) nor its sample positions: for each solved row of a
``python -m planning.benchmark`` report it loads the row's MoveIt scene (``--dataset``: the
problems folder the benchmark ran, found as the benchmark finds it) onto a robot of its own
(``planning_scene_target``: a fresh ``PlanningScene``, its plant and ``SceneGraphCollisionChecker``
with the SRDF's disabled pairs, no padding), sets the joints the request names by name (the
path's by the row's ``joint_names``, the others from the request's start state), and samples
every segment of ``path`` from ``offsets`` different starting points: at s = (j + k / offsets)
``step`` along it for k = 0 .. offsets - 1, plus both ends. At each sample SceneGraph's signed
distances between the pairs the checker does not filter tell whether the robot touches
(distance < 0): the path's least distance, the pair and how far along the path the touch runs.

Only the report's ``path``, ``joint_names``, ``family`` and ``problem`` are read. Another robot
needs another ``AuditTarget`` (``planning_scene_target`` is the Panda's, from the scene the
benchmark plans in); the rest maps joint values by name and is the same for every robot.
Exit code 0 when no path touches, 1 when some does, 2 on bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError

DEFAULT_STEP = 0.01  # rad, the benchmark's validation resolution
DEFAULT_OFFSETS = 4


@dataclass
class AuditTarget:
    """What the audit needs of one robot: its own checker and how to name its joints.

    Attributes:
        checker: a ``SceneGraphCollisionChecker`` over the robot's collision geometry, its
            filters the SRDF's (padding is not read: the audit asks for touching, distance < 0).
        load_scene: loads a MoveIt scene file into the checker's model, replacing the last one.
        default_positions: the plant's positions for the joints a request does not name.
        position_index: the plant position of each joint, by name.
    """

    checker: object
    load_scene: Callable[[Path], None]
    default_positions: np.ndarray
    position_index: dict[str, int]

    def __post_init__(self):
        self._context = self.checker.MakeStandaloneModelContext()
        self._plant = self.checker.plant()

    def positions(self, values: dict[str, float]) -> np.ndarray:
        """The plant's positions with the named joints set (the others at their defaults)."""
        full = np.array(self.default_positions, dtype=float)
        for name, value in values.items():
            if name in self.position_index:
                full[self.position_index[name]] = value
        return full

    def closest(self, full: np.ndarray, reach: float = 0.0) -> tuple[float, str]:
        """The least signed distance (m) among the checked pairs within ``reach`` at the plant
        positions ``full``, and the pair ("a <-> b"); (inf, "") when none is that close."""
        self.checker.UpdateContextPositions(self._context, full)
        query = self._context.GetQueryObject()
        inspector = query.inspector()
        best, pair = np.inf, ""
        for found in query.ComputeSignedDistancePairwiseClosestPoints(reach):
            if found.distance >= best:
                continue
            body_a = self._body(inspector, found.id_A)
            body_b = self._body(inspector, found.id_B)
            if body_a.index() == body_b.index():
                continue
            if self.checker.IsCollisionFilteredBetween(body_a.index(), body_b.index()):
                continue
            best = found.distance
            names = (
                self._name(inspector, found.id_A, body_a),
                self._name(inspector, found.id_B, body_b),
            )
            pair = " <-> ".join(sorted(names))
        return best, pair

    def _body(self, inspector, geometry_id):
        return self._plant.GetBodyFromFrameId(inspector.GetFrameId(geometry_id))

    def _name(self, inspector, geometry_id, body) -> str:
        if body.index() == self._plant.world_body().index():
            return inspector.GetName(geometry_id).split(" (<")[0]
        return body.name()


def planning_scene_target(scene) -> AuditTarget:
    """The audit's robot from a ``planning.planning_scene.PlanningScene`` made for it (a fresh
    one: its checker is the audit's own): the robot-specific part of the audit. Its padding is
    not used; its SRDF's disabled pairs are (``IsCollisionFilteredBetween``)."""
    plant = scene.plant
    index = {}
    for k in range(plant.num_joints()):
        joint = plant.get_joint(_joint_index(k))
        if joint.num_positions() == 1:
            index[joint.name()] = joint.position_start()
    return AuditTarget(
        checker=scene.checker,
        load_scene=scene.load_moveit,
        default_positions=scene.full_q(np.zeros(len(scene.model.arm_indices))),
        position_index=index,
    )


def _joint_index(k: int):
    from pydrake.multibody.tree import JointIndex

    return JointIndex(k)


@dataclass
class Touch:
    """A path that touches: its least signed distance (m, < 0), the pair, the segment and the
    distance along it (rad) of the deepest sample, and the span (rad) of the samples of that
    segment that touch."""

    family: str
    problem: int
    distance: float
    pair: str
    segment: int
    at: float
    span: float

    def line(self) -> str:
        return (
            f"{self.family} {self.problem:4d}: touches by {-self.distance * 1e3:.3f} mm "
            f"({self.pair}), segment {self.segment} at {self.at:.4f} rad, over "
            f"{self.span * 1e3:.2f} mrad"
        )


def segment_samples(length: float, step: float, offsets: int) -> np.ndarray:
    """Where a segment of ``length`` (rad) is sampled, sorted: s = (j + k / offsets) step for
    every k < offsets and j >= 0 within it, plus both ends."""
    starts = step * np.arange(offsets) / offsets
    count = int(np.floor(length / step)) + 1
    s = (np.arange(count)[:, None] * step + starts[None, :]).ravel()
    return np.unique(np.concatenate([s[s < length], [0.0, length]]))


def audit_path(
    target: AuditTarget,
    path,
    joint_names,
    other_joints: dict[str, float] | None = None,
    *,
    step: float = DEFAULT_STEP,
    offsets: int = DEFAULT_OFFSETS,
) -> tuple[float, str, int, float, float]:
    """Samples every segment of ``path`` (rows of values of ``joint_names``) as
    ``segment_samples`` says and returns (the least signed distance found (inf when nothing
    touches), its pair, segment, distance along it (rad), span of that segment's touching
    samples (rad)). ``other_joints``: the values of joints outside the path, by name."""
    path = np.asarray(path, dtype=float)
    if path.ndim != 2 or path.shape[1] != len(joint_names) or len(path) < 1:
        raise ValueError(f"a path of {len(joint_names)} joints expected, got shape {path.shape}")
    base = dict(other_joints or {})
    worst = (np.inf, "", -1, 0.0, 0.0)
    segments = [(path[0], path[0])] + list(zip(path[:-1], path[1:], strict=True))
    for k, (q_a, q_b) in enumerate(segments):
        length = float(np.linalg.norm(q_b - q_a))
        s = segment_samples(length, step, offsets)
        touching = []
        for at in s:
            q = q_a if length == 0.0 else q_a + (at / length) * (q_b - q_a)
            full = target.positions(base | dict(zip(joint_names, q, strict=True)))
            distance, pair = target.closest(full)
            if distance < 0.0:
                touching.append(at)
                if distance < worst[0]:
                    worst = (distance, pair, k - 1, float(at), 0.0)
        if touching and worst[2] == k - 1:
            worst = (*worst[:4], float(max(touching) - min(touching)))
    return worst


def _request_joints(request_file: Path) -> dict[str, float]:
    """The start state's joint values of a MotionPlanRequest YAML, by name."""
    data = yaml.safe_load(Path(request_file).read_text())
    state = data["start_state"]["joint_state"]
    return dict(zip(state["name"], map(float, state["position"]), strict=True))


def audit_rows(
    rows: list[dict],
    dataset: Path,
    target: AuditTarget,
    *,
    step: float = DEFAULT_STEP,
    offsets: int = DEFAULT_OFFSETS,
    progress: Callable[[str], None] | None = None,
) -> tuple[int, list[Touch]]:
    """Audits the solved rows of a benchmark report (problems from ``dataset``, a problems
    folder); returns (paths audited, the touching ones)."""
    audited, touches = 0, []
    for row in rows:
        if not row.get("success") or row.get("path") is None:
            continue
        family, number = row["family"], int(row["problem"])
        names = row.get("joint_names")
        if not names:
            raise ConfigError(f"row {family} {number} has a path but no joint_names")
        scene_file = dataset / family / f"scene{number:04d}.yaml"
        request_file = dataset / family / f"request{number:04d}.yaml"
        if not (scene_file.is_file() and request_file.is_file()):
            raise ConfigError(f"{dataset}: no problem {family} {number}")
        target.load_scene(scene_file)
        found = audit_path(
            target,
            row["path"],
            names,
            _request_joints(request_file),
            step=step,
            offsets=offsets,
        )
        audited += 1
        if found[0] < 0.0:
            touches.append(Touch(family, number, *found))
            if progress is not None:
                progress(touches[-1].line())
    return audited, touches


def load_report(filename: Path) -> list[dict]:
    """The rows of a benchmark report; ConfigError naming the file when it is not one."""
    try:
        rows = json.loads(Path(filename).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ConfigError(f"{filename}: not a benchmark report ({e})") from None
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ConfigError(f"{filename}: not a benchmark report (a list of rows expected)")
    for r in rows:
        if r.get("success") and not {"family", "problem", "path"} <= set(r):
            raise ConfigError(f"{filename}: a solved row lacks family, problem or path")
    return rows


def main(argv=None) -> int:
    """Runs the audit; returns the exit code (0: nothing touches, 1: some path does). The
    scenes load as the benchmark loads them: ``planning.io`` logs errors only while it runs."""
    with cli.logger_level("planning.io", logging.ERROR):
        return cli.run(_main, argv)


def _main(argv) -> int:
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.path_audit",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("report", type=cli.input_file("report"), help="benchmark report JSON")
    parser.add_argument(
        "--dataset", type=cli.input_path("dataset"), help="MBM problems (as the benchmark's)"
    )
    parser.add_argument(
        "--robot",
        default="panda",
        metavar="NAME|FILE",
        help="the robot the report is for, as planning.benchmark's --robot (default panda)",
    )
    parser.add_argument("--step", type=cli.positive_float, default=DEFAULT_STEP, help="rad")
    parser.add_argument(
        "--offsets", type=cli.positive_int, default=DEFAULT_OFFSETS, help="sample offsets"
    )
    args = parser.parse_args(argv)
    rows = load_report(args.report)
    from drake_sim.tools.plan_benchmark import robot_config
    from planning.io import mbm
    from planning.planning_scene import PlanningScene

    shipped = args.robot in mbm.ARCHIVE_SHA256
    if args.dataset is None and not shipped:
        raise ConfigError(f"--robot {args.robot}: give the problems the report ran with --dataset")
    try:
        dataset = mbm.find_problems(args.dataset, robot=args.robot if shipped else "panda")
    except (FileNotFoundError, RuntimeError, ValueError) as e:
        raise ConfigError(str(e).splitlines()[0]) from None
    target = planning_scene_target(PlanningScene(robot_config(args.robot)))
    audited, touches = audit_rows(
        rows, dataset, target, step=args.step, offsets=args.offsets, progress=print
    )
    print(
        f"{len(touches)} of {audited} paths touch (signed distance < 0) at {args.offsets} "
        f"offsets of {args.step} rad"
    )
    return 1 if touches else 0


if __name__ == "__main__":
    sys.exit(main())
