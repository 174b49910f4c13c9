"""The LineDetector system (drake_sim.systems.perception.line_detector) in a simulated diagram:
a welded camera over the oval's floor, VTK rendering, the detector at the camera's rate."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.common.value import Value
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.primitives import ConstantValueSource

import drake_sim.systems.perception.line_detector as mut
from drake_sim.base.errors import ConfigError
from drake_sim.systems.perception.line_detection import (
    LineDetectorConfig,
    LineMeasurement,
    camera_pose_over_ground,
)
from drake_sim.worlds.course import centreline, load_course, shipped_courses
from tests.line_camera_helpers import CAMERA, X_BC, make_scene, pose_near_line, true_line

CONFIG = LineDetectorConfig()
OVAL = centreline(load_course(shipped_courses()[0]))


def _run(X_WB, *, camera_pose=None, camera=CAMERA):
    """Builds the diagram with the body welded at X_WB; returns (scene, simulator)."""
    course = load_course(shipped_courses()[0])

    def add_detector(builder, scene):
        dut = builder.AddNamedSystem(
            "line_detector",
            mut.LineDetector(
                camera=camera, X_GC=camera_pose_over_ground(X_WB, X_BC), config=CONFIG
            ),
        )
        builder.Connect(scene.camera.color_image_output_port(), dut.GetInputPort("color_image"))
        if camera_pose is not None:
            source = builder.AddSystem(ConstantValueSource(Value(camera_pose)))
            builder.Connect(source.get_output_port(), dut.GetInputPort("camera_pose"))
        builder.ExportOutput(dut.GetOutputPort("measurement"), "measurement")

    scene = make_scene(course, X_WB=X_WB, camera=camera, extend=add_detector)
    return scene, Simulator(scene.diagram)


def _measurement(scene, simulator) -> LineMeasurement:
    port = scene.diagram.GetOutputPort("measurement")
    return mut.LineDetector.measurement(port.Eval(simulator.get_context()))


def test_it_measures_each_frame_a_little_after_the_camera_takes_it():
    X_WB = pose_near_line(OVAL, 0.8, -0.03, 0.2)
    scene, simulator = _run(X_WB)
    assert not _measurement(scene, simulator).found  # nothing yet
    simulator.AdvanceTo(0.9 * CONFIG.delay)
    assert not _measurement(scene, simulator).found  # the first frame is being processed
    simulator.AdvanceTo(1.1 * CONFIG.delay)
    m = _measurement(scene, simulator)
    offset, heading = true_line(scene.line, X_WB)
    assert m.found
    assert m.offset == pytest.approx(offset, abs=0.003)
    assert m.heading == pytest.approx(heading, abs=math.radians(1))
    assert m.distance > 0
    simulator.AdvanceTo(0.3)
    assert _measurement(scene, simulator) == m  # nothing moves: the same every frame


def test_the_camera_pose_input_replaces_the_fixed_one():
    """Told the camera is twice as high as it is, the detector sees the line twice as far."""
    X_WB = pose_near_line(OVAL, 0.8, -0.03, 0.0)
    X_GC = camera_pose_over_ground(X_WB, X_BC)
    wrong = RigidTransform(X_GC.rotation(), X_GC.translation() * [1.0, 1.0, 2.0])
    scene, simulator = _run(X_WB, camera_pose=wrong)
    simulator.AdvanceTo(0.01)
    m = _measurement(scene, simulator)
    assert m.found and m.offset == pytest.approx(2 * 0.03, abs=0.006)


def test_off_the_line_it_reports_not_found():
    X_WB = RigidTransform(RollPitchYaw(0.0, 0.0, -math.pi / 2), [0.7, -0.25, 0.0])
    scene, simulator = _run(X_WB)
    simulator.AdvanceTo(0.01)
    vector = scene.diagram.GetOutputPort("measurement").Eval(simulator.get_context())
    np.testing.assert_array_equal(vector, np.zeros(mut.MEASUREMENT_SIZE))


def test_the_measurement_vector_round_trips():
    m = LineMeasurement(True, offset=-0.02, heading=0.1, curvature=2.0, distance=0.3)
    vector = mut.measurement_vector(m)
    assert vector[mut.FOUND] == 1.0 and vector[mut.CURVATURE] == 2.0
    assert mut.LineDetector.measurement(vector) == m


def test_a_delay_longer_than_a_frame_is_refused():
    with pytest.raises(ConfigError, match="'delay' must be less than a frame"):
        mut.LineDetector(
            camera=CAMERA, X_GC=RigidTransform(), config=dc.replace(CONFIG, delay=0.05)
        )
