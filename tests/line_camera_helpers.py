"""Shared set-up for the line-following camera tests: a course's floor, a camera on a body
posed over it, rendered headless by VTK, and the true line under the body."""

import dataclasses as dc
import math

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import RigidBody, SpatialInertia
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.sensors import RgbdSensorDiscrete

from drake_sim.systems.sensors.camera import CameraConfig, look_down_pose
from drake_sim.systems.sensors.camera import add_camera as add_camera_to
from drake_sim.worlds.course import Centreline, Course, centreline
from drake_sim.worlds.course_floor import add_course_floor

CAMERA = CameraConfig()
"""The default camera: 80 x 60 pixels, 80 degrees vertical field of view, 20 Hz."""

X_BC = look_down_pose([0.05, 0.0, 0.25], math.radians(60))
"""The camera 0.25 m above the ground frame's origin, 5 cm ahead, pitched 60 degrees down."""


@dc.dataclass
class LineScene:
    """A plant with a course's floor and a body carrying a camera."""

    diagram: Diagram
    plant: MultibodyPlant
    body: RigidBody
    camera: RgbdSensorDiscrete
    line: Centreline
    _context: object = None

    def render(self, X_WB: RigidTransform) -> np.ndarray:
        """Returns the (h, w, 4) uint8 image the camera takes with its body at X_WB (the body
        must be free)."""
        if self._context is None:  # one context: each new one copies the renderer
            self._context = self.diagram.CreateDefaultContext()
        context = self._context
        self.plant.SetFreeBodyPose(self.plant.GetMyContextFromRoot(context), self.body, X_WB)
        sensor = self.camera.sensor()
        image = sensor.color_image_output_port().Eval(sensor.GetMyContextFromRoot(context))
        return np.array(image.data)


def make_scene(
    course: Course,
    *,
    X_WB: RigidTransform | None = None,
    camera: CameraConfig = CAMERA,
    X_BC: RigidTransform = X_BC,
    extend=None,
) -> LineScene:
    """Builds the scene: the body is free (pose it with ``render``) unless ``X_WB`` welds it.
    ``extend(builder, scene)`` may add systems before the diagram is built."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    add_course_floor(plant, course)
    body = plant.AddRigidBody("camera_body", SpatialInertia.SolidSphereWithMass(0.1, 0.02))
    if X_WB is not None:
        plant.WeldFrames(plant.world_frame(), body.body_frame(), X_WB)
    plant.Finalize()
    sensor = add_camera_to(
        builder,
        plant=plant,
        scene_graph=scene_graph,
        frame=body.body_frame(),
        X_FC=X_BC,
        config=camera,
    )
    scene = LineScene(None, plant, body, sensor, centreline(course))
    if extend is not None:
        extend(builder, scene)
    scene.diagram = builder.Build()
    return scene


def pose_near_line(line: Centreline, s: float, lateral: float = 0.0, yaw: float = 0.0):
    """X_WB of a body on the floor at arc length ``s``, ``lateral`` m to the left of the line,
    turned ``yaw`` rad to the left of the line's direction."""
    p, heading = line.pose_at(s)
    left = np.array([-math.sin(heading), math.cos(heading)])
    q = p + lateral * left
    return RigidTransform(RollPitchYaw(0.0, 0.0, heading + yaw), [q[0], q[1], 0.0])


def true_line(line: Centreline, X_WB: RigidTransform) -> tuple[float, float]:
    """The line's true (offset, heading) relative to the body's ground frame (see
    ``LineMeasurement``): offset positive when the line is on the body's left."""
    projection = line.project(X_WB.translation())
    R = X_WB.rotation().matrix()
    yaw = math.atan2(R[1, 0], R[0, 0])
    return -projection.offset, math.remainder(projection.heading - yaw, 2 * math.pi)
