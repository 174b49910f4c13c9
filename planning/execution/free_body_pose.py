"""A free body's pose from its positions: the LeafSystem behind the Panda station's
``object.pose`` output (the object's plant state in ``physics`` mode, its commanded positions in
``kinematic`` mode), which the interface reads to know where the object is."""

from pydrake.common.value import Value
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from planning.scene_objects import FREE_BODY_POSITIONS, free_body_pose


class FreeBodyPose(LeafSystem):
    """Outputs a free body's pose from its positions [qw, qx, qy, qz, x, y, z].

    .. pydrake_system::

        name: FreeBodyPose
        input_ports:
        - positions
        output_ports:
        - pose

    ``positions`` is a vector whose first 7 entries are the body's quaternion (w, x, y, z) and
    position p_WB (m), e.g. a plant's state output port of a model instance holding one free
    body (13 values); ``pose`` is the abstract RigidTransform X_WB. Evaluated on demand only.
    """

    def __init__(self, *, input_size: int = 7):
        super().__init__()
        if input_size < 7:
            raise ValueError(f"positions needs at least 7 values, got input_size={input_size}")
        self._input = self.DeclareVectorInputPort("positions", input_size)
        self.DeclareAbstractOutputPort("pose", lambda: Value(RigidTransform()), self.CalcPose)

    def CalcPose(self, context, output) -> None:
        output.set_value(free_body_pose(self._input.Eval(context)[:FREE_BODY_POSITIONS]))
