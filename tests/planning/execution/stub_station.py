"""A stub Panda station for the execution tests: its state is exactly the position command, at
rest, so actions end at times that follow from the commands alone."""

import numpy as np
from pydrake.systems.framework import DiagramBuilder, LeafSystem


class PerfectTracking(LeafSystem):
    """The Panda's state is the position command (9 values) and zero velocities."""

    def __init__(self):
        super().__init__()
        self.DeclareVectorInputPort("u", 9)
        self.DeclareVectorOutputPort("x", 18, self.CalcState)

    def CalcState(self, context, output):
        output.SetFromVector(np.concatenate([self.get_input_port().Eval(context), np.zeros(9)]))


def started_interface(scene, options=None):
    """A ``MotionPlanningInterface`` on ``scene`` joined to a ``PerfectTracking`` station and
    started at simulated time 0."""
    from planning.interface import MotionPlanningInterface

    station_builder = DiagramBuilder()
    arm = station_builder.AddSystem(PerfectTracking())
    station_builder.ExportInput(arm.get_input_port(), "panda.position_command")
    station_builder.ExportOutput(arm.get_output_port(), "panda.state")
    builder = DiagramBuilder()
    station = builder.AddSystem(station_builder.Build())
    interface = MotionPlanningInterface(scene, options=options)
    interface.add_to_builder(builder, station)
    interface.start(builder.Build())
    return interface
