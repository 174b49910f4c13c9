"""The colour camera (drake_sim.systems.sensors.camera), rendered headless by VTK."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Box
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import FixedOffsetFrame, SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import drake_sim.systems.sensors.camera as mut
from drake_sim.base.errors import ConfigError

WHITE = np.array([1.0, 1.0, 1.0, 1.0])


def _scene(config: mut.CameraConfig, X_FC: RigidTransform, *, mount_offset=None):
    """A white 0.2 m square 1 m along W's x axis, before a camera on a body at the origin (on a
    frame of that body at ``mount_offset`` if given)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    plant.RegisterVisualGeometry(
        plant.world_body(), RigidTransform([1.0, 0.0, 0.0]), Box(0.01, 0.2, 0.2), "square", WHITE
    )
    body = plant.AddRigidBody("mount", SpatialInertia.SolidSphereWithMass(0.1, 0.02))
    plant.WeldFrames(plant.world_frame(), body.body_frame())
    frame = body.body_frame()
    if mount_offset is not None:
        frame = plant.AddFrame(FixedOffsetFrame("camera_mount", frame, mount_offset))
    plant.Finalize()
    camera = mut.add_camera(
        builder, plant=plant, scene_graph=scene_graph, frame=frame, X_FC=X_FC, config=config
    )
    return builder.Build(), camera, scene_graph


def _image(diagram, camera, context=None) -> np.ndarray:
    context = context or diagram.CreateDefaultContext()
    sensor = camera.sensor()
    image = sensor.color_image_output_port().Eval(sensor.GetMyContextFromRoot(context))
    return np.array(image.data)[..., :3].mean(axis=-1)


def _square_pixels(grey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    bright = grey > 0.5 * (grey.max() + np.median(grey))
    return np.flatnonzero(bright.any(axis=0)), np.flatnonzero(bright.any(axis=1))


@pytest.mark.parametrize("size", [(80, 60), (81, 61), (160, 120)])
def test_images_are_centred_on_the_principal_point_of_camera_info(size):
    """A square on the optical axis lands symmetric about (w/2 - 0.5, h/2 - 0.5), Drake's
    documented principal point, to the pixel, with the size the field of view gives it."""
    config = mut.CameraConfig(width=size[0], height=size[1], fov_y=60.0)
    diagram, camera, _ = _scene(config, mut.look_down_pose([0.0, 0.0, 0.0], 0.0))
    grey = _image(diagram, camera)
    assert grey.shape == (size[1], size[0])
    columns, rows = _square_pixels(grey)
    info = mut.camera_info(config)
    assert columns.min() + columns.max() == pytest.approx(2 * info.center_x())
    assert rows.min() + rows.max() == pytest.approx(2 * info.center_y())
    half_width = 0.1 / 0.995 * info.focal_x()  # the square's near face is 0.995 m away
    assert (columns.max() - columns.min() + 1) / 2 == pytest.approx(half_width, abs=1.0)


def test_look_down_pose_axes():
    X_BC = mut.look_down_pose([0.1, 0.0, 0.3], math.radians(30))
    R = X_BC.rotation().matrix()
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    np.testing.assert_allclose(R[:, 2], [c, 0, -s], atol=1e-12)  # optical axis: ahead, down
    np.testing.assert_allclose(R[:, 0], [0, -1, 0], atol=1e-12)  # image right: B's right
    np.testing.assert_allclose(R[:, 1], [-s, 0, -c], atol=1e-12)  # image down
    np.testing.assert_allclose(X_BC.translation(), [0.1, 0.0, 0.3])
    straight_down = mut.look_down_pose([0, 0, 0], math.pi / 2).rotation().matrix()
    np.testing.assert_allclose(straight_down[:, 2], [0, 0, -1], atol=1e-12)


def test_the_camera_rides_on_an_offset_frame():
    """On a frame 1 m behind the body, pointing the other way: the square is behind the
    camera's view, so it sees only the background; turned back towards it, the square is
    there, smaller (2 m away)."""
    config = mut.CameraConfig(fov_y=60.0)
    away = RigidTransform(RotationMatrix.MakeZRotation(math.pi), [-1.0, 0.0, 0.0])
    X_FC = mut.look_down_pose([0.0, 0.0, 0.0], 0.0)
    diagram, camera, _ = _scene(config, X_FC, mount_offset=away)
    assert np.ptp(_image(diagram, camera)) == 0
    back = RigidTransform([-1.0, 0.0, 0.0])
    diagram, camera, _ = _scene(config, X_FC, mount_offset=back)
    columns, _ = _square_pixels(_image(diagram, camera))
    half_width = 0.1 / 1.995 * mut.camera_info(config).focal_x()
    assert (columns.max() - columns.min() + 1) / 2 == pytest.approx(half_width, abs=1.0)


def test_the_image_is_sampled_at_the_camera_rate():
    config = mut.CameraConfig(rate=25.0, fov_y=60.0)
    diagram, camera, scene_graph = _scene(config, mut.look_down_pose([0, 0, 0], 0.0))
    assert scene_graph.HasRenderer(config.renderer)
    assert camera.period() == pytest.approx(0.04)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    held = camera.color_image_output_port().Eval(camera.GetMyContextFromRoot(context))
    assert (held.width(), held.height()) == (80, 60)
    assert np.ptp(np.array(held.data)) == 0  # nothing sampled yet
    simulator.AdvanceTo(0.001)
    held = camera.color_image_output_port().Eval(camera.GetMyContextFromRoot(context))
    np.testing.assert_array_equal(
        np.array(held.data)[..., :3].mean(axis=-1), _image(diagram, camera)
    )


def test_a_second_camera_shares_the_renderer():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    plant.Finalize()
    for name in ("left", "right"):
        mut.add_camera(
            builder,
            plant=plant,
            scene_graph=scene_graph,
            frame=plant.world_frame(),
            X_FC=RigidTransform(),
            config=mut.CameraConfig(),
            name=name,
        )
    assert scene_graph.RendererCount() == 1


@pytest.mark.parametrize(
    "change, match",
    [
        ({"width": 0}, "'width' must be at least 1"),
        ({"height": -3}, "'height' must be at least 1"),
        ({"fov_y": 180.0}, "'fov_y' must be between"),
        ({"rate": 0.0}, "'rate' must be positive"),
        ({"near": 5.0}, "need 0 < 'near' < 'far'"),
    ],
)
def test_impossible_cameras_are_rejected(change, match):
    with pytest.raises(ConfigError, match=match):
        mut.check_camera_config(dc.replace(mut.CameraConfig(), **change))
