"""The robot alone, welded in place, for looking at it (the robot_state_publisher + RViz view)."""

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.multibody.meshcat import JointSliders
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import Diagram, DiagramBuilder

from diagrams.ddrive_world import ROBOT_NAME, add_link_frames, robot_start_pose
from diagrams.world_scenario import PlanarPose
from drake_sim.robots.ddrive import BODY_LINK, add_robot
from drake_sim.robots.ddrive_params import RobotParams


def make_ddrive_model_diagram(
    robot: RobotParams,
    *,
    meshcat: Meshcat | None = None,
    frame_triad_length: float = 0.15,
    joint_sliders: bool = False,
) -> Diagram:
    """Builds a continuous-time plant holding only the robot, its body welded where it would
    stand at the origin, so its joints (the two wheels) can be posed by hand.

    Ports: none exported; pose the wheels through the plant's context (e.g. JointSliders).

    Args:
        robot: the robot's dimensions.
        meshcat: where to draw (illustration and collision geometry), or None.
        frame_triad_length: length of the frame triads on each link, m; 0 hides them.
        joint_sliders: add a Meshcat slider per wheel joint (a ``JointSliders`` system named
            ``joint_sliders``; ``drake_sim.view`` polls it in a loop that Ctrl-C can stop).
            Needs ``meshcat``.
    """
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    instance = add_robot(plant, robot, name=ROBOT_NAME)
    plant.WeldFrames(
        plant.world_frame(),
        plant.GetFrameByName(BODY_LINK, instance),
        robot_start_pose(PlanarPose(), robot),
    )
    plant.Finalize()
    add_link_frames(plant, scene_graph, instance, frame_triad_length)
    if meshcat is not None:
        MeshcatVisualizer.AddToBuilder(
            builder, scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration)
        )
        MeshcatVisualizer.AddToBuilder(
            builder,
            scene_graph,
            meshcat,
            MeshcatVisualizerParams(
                role=Role.kProximity, prefix="collision", visible_by_default=False
            ),
        )
    if joint_sliders:
        if meshcat is None:
            raise ValueError("joint_sliders needs a Meshcat")
        sliders = JointSliders(meshcat, plant, lower_limit=-np.pi, upper_limit=np.pi, step=0.01)
        builder.AddNamedSystem("joint_sliders", sliders)
    diagram = builder.Build()
    diagram.set_name("ddrive_model")
    return diagram
