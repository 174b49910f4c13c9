"""Line detection (drake_sim.systems.perception.line_detection): the pieces on made-up data, then
the whole on images VTK renders of the shipped courses, against the true line."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

import drake_sim.systems.perception.line_detection as mut
from drake_sim.base.errors import ConfigError
from drake_sim.systems.sensors.camera import camera_info, look_down_pose
from drake_sim.worlds.course import load_course, shipped_courses
from tests.line_camera_helpers import CAMERA, X_BC, make_scene, pose_near_line, true_line

CONFIG = mut.LineDetectorConfig()
INFO = camera_info(CAMERA)
DEG = math.pi / 180


@pytest.fixture(scope="module")
def oval():
    return make_scene(load_course(shipped_courses()[0]))


@pytest.fixture(scope="module")
def tight():
    return make_scene(load_course(shipped_courses()[2]))


def _detect(scene, X_WB, image=None):
    image = scene.render(X_WB) if image is None else image
    return mut.detect_line(image, INFO, mut.camera_pose_over_ground(X_WB, X_BC), CONFIG)


def test_camera_pose_over_ground_keeps_pitch_and_height_but_not_yaw_or_place():
    X_WB = RigidTransform(RollPitchYaw(0.0, 0.1, 2.0), [3.0, -1.0, 0.2])
    X_GC = mut.camera_pose_over_ground(X_WB, X_BC)
    X_GB = RigidTransform(RollPitchYaw(0.0, 0.1, 0.0), [0.0, 0.0, 0.2])
    assert X_GC.IsNearlyEqualTo(X_GB @ X_BC, 1e-12)


def test_ground_points_back_project_through_the_pinhole():
    X_GC = mut.camera_pose_over_ground(RigidTransform(), X_BC)
    points, area = mut.ground_points(INFO, X_GC, max_range=10.0)
    assert points.shape == (INFO.height(), INFO.width(), 2)
    # The optical axis (60 degrees down from 0.25 m, 5 cm ahead) meets the floor here, between
    # the four middle pixels.
    middle = points[29:31, 39:41].reshape(4, 2).mean(axis=0)
    np.testing.assert_allclose(middle, [0.05 + 0.25 / math.tan(60 * DEG), 0.0], atol=2e-3)
    assert np.all(points[:, :40, 1] > points[:, 40:, 1][:, ::-1])  # image left is G's left
    assert np.all(np.diff(points[:, 40, 0]) < 0)  # rows further down are nearer
    assert area[0, 40] > 20 * area[-1, 40]  # far pixels cover more floor
    level = mut.camera_pose_over_ground(RigidTransform(), look_down_pose([0, 0, 0.25], 0.0))
    points, area = mut.ground_points(INFO, level, max_range=10.0)
    assert np.all(np.isnan(points[:30])) and np.all(np.isfinite(points[31:]))  # horizon
    points, area = mut.ground_points(INFO, X_GC, max_range=0.4)
    assert np.nanmax(np.hypot(points[..., 0], points[..., 1])) <= 0.4
    assert np.array_equal(np.isnan(area), np.isnan(points[..., 0]))


def test_components_are_eight_connected():
    mask = np.zeros((6, 8), bool)
    mask[0, 0] = mask[1, 1] = mask[2, 2] = True  # a diagonal: one piece
    mask[0, 5:8] = mask[1, 5] = mask[2, 4:6] = True  # a hook: one piece
    mask[5, 0:3] = True
    mask[4, 6:8] = mask[5, 7] = True  # a U (joins as the rows go down)
    mask[3, 7] = mask[4, 4] = True  # touching the U, and a lone pixel
    labels = mut.label_components(mask)
    assert labels[0, 0] == labels[2, 2] and labels[0, 5] == labels[2, 4]
    assert len({labels[0, 0], labels[0, 5], labels[5, 0], labels[4, 6], labels[4, 4]}) == 5
    assert labels[3, 7] == labels[5, 7]
    assert np.array_equal(labels > 0, mask) and labels.max() == 5


def test_line_pixels_need_contrast_and_grey_and_drop_isolated_specks():
    image = np.full((60, 80, 3), 12, np.uint8)
    mask, _, reason = mut.line_pixels(image, CONFIG)
    assert reason.startswith("no line: contrast 0") and not mask.any()
    image[:, 38:42] = 200
    image[10, 10] = image[20, 60:62] = 255  # a speck and a pair: noise
    image[40:50, 5:15] = (90, 160, 250)  # bright but blue: not a white line
    mask, weight, reason = mut.line_pixels(image, CONFIG)
    assert reason == ""
    assert np.array_equal(np.flatnonzero(mask.any(axis=0)), np.arange(38, 42))
    assert weight[0, 39] == 1.0 and weight[0, 0] == 0.0


def test_a_circle_fit_recovers_curvature_and_extrapolates_to_the_robot():
    """Points of a circle of radius 0.5 m ahead of the robot, which stands on the same circle:
    the measurement at the robot is on the line, along it, turning left at 2 /m."""
    angles = np.linspace(0.3, 1.2, 200)  # the robot is at angle 0, heading +y... turned below
    circle = np.column_stack([0.5 * np.sin(angles), 0.5 - 0.5 * np.cos(angles)])
    p0, v, t0 = mut.fit_curve(circle, np.ones(len(circle)), CONFIG)
    np.testing.assert_allclose(p0, circle[0])
    assert abs(2 * v[0]) == pytest.approx(2.0, rel=1e-6)
    m = mut._at_robot(p0, v, t0, float(np.hypot(*p0)))
    assert (m.offset, m.heading, m.curvature) == pytest.approx((0.0, 0.0, 2.0), abs=1e-6)
    straight = np.column_stack([np.linspace(0.2, 0.6, 50), np.full(50, -0.03)])
    p0, v, t0 = mut.fit_curve(straight, np.ones(50), CONFIG)
    m = mut._at_robot(p0, v, t0, float(np.hypot(*p0)))
    assert (m.offset, m.heading, m.curvature) == pytest.approx((-0.03, 0.0, 0.0), abs=1e-9)


@pytest.mark.parametrize(
    "lateral, yaw",
    [(0.0, 0.0), (0.04, 0.0), (-0.04, 0.0), (0.0, 20 * DEG), (0.02, -25 * DEG), (-0.1, 0.3)],
)
def test_on_a_straight_the_offset_and_heading_are_recovered(oval, lateral, yaw):
    """On the oval's first straight: the robot on the line, beside it (left, right), turned."""
    X_WB = pose_near_line(oval.line, 0.6, lateral, yaw)
    m = _detect(oval, X_WB)
    offset, heading = true_line(oval.line, X_WB)
    assert m.found, m.reason
    assert m.offset == pytest.approx(offset, abs=0.003)
    assert m.heading == pytest.approx(heading, abs=1.0 * DEG)
    assert abs(m.curvature) < 0.2


@pytest.mark.parametrize("s, radius", [(1.5 + 0.8, 0.5), (5.0 - 0.2, 0.5)])
def test_in_a_curve_the_curvature_is_measured(oval, s, radius):
    X_WB = pose_near_line(oval.line, s, 0.02, 0.1)
    m = _detect(oval, X_WB)
    offset, heading = true_line(oval.line, X_WB)
    assert m.found, m.reason
    assert m.offset == pytest.approx(offset, abs=0.004)
    assert m.heading == pytest.approx(heading, abs=1.5 * DEG)
    assert m.curvature == pytest.approx(1 / radius, rel=0.15)


@pytest.mark.parametrize("s, curvature", [(1.8, 1 / 0.3), (3.98, -1 / 0.25)])
def test_in_the_tight_courses_turns(tight, s, curvature):
    """Early in a 0.3 m left corner and in the chicane's 0.25 m right turn."""
    X_WB = pose_near_line(tight.line, s, -0.01, 0.0)
    m = _detect(tight, X_WB)
    offset, heading = true_line(tight.line, X_WB)
    assert m.found, m.reason
    assert m.offset == pytest.approx(offset, abs=0.006)
    assert m.heading == pytest.approx(heading, abs=3 * DEG)
    assert m.curvature == pytest.approx(curvature, rel=0.2)


def test_approaching_a_corner_the_curve_ahead_is_seen(tight):
    """0.1 m before the first corner, on the straight: the camera already sees the corner, so
    the curvature is that of the turn ahead. The circle through what it sees passes near the
    robot, turned a little right to meet the corner: the price of seeing only ahead."""
    X_WB = pose_near_line(tight.line, 1.7 - 0.1, 0.0, 0.0)
    m = _detect(tight, X_WB)
    assert m.found and m.curvature > 2.0
    assert abs(m.offset) < 0.01 and -15 * DEG < m.heading < 0.0


@pytest.mark.parametrize(
    "where",
    [
        RigidTransform(RollPitchYaw(0, 0, -math.pi / 2), [0.7, -0.25, 0.0]),  # facing off the floor
        RigidTransform(RollPitchYaw(0, 0, 0.0), [2.3, 0.5, 0.0]),  # past the loop, facing out
    ],
)
def test_off_the_line_it_is_not_found(oval, where):
    m = _detect(oval, where)
    assert not m.found and m.reason
    assert (m.offset, m.heading, m.curvature) == (0.0, 0.0, 0.0)


def test_the_nearest_piece_of_line_is_the_one_measured(oval):
    """In the middle of the oval, turned 45 degrees to the bottom straight: the top straight may
    be in view too, but the measurement is the nearer line's."""
    X_WB = RigidTransform(RollPitchYaw(0, 0, -45 * DEG), [0.75, 0.3, 0.0])
    m = _detect(oval, X_WB)
    offset, heading = true_line(oval.line, X_WB)
    assert m.found and m.offset == pytest.approx(offset, abs=0.01)
    assert m.heading == pytest.approx(heading, abs=2 * DEG)


def test_noise_and_a_pitched_body_barely_matter(oval):
    """Gaussian noise (10 grey levels), 1 % salt and pepper, and the body pitched 5 degrees
    forward (its camera pose over the ground follows)."""
    X_WB = pose_near_line(oval.line, 1.0, 0.03, 0.15) @ RigidTransform(
        RollPitchYaw(0.0, 5 * DEG, 0.0), [0.0, 0.0, 0.0]
    )
    image = oval.render(X_WB)
    rng = np.random.default_rng(7)
    noisy = image[..., :3] + rng.normal(0.0, 10.0, image[..., :3].shape)
    speck = rng.random(image.shape[:2])
    noisy[speck < 0.01], noisy[speck > 0.99] = 255, 0
    m = _detect(oval, X_WB, np.clip(noisy, 0, 255).astype(np.uint8))
    offset, heading = true_line(oval.line, X_WB)
    assert m.found and m.offset == pytest.approx(offset, abs=0.004)
    assert m.heading == pytest.approx(heading, abs=1.5 * DEG)


def test_accuracy_over_random_poses_on_every_course():
    """Seeded random poses (up to 6 cm off the line, turned up to 0.4 rad) where the curvature
    is the same from 0.15 m behind to 0.7 m ahead of the robot, so the line under the robot is
    what the camera sees: every one found, offsets within 3 mm, headings within 1.5 degrees."""
    rng = np.random.default_rng(3)
    errors = []
    for path in shipped_courses():
        scene = make_scene(load_course(path))
        line = scene.line
        while len(errors) < 10 * (1 + shipped_courses().index(path)):
            s = rng.uniform(0.15, line.length - 0.7)
            window = (line.s > s - 0.15) & (line.s < s + 0.7)
            if np.ptp(line.curvature[window][:-1]) > 0:
                continue
            X_WB = pose_near_line(line, s, rng.uniform(-0.06, 0.06), rng.uniform(-0.4, 0.4))
            m = _detect(scene, X_WB)
            offset, heading = true_line(line, X_WB)
            assert m.found, (path.name, s, m.reason)
            errors.append((m.offset - offset, math.remainder(m.heading - heading, 2 * math.pi)))
    errors = np.abs(np.array(errors))
    assert np.max(errors[:, 0]) < 0.003 and np.median(errors[:, 0]) < 0.0015
    assert np.max(errors[:, 1]) < 1.5 * DEG and np.median(errors[:, 1]) < 0.8 * DEG


def test_a_wrong_sized_image_is_not_found():
    m = mut.detect_line(np.zeros((0, 0, 4), np.uint8), INFO, RigidTransform(), CONFIG)
    assert not m.found and "80x60" in m.reason


@pytest.mark.parametrize(
    "change, match",
    [
        ({"gate": 0.0}, "'gate' must be positive"),
        ({"delay": -0.01}, "'delay' must be zero or positive"),
        ({"max_range": math.inf}, "'max_range' must be positive"),
        ({"threshold": 1.0}, "'threshold' must be below 1"),
    ],
)
def test_unusable_settings_are_rejected(change, match):
    assert mut.check_line_detector_config(CONFIG) is CONFIG
    with pytest.raises(ConfigError, match=match):
        mut.check_line_detector_config(dc.replace(CONFIG, **change))
