"""A colour camera on a body: Drake's ``RgbdSensorDiscrete`` rendered by ``RenderEngineVtk``.

VTK renders headless here (``RenderEngineGl`` needs a display), so tests and headless runs see
the same images as interactive ones.

Camera frame convention (Drake's): the camera frame C has its origin at the optical centre, +z
along the optical axis (forward, into the scene), +x to the right of the image and +y down it;
pixel (u, v) = (column, row) from the image's top-left corner. ``look_down_pose`` builds the
pose X_BC of a camera that looks forward and down from a body frame B whose x axis points
forward, y left and z up.

For following a line on the floor the defaults (80 x 60 pixels, 80 degrees vertical field of
view, 20 Hz) mounted about 0.25 m above the floor and pitched 60 degrees down
(``look_down_pose([0.05, 0, 0.25 - z_B], math.radians(60))`` on a body whose origin is z_B
above the floor) see the floor from just ahead of the robot to about 0.7 m ahead, and 0.75 m
wide at 0.3 m ahead. Rendering one frame costs about 4 ms here.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.geometry import (
    ClippingRange,
    ColorRenderCamera,
    DepthRange,
    DepthRenderCamera,
    MakeRenderEngineVtk,
    RenderCameraCore,
    RenderEngineVtkParams,
    SceneGraph,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.sensors import CameraInfo, RgbdSensor, RgbdSensorDiscrete

from drake_sim.base.errors import ConfigError


@dc.dataclass
class CameraConfig:
    """A small colour camera: image size, field of view, frame rate and clipping planes."""

    width: int = 80  # pixels.
    height: int = 60  # pixels.
    fov_y: float = 80.0  # degrees, vertical field of view (square pixels: 96 degrees across).
    rate: float = 20.0  # Hz, frames a second.
    near: float = 0.02  # m, nearest distance rendered.
    far: float = 4.0  # m, farthest distance rendered.
    renderer: str = "vtk"  # name of the SceneGraph renderer (a RenderEngineVtk).


def check_camera_config(config: CameraConfig, where: str = "camera") -> CameraConfig:
    """Returns ``config`` if its values make a camera; raises ``ConfigError`` naming the key."""
    for key in ("width", "height"):
        if getattr(config, key) < 1:
            raise ConfigError(f"{where}: '{key}' must be at least 1 pixel")
    if not 0.0 < config.fov_y < 180.0:
        raise ConfigError(f"{where}: 'fov_y' must be between 0 and 180 degrees")
    if not config.rate > 0.0:
        raise ConfigError(f"{where}: 'rate' must be positive")
    if not 0.0 < config.near < config.far:
        raise ConfigError(f"{where}: need 0 < 'near' < 'far'")
    return config


RENDER_PRINCIPAL_POINT_SHIFT = 0.5
"""Pixels added to the principal point given to ``RenderEngineVtk``, measured here (Drake 1.51):
VTK draws the principal point half a pixel up and left of the one it is given, so without this
a scene symmetric about the optical axis renders centred on pixel (w/2 - 1, h/2 - 1) instead of
(w/2 - 0.5, h/2 - 0.5). With it, the images follow ``camera_info`` (``test_camera`` checks)."""


def camera_info(config: CameraConfig) -> CameraInfo:
    """Returns the pinhole intrinsics of the images (Drake's convention: the centre of the top-left
    pixel is (u, v) = (0, 0); the principal point is the image's centre, (w/2 - 0.5, h/2 - 0.5))."""
    return CameraInfo(config.width, config.height, math.radians(config.fov_y))


def _render_info(config: CameraConfig) -> CameraInfo:
    """The intrinsics to give the renderer so that its images follow ``camera_info``."""
    info = camera_info(config)
    shift = RENDER_PRINCIPAL_POINT_SHIFT
    return CameraInfo(
        info.width(),
        info.height(),
        info.focal_x(),
        info.focal_y(),
        info.center_x() + shift,
        info.center_y() + shift,
    )


def look_down_pose(p_BC, pitch_down: float) -> RigidTransform:
    """Returns X_BC of a camera at ``p_BC`` (m, in B) looking along B's +x axis tilted
    ``pitch_down`` (rad) towards B's -z axis, with the image's right (C's +x) along B's -y.

    B is a body frame with x forward, y left and z up; C is Drake's camera frame.
    """
    c, s = math.cos(pitch_down), math.sin(pitch_down)
    Cz = np.array([c, 0.0, -s])  # optical axis
    Cx = np.array([0.0, -1.0, 0.0])  # image right
    Cy = np.cross(Cz, Cx)  # image down
    return RigidTransform(RotationMatrix(np.column_stack([Cx, Cy, Cz])), np.asarray(p_BC, float))


def ensure_vtk_renderer(scene_graph: SceneGraph, name: str) -> None:
    """Adds a ``RenderEngineVtk`` called ``name`` to ``scene_graph`` unless it has one."""
    if not scene_graph.HasRenderer(name):
        scene_graph.AddRenderer(name, MakeRenderEngineVtk(RenderEngineVtkParams()))


def add_camera(
    builder: DiagramBuilder,
    *,
    plant: MultibodyPlant,
    scene_graph: SceneGraph,
    frame: Frame,
    X_FC: RigidTransform,
    config: CameraConfig,
    name: str = "camera",
) -> RgbdSensorDiscrete:
    """Adds a camera rigidly attached to ``frame`` at ``X_FC``, rendering at ``config.rate``.

    The camera renders everything with a perception role (``plant.RegisterVisualGeometry``
    gives one) through the VTK renderer ``config.renderer``, added to ``scene_graph`` if it is
    not there yet. The sensor's ``query_object`` input is connected to the scene graph.

    Args:
        builder: the diagram builder holding ``plant`` and ``scene_graph``.
        plant: the finalised MultibodyPlant whose frame carries the camera.
        scene_graph: the plant's SceneGraph.
        frame: a frame of ``plant`` (a body frame or one fixed to a body).
        X_FC: the camera frame C's pose in ``frame`` (see the module's convention).
        config: the camera's settings.
        name: the sensor's system name.

    Returns:
        The ``RgbdSensorDiscrete``: its ``color_image`` output (an ``ImageRgba8U`` of
        ``config.height`` x ``config.width`` pixels) is sampled and held every
        ``1 / config.rate`` s from t = 0; ``depth_image_32f`` likewise (no label image).
    """
    check_camera_config(config, name)
    ensure_vtk_renderer(scene_graph, config.renderer)
    body = frame.body()
    X_PC = frame.GetFixedPoseInBodyFrame() @ X_FC
    core = RenderCameraCore(
        config.renderer,
        _render_info(config),
        ClippingRange(config.near, config.far),
        RigidTransform(),
    )
    sensor = RgbdSensor(
        plant.GetBodyFrameIdOrThrow(body.index()),
        X_PC,
        ColorRenderCamera(core, False),
        DepthRenderCamera(core, DepthRange(config.near * 1.001, config.far * 0.999)),
    )
    discrete = builder.AddNamedSystem(
        name, RgbdSensorDiscrete(sensor, 1.0 / config.rate, render_label_image=False)
    )
    builder.Connect(scene_graph.get_query_output_port(), discrete.query_object_input_port())
    return discrete
