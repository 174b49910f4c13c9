"""Collision-aware inverse kinematics for the Panda with seeded random restarts.

Each attempt is Drake's ``InverseKinematics`` nonlinear program: a position constraint (a box of
half-width ``position_tolerance`` about the target point) and/or an orientation constraint (angle
to the target rotation at most ``orientation_tolerance``), the arm's joint limits, the fingers
fixed at the scene's positions, a ``MinimumDistanceLowerBoundConstraint`` built on the scene's
collision checker (so it sees added and held objects and the scene's collision filters), and a
small quadratic cost pulling q towards the attempt's start. The first attempt starts at the seed;
restarts start at joint vectors drawn uniformly within the limits from
``np.random.default_rng(options.seed)``, so results are deterministic for a given seed. The
attempt first takes damped Newton steps from its start, pulled towards the start in the
Jacobian's null space (``planning.search.cartesian.PoseNewton``): the joints nearest the start
that reach the target, as the program's cost asks. When they satisfy every constraint of the
program, they are the attempt's answer (about 1 ms, against 3 ms for the program); otherwise the
program starts from them. A
solution is accepted only when forward kinematics confirms the tolerances and the collision
checker finds it collision-free.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.inverse_kinematics import (
    InverseKinematics,
    MinimumDistanceLowerBoundConstraint,
)
from pydrake.solvers import Solve

from planning.collision.sphere_kernel import announce_compile
from planning.config import IkOptions
from planning.errors import ErrorCode, PlanningError
from planning.search import pose_kernel
from planning.search.cartesian import PoseNewton
from planning.search.reach import reach_bound

_REACH_MARGIN = 0.02  # m added to the computed reach bound
_POSITION_COST = 1e3  # 1/m^2, weight of the squared position error (joint cost: 1e-2/rad^2)
_ORIENTATION_COST = 10.0  # weight of (1 - cos(angle error))
_NEWTON_STEPS = 50  # damped Newton steps that find the program's initial guess


@dataclass
class IkResult:
    """A solved IK request.

    Attributes:
        q: the 7 arm joints, rad.
        X_WE: the pose of the target frame E reached at q, in the world frame W.
        attempts: how many attempts were made (1 when the seeded attempt succeeded).
        solve_time: wall time, s.
    """

    q: np.ndarray
    X_WE: RigidTransform
    attempts: int
    solve_time: float


class IkSolver:
    """Solves IK on a ``PlanningScene`` (one per scene; not thread-safe).

    Args:
        scene: the planning scene (robot, objects, collision checker).
    """

    def __init__(self, scene):
        self._scene = scene
        announce_compile(pose_kernel.newton, pose_kernel.line)
        pose_kernel.warm_up()  # the compiled Newton steps, compiled or loaded now
        self._checker_context = scene.checker.MakeStandaloneModelContext()
        plant = scene.plant
        self._context = plant.CreateDefaultContext()
        self._lower, self._upper = scene.lower, scene.upper
        self._newtons: dict[int, PoseNewton] = {}  # by frame index

    def solve(
        self,
        frame_name: str,
        *,
        p_WE=None,
        R_WE: RotationMatrix | None = None,
        q_seed=None,
        options: IkOptions,
    ) -> IkResult:
        """Finds arm joints placing frame E at ``p_WE`` and/or orientation ``R_WE``.

        Args:
            frame_name: the robot's frame E to place (e.g. "panda_hand_tcp").
            p_WE: target position of E's origin in W, m; None leaves it free.
            R_WE: target orientation of E in W; None leaves it free.
            q_seed: the first attempt's start (group or full q); the model's ``home`` when None.
            options: tolerances, restarts, time budget and seed.

        Raises:
            PlanningError: NO_IK_SOLUTION (unreachable, or every attempt failed within the
                budget; the message names colliding bodies of the last colliding solution),
                INVALID_GOAL (no target, non-finite values), FRAME_NOT_FOUND.
        """
        start = time.perf_counter()
        scene, plant = self._scene, self._scene.plant
        if p_WE is None and R_WE is None:
            raise PlanningError(
                ErrorCode.INVALID_GOAL, "IK needs a position, an orientation or both"
            )
        if not plant.HasFrameNamed(frame_name, scene.model.instance):
            raise PlanningError(
                ErrorCode.FRAME_NOT_FOUND, f"{scene.model.robot.name} has no frame {frame_name!r}"
            )
        frame = plant.GetFrameByName(frame_name, scene.model.instance)
        if p_WE is not None:
            p_WE = np.asarray(p_WE, dtype=float).reshape(-1)
            if p_WE.size != 3 or not np.all(np.isfinite(p_WE)):
                raise PlanningError(
                    ErrorCode.INVALID_GOAL, f"target position {p_WE} is not 3 finite values"
                )
            self._check_reach(frame, p_WE)
        if R_WE is not None and not np.all(np.isfinite(R_WE.matrix())):
            raise PlanningError(ErrorCode.INVALID_GOAL, "target orientation is not finite")
        q_seed = scene.arm_q(scene.model.home if q_seed is None else q_seed)

        ik, q_vars = self._make_program(frame, p_WE, R_WE, options)
        newton = self.newton(frame)
        rng = np.random.default_rng(options.seed)
        why = "no attempt converged"
        attempts = 0
        for attempt in range(options.max_restarts + 1):
            if attempt > 0 and time.perf_counter() - start > options.time_budget:
                break
            attempts += 1
            q0 = q_seed if attempt == 0 else rng.uniform(self._lower, self._upper)
            # Damped Newton steps first, pulled towards q0 in the null space: the joints nearest
            # q0 that reach the target, which is what the program's cost asks for too. When
            # they meet every constraint of the program, they are the answer (about 1 ms);
            # otherwise the program starts from them (or from q0).
            R = None if R_WE is None else R_WE.matrix()
            q = newton.solve(q0, R, p_WE, _NEWTON_STEPS, rest=q0)
            if q is None or not self._program_accepts(ik, q):
                ik.prog().SetInitialGuess(q_vars, scene.full_q(q0 if q is None else q))
                self._set_nominal(ik, scene.full_q(q0))
                result = Solve(ik.prog())
                if not result.is_success():
                    continue
                q = scene.arm_q(result.GetSolution(q_vars))
            X_WE = self._fk(frame, q)
            if not self._within_tolerance(X_WE, p_WE, R_WE, options):
                continue
            if options.check_collisions and not scene.is_collision_free(q):
                why = f"solutions collide: {scene.describe_collisions(q)}"
                continue
            return IkResult(q, X_WE, attempts, time.perf_counter() - start)
        raise PlanningError(
            ErrorCode.NO_IK_SOLUTION,
            f"no IK solution for {frame_name} after {attempts} attempts in "
            f"{time.perf_counter() - start:.2f} s ({why})",
        )

    def newton(self, frame) -> PoseNewton:
        """The damped Newton steps placing ``frame`` (a Panda frame), made on the first call
        for that frame (reading its kinematic chain costs about half a millisecond)."""
        key = int(frame.index())
        if key not in self._newtons:
            scene = self._scene
            self._newtons[key] = PoseNewton(
                scene.plant, frame, scene.full_q, scene.model.arm_indices, self._lower, self._upper
            )
        return self._newtons[key]

    def _make_program(self, frame, p_WE, R_WE, options: IkOptions):
        scene, plant = self._scene, self._scene.plant
        ik = InverseKinematics(plant, with_joint_limits=False)
        q_vars = ik.q()
        prog = ik.prog()
        world = plant.world_frame()
        if p_WE is not None:
            tol = np.full(3, options.position_tolerance)
            ik.AddPositionConstraint(frame, np.zeros(3), world, p_WE - tol, p_WE + tol)
            # Aim for the centre of the tolerance box (the joint cost alone would stop at the
            # box's corner nearest the seed): 1 mm costs as much as moving joints 0.3 rad.
            ik.AddPositionCost(world, p_WE, frame, np.zeros(3), _POSITION_COST * np.eye(3))
        if R_WE is not None:
            ik.AddOrientationConstraint(
                world, R_WE, frame, RotationMatrix(), options.orientation_tolerance
            )
            ik.AddOrientationCost(world, R_WE, frame, RotationMatrix(), _ORIENTATION_COST)
        group, others = scene.model.group_indices, scene.model.other_indices
        prog.AddBoundingBoxConstraint(self._lower, self._upper, q_vars[group])
        if len(others):
            f = scene.other_positions
            prog.AddBoundingBoxConstraint(f, f, q_vars[others])
        if options.minimum_distance is not None:
            constraint = MinimumDistanceLowerBoundConstraint(
                scene.checker,
                options.minimum_distance,
                self._checker_context,
                None,
                options.influence_distance,
            )
            prog.AddConstraint(constraint, q_vars)
        self._cost = prog.AddQuadraticErrorCost(
            1e-2 * np.eye(len(q_vars)), np.zeros(len(q_vars)), q_vars
        )
        return ik, q_vars

    def _program_accepts(self, ik, q) -> bool:
        """True when the group's joints q satisfy every constraint of the program (joint
        limits, the other joints, pose, minimum distance)."""
        return bool(ik.prog().CheckSatisfied(ik.prog().GetAllConstraints(), self._scene.full_q(q)))

    def _set_nominal(self, ik, q_full) -> None:
        cost = self._cost.evaluator()
        cost.UpdateCoefficients(
            2e-2 * np.eye(len(q_full)), -2e-2 * q_full, float(1e-2 * q_full @ q_full)
        )

    def _fk(self, frame, q) -> RigidTransform:
        plant = self._scene.plant
        plant.SetPositions(self._context, self._scene.full_q(q))
        return frame.CalcPoseInWorld(self._context)

    def _check_reach(self, frame, p_WE) -> None:
        """Raises NO_IK_SOLUTION at once when p_WE is beyond a conservative reach bound."""
        scene, plant = self._scene, self._scene.plant
        plant.SetPositions(self._context, scene.full_q(np.zeros(scene.num_joints)))
        p_WA, reach = reach_bound(plant, self._context, frame)
        distance = np.linalg.norm(p_WE - p_WA)
        if distance > reach + _REACH_MARGIN:
            raise PlanningError(
                ErrorCode.NO_IK_SOLUTION,
                f"target {np.round(p_WE, 3).tolist()} is {distance:.3f} m from the first joint, "
                f"beyond the reach of {frame.name()} ({reach:.3f} m)",
            )

    @staticmethod
    def _within_tolerance(X_WE, p_WE, R_WE, options: IkOptions) -> bool:
        slack = 1.01
        if p_WE is not None and np.max(np.abs(X_WE.translation() - p_WE)) > (
            options.position_tolerance * slack + 1e-6
        ):
            return False
        if R_WE is not None:
            angle = (R_WE.inverse() @ X_WE.rotation()).ToAngleAxis().angle()
            if angle > options.orientation_tolerance * slack + 1e-6:
                return False
        return True
