"""RobotState: a robot's joints, forward and inverse kinematics, and live state from a diagram.

``RobotState`` holds a current configuration (like MoveIt's ``RobotState``) on a
``PlanningScene``. ``RobotStateReader`` is a LeafSystem that a running diagram feeds with the
robot's positions (or its full state), in the order of the scene's plant (the Panda's: 7 arm
joints, then 2 fingers); ``RobotState.read(root_context)`` then returns the latest joints, and
``RobotState.read_plant_context`` does the same from any plant context that holds the robot.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import Value
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import LeafSystem

from planning.config import IkOptions
from planning.errors import ErrorCode, PlanningError
from planning.search.ik import IkResult, IkSolver


class RobotStateReader(LeafSystem):
    """Receives the robot's positions from a running diagram and outputs the end-effector pose.

    .. pydrake_system::

        name: RobotStateReader
        input_ports:
        - panda_state
        output_ports:
        - q
        - X_WE

    ``panda_state`` (the name kept from the Panda's stations) is a vector whose first N entries
    are the positions of ``plant`` (N = ``plant.num_positions()``: the Panda's 7 arm joints in
    rad and 2 fingers in m), e.g. a station's ``panda.state`` output (positions then
    velocities, 2N values, the default ``input_size``) or N positions; ``q`` passes those N
    through and ``X_WE`` (an abstract RigidTransform) is the pose of the end-effector frame E
    in the world frame W.
    """

    def __init__(self, *, plant, frame, input_size: int | None = None):
        super().__init__()
        n = plant.num_positions()
        input_size = 2 * n if input_size is None else input_size
        if input_size < n:
            raise ValueError(f"panda_state needs at least {n} values, got input_size={input_size}")
        self._n = n
        self._plant = plant
        self._frame = frame
        self._plant_context = plant.CreateDefaultContext()
        self._input = self.DeclareVectorInputPort("panda_state", input_size)
        self.DeclareVectorOutputPort("q", n, self.CalcQ)
        self.DeclareAbstractOutputPort("X_WE", lambda: Value(RigidTransform()), self.CalcPose)

    def CalcQ(self, context, output) -> None:
        output.SetFromVector(self._input.Eval(context)[: self._n])

    def CalcPose(self, context, output) -> None:
        self._plant.SetPositions(self._plant_context, self._input.Eval(context)[: self._n])
        output.set_value(self._frame.CalcPoseInWorld(self._plant_context))


class RobotState:
    """A configuration of the scene's robot (its planning group), with kinematics.

    Args:
        scene: the ``PlanningScene`` (robot model, objects, collision checker).
        q: the initial configuration (the group's joints, or all of the plant's positions); the
            model's ``home`` ("ready" for the Panda) when None.
        ik_options: IK options; the scene configuration's ``ik`` when None.
    """

    def __init__(self, scene, q=None, *, ik_options: IkOptions | None = None):
        self._scene = scene
        self._ik_options = ik_options or scene.config.ik
        self._ee_frame = scene.model.ee_frame
        self._q = scene.full_q(scene.model.home if q is None else q)
        self._context = scene.plant.CreateDefaultContext()
        self._ik = None
        self._reader = None

    @property
    def scene(self):
        return self._scene

    @property
    def q(self) -> np.ndarray:
        """The 7 arm joints of the current configuration, rad."""
        return self._scene.arm_q(self._q)

    @property
    def q_full(self) -> np.ndarray:
        """All 9 plant positions (arm joints in rad, then the fingers in m)."""
        return self._q.copy()

    def set_q(self, q) -> None:
        """Sets the current configuration (7 values, fingers from the scene, or 9)."""
        self._q = self._scene.full_q(q)

    def named(self, name: str) -> np.ndarray:
        """Returns a named arm configuration (7 joints, rad), from the YAML or the SRDF.

        Raises:
            PlanningError: INVALID_GOAL for an unknown name.
        """
        named = self._scene.model.named_configurations
        if name not in named:
            raise PlanningError(
                ErrorCode.INVALID_GOAL, f"no named configuration {name!r}; known: {sorted(named)}"
            )
        return named[name].copy()

    def fk(self, q=None, frame: str | None = None) -> RigidTransform:
        """Returns X_WF, the pose of a frame F of the robot (the end effector by default) at q.

        Args:
            q: the group's positions or all of the plant's (the Panda's 7 or 9); the current
                configuration when None.
            frame: a frame name of the robot, e.g. the Panda's "panda_hand" or "panda_link7".
        """
        plant, scene = self._scene.plant, self._scene
        name = frame or self._ee_frame
        if not plant.HasFrameNamed(name, scene.model.instance):
            message = f"the robot {scene.model.robot.name} has no frame {name!r}"
            raise PlanningError(ErrorCode.FRAME_NOT_FOUND, message)
        plant.SetPositions(self._context, self._q if q is None else scene.full_q(q))
        return plant.GetFrameByName(name, scene.model.instance).CalcPoseInWorld(self._context)

    def hand_pose(self, q=None) -> RigidTransform:
        """Returns X_WE of the end-effector frame E (``model.ee_frame``) at q or the current q."""
        return self.fk(q)

    def ik(
        self,
        X_WE: RigidTransform | None = None,
        *,
        p_WE=None,
        R_WE: RotationMatrix | None = None,
        q_seed=None,
        frame: str | None = None,
        options: IkOptions | None = None,
    ) -> IkResult:
        """Solves IK for a full pose, a position alone, or an orientation alone.

        With ``X_WE`` both are constrained; with only ``p_WE`` the orientation is free, with only
        ``R_WE`` the position is free. With no target at all, the target is the current pose.
        Does not change the current configuration.

        Args:
            X_WE: target pose of frame E in the world frame W.
            p_WE: target position of E's origin, m (when ``X_WE`` is None).
            R_WE: target orientation of E (when ``X_WE`` is None).
            q_seed: start of the first attempt; the current configuration when None.
            frame: the frame E; the end effector (``model.ee_frame``) when None.
            options: overrides this state's IK options.

        Raises:
            PlanningError: NO_IK_SOLUTION, INVALID_GOAL or FRAME_NOT_FOUND.
        """
        if X_WE is not None:
            if p_WE is not None or R_WE is not None:
                raise PlanningError(ErrorCode.INVALID_GOAL, "give X_WE or p_WE/R_WE, not both")
            p_WE, R_WE = X_WE.translation(), X_WE.rotation()
        elif p_WE is None and R_WE is None:
            X_WE = self.fk(frame=frame)
            p_WE, R_WE = X_WE.translation(), X_WE.rotation()
        return self.ik_solver().solve(
            frame or self._ee_frame,
            p_WE=p_WE,
            R_WE=R_WE,
            q_seed=self._q if q_seed is None else q_seed,
            options=options or self._ik_options,
        )

    def ik_solver(self) -> IkSolver:
        """This state's IK solver, made on the first call (it allocates a collision-checker
        context, a few milliseconds, and loads the compiled Newton steps, about 0.4 s, or
        compiles them once per machine: ``MotionPlanner`` calls this when it is made, so that
        no request pays for it)."""
        if self._ik is None:
            self._ik = IkSolver(self._scene)
        return self._ik

    def make_reader(self, input_size: int | None = None) -> RobotStateReader:
        """Returns a new ``RobotStateReader`` to add to a diagram (``input_size``: the
        positions and velocities of the scene's plant when None); ``read`` uses it after."""
        plant = self._scene.plant
        frame = plant.GetFrameByName(self._ee_frame, self._scene.model.instance)
        self._reader = RobotStateReader(plant=plant, frame=frame, input_size=input_size)
        return self._reader

    def read(self, root_context) -> tuple[np.ndarray, RigidTransform]:
        """Reads the latest configuration from the running diagram through the reader.

        Sets the current configuration and returns (q, X_WE): the group's joints (rad or m) and
        the end-effector pose.
        """
        if self._reader is None:
            raise RuntimeError("call make_reader() and wire its panda_state port first")
        context = self._reader.GetMyContextFromRoot(root_context)
        self.set_q(self._reader.GetOutputPort("q").Eval(context))
        return self.q, self._reader.GetOutputPort("X_WE").Eval(context)

    def read_plant_context(self, plant, plant_context, model_instance=None):
        """Reads the robot's positions from a plant's context (any plant holding the robot).

        Args:
            plant: the plant; its robot is ``model_instance`` or the instance named as in the
                scene's plant ("panda" for the Panda).
            plant_context: that plant's context.

        Returns:
            (q, X_WE) as ``read``.
        """
        if model_instance is None:
            ours = self._scene.plant
            model_instance = plant.GetModelInstanceByName(
                ours.GetModelInstanceName(self._scene.model.instance)
            )
        n = self._scene.plant.num_positions()
        self.set_q(plant.GetPositions(plant_context, model_instance)[:n])
        return self.q, self.fk()
