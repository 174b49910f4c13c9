"""Random planning problems for an arm: obstacles around it, a start and a goal that differ.

A problem is a scene of boxes and cylinders (3 to 8 by default) placed within the arm's reach
and clear of its base, and a collision-free start and goal of the planning group's joints,
drawn uniformly within the joint limits and checked with the planning scene's collision
checker, at least ``min_separation`` apart and, by default, with the straight line between them
colliding (a problem asks for more than a straight line). What is robot-specific is the
planning scene (its model, joint limits and checker) and a ``Workspace`` (where the arm
reaches, how wide its base is, its group's name):
``PANDA_WORKSPACE`` for the Panda; another robot passes its scene and its own workspace.

Problems are deterministic for a seed: problem ``k`` draws from its own generator, spawned from
``numpy.random.default_rng(seed)``'s seed sequence, so the first problems of a seed are the same
whatever the number asked for. A problem whose obstacles leave no valid start and goal is drawn
again (new obstacles), a bounded number of times; then ``ProblemGenerationError`` names it.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform

from planning.scene_objects import SceneObject


@dc.dataclass(frozen=True)
class Workspace:
    """Where an arm reaches and what of it obstacles must keep clear of (world frame, m).

    Attributes:
        group: the planning group's name, written into requests.
        shoulder: the centre of the reachable ball (the second joint's axis for the Panda).
        reach: the ball's radius: obstacle centres lie within it.
        base_radius: obstacles stay this far from the base's vertical axis (whole object).
        floor: obstacle centres lie at or above this height.
    """

    group: str
    shoulder: tuple[float, float, float]
    reach: float
    base_radius: float
    floor: float


PANDA_WORKSPACE = Workspace(
    group="panda_arm", shoulder=(0.0, 0.0, 0.333), reach=0.855, base_radius=0.2, floor=-0.3
)
"""The Panda: 85.5 cm reach from the shoulder, link0 and link1 within 0.2 m of the z axis."""

_TUNED = {"panda": PANDA_WORKSPACE}
"""Workspaces measured for a robot (by its URDF name); others are derived (``workspace_of``)."""


def workspace_of(scene) -> Workspace:
    """The workspace of the scene's robot: the tuned one when there is one (the Panda's), else
    derived from its model: the ball around the end-effector chain's first joint whose radius is
    the chain's reach bound (``planning.search.reach``), obstacles 0.2 m clear of the vertical
    axis through the root and at most 0.3 m below it."""
    model = scene.model
    tuned = _TUNED.get(model.robot.name)
    if tuned is not None and model.robot.group in ("arm", tuned.group):
        return tuned
    from planning.search.reach import reach_bound

    plant = scene.plant
    context = plant.CreateDefaultContext()
    plant.SetPositions(
        context, scene.full_q(np.clip(np.zeros(model.num_joints), scene.lower, scene.upper))
    )
    frame = plant.GetFrameByName(model.ee_frame, model.instance)
    shoulder, reach = reach_bound(plant, context, frame)
    root = model.robot.root_link
    at = plant.world_frame() if root == "world" else plant.GetFrameByName(root, model.instance)
    base = at.CalcPoseInWorld(context).translation()
    return Workspace(
        group=model.robot.group,
        shoulder=tuple(float(v) for v in shoulder),
        reach=float(reach),
        base_radius=0.2,
        floor=float(base[2] - 0.3),
    )


@dc.dataclass(frozen=True)
class RandomProblemOptions:
    """What to draw (m; angles in rad).

    Attributes:
        obstacles: least and most obstacles (inclusive).
        box_size: least and most edge of a box.
        cylinder_radius, cylinder_length: ranges of a cylinder's.
        min_separation: least joint-space distance (L2) between start and goal.
        blocked: whether the straight line from start to goal must collide (so that a
            problem asks for more than the straight line).
        configuration_draws: draws for each of the start and the goal in one scene.
        scene_draws: scenes drawn before the problem is given up.
    """

    obstacles: tuple[int, int] = (3, 8)
    box_size: tuple[float, float] = (0.05, 0.3)
    cylinder_radius: tuple[float, float] = (0.02, 0.1)
    cylinder_length: tuple[float, float] = (0.1, 0.5)
    min_separation: float = 1.0
    blocked: bool = True
    configuration_draws: int = 300
    scene_draws: int = 10


@dc.dataclass(frozen=True)
class RandomProblem:
    """One problem.

    Attributes:
        number: 1-based.
        objects: the world objects.
        joint_names: the group's joints, in order.
        q_start, q_goal: the group's positions (rad), in ``joint_names``' order.
        other_joints: the joints outside the group at the start (e.g. fingers), by name.
    """

    number: int
    objects: tuple[SceneObject, ...]
    joint_names: tuple[str, ...]
    q_start: np.ndarray
    q_goal: np.ndarray
    other_joints: dict[str, float]


class ProblemGenerationError(ValueError):
    """No valid start and goal was found for problem ``number`` within the draws allowed."""

    def __init__(self, number: int, message: str):
        super().__init__(message)
        self.number = number


def group_joint_names(scene) -> tuple[str, ...]:
    """The names of the scene's planning group's joints, in the order of its configurations."""
    return _joint_names(scene, scene.model.arm_indices)


def random_problems(
    scene,
    count: int,
    seed: int,
    workspace: Workspace = PANDA_WORKSPACE,
    options: RandomProblemOptions | None = None,
):
    """Yields ``count`` problems (``RandomProblem``), or a ``ProblemGenerationError`` in place
    of a problem that could not be made; the scene holds each problem's objects as it is
    yielded (its world objects are replaced).

    Raises:
        ValueError: ``count`` < 1.
    """
    if count < 1:
        raise ValueError(f"the number of problems must be >= 1, got {count}")
    options = options or RandomProblemOptions()
    children = np.random.default_rng(seed).bit_generator.seed_seq.spawn(count)
    for number, child in enumerate(children, start=1):
        try:
            yield make_problem(scene, number, np.random.default_rng(child), workspace, options)
        except ProblemGenerationError as e:
            yield e


def make_problem(
    scene, number: int, rng: np.random.Generator, workspace: Workspace, options
) -> RandomProblem:
    """Draws one problem into ``scene`` (its world objects replaced).

    Raises:
        ProblemGenerationError: no scene of the ``scene_draws`` had a valid start and goal.
    """
    model = scene.model
    lower, upper = scene.lower, scene.upper
    for _ in range(options.scene_draws):
        objects = tuple(random_obstacles(rng, workspace, options))
        scene.replace(world=objects)
        start = _free_configuration(scene, rng, lower, upper, options.configuration_draws)
        if start is None:
            continue
        for _ in range(options.configuration_draws):
            goal = _free_configuration(scene, rng, lower, upper, 1)
            if _acceptable(scene, start, goal, options):
                others = _joint_names(scene, model.other_indices)
                return RandomProblem(
                    number,
                    objects,
                    group_joint_names(scene),
                    start,
                    goal,
                    dict(zip(others, map(float, scene.other_positions), strict=True)),
                )
    raise ProblemGenerationError(
        number,
        f"random problem {number}: no collision-free start and goal {options.min_separation} "
        f"rad apart{' (the straight line between blocked)' if options.blocked else ''} in "
        f"{options.scene_draws} scenes of {options.configuration_draws} draws",
    )


def random_obstacles(rng: np.random.Generator, workspace: Workspace, options):
    """Yields the obstacles of one scene: boxes and cylinders at random orientations, centres
    within reach, each wholly ``base_radius`` from the base's vertical axis."""
    count = int(rng.integers(options.obstacles[0], options.obstacles[1] + 1))
    for k in range(count):
        if rng.random() < 0.5:
            shape, size = "box", tuple(rng.uniform(*options.box_size, size=3))
        else:
            size = (rng.uniform(*options.cylinder_radius), rng.uniform(*options.cylinder_length))
            shape = "cylinder"
        centre = _centre(rng, workspace, bounding_radius(shape, size))
        rotation = Quaternion(_unit(rng.normal(size=4)))
        yield SceneObject(f"obstacle{k}", shape, size, RigidTransform(rotation, centre))


def bounding_radius(shape: str, size) -> float:
    """The radius of the ball about an object's centre that holds it (m)."""
    if shape == "box":
        return 0.5 * float(np.linalg.norm(size))
    if shape == "cylinder":
        return float(np.hypot(size[0], 0.5 * size[1]))
    return float(size[0])


def _centre(rng, workspace: Workspace, radius: float) -> np.ndarray:
    """A point within reach whose ball of ``radius`` keeps clear of the base's axis (rejection
    sampling in the reach's bounding box: most draws are kept)."""
    shoulder = np.asarray(workspace.shoulder, dtype=float)
    clear = workspace.base_radius + radius
    for _ in range(10_000):
        p = shoulder + rng.uniform(-workspace.reach, workspace.reach, size=3)
        if (
            np.linalg.norm(p - shoulder) <= workspace.reach
            and np.hypot(p[0], p[1]) >= clear
            and p[2] >= workspace.floor
        ):
            return p
    raise ValueError(f"no room within reach for an obstacle of radius {radius:.3f} m")


def _acceptable(scene, start, goal, options) -> bool:
    if goal is None or np.linalg.norm(goal - start) < options.min_separation:
        return False
    return not (options.blocked and scene.is_edge_collision_free(start, goal))


def _free_configuration(scene, rng, lower, upper, draws: int):
    for _ in range(draws):
        q = rng.uniform(lower, upper)
        if scene.is_collision_free(q):
            return q
    return None


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _joint_names(scene, indices) -> tuple[str, ...]:
    """The names of the one-position joints of the scene's robot at plant positions
    ``indices``, in that order."""
    plant, instance = scene.plant, scene.model.instance
    by_position = {}
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        if joint.num_positions() == 1:
            by_position[joint.position_start()] = joint.name()
    return tuple(by_position[int(i)] for i in indices)
