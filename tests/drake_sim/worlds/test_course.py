"""Wall-E's courses (drake_sim.worlds.course): loading, checks naming the key, and geometry."""

import math

import numpy as np
import pytest

import drake_sim.worlds.course as mut
from drake_sim.base.errors import ConfigError

OVAL = """
line_width: 0.03
floor_margin: 0.5
closed: true
start: {x: 0.0, y: 0.0, yaw: 0.0}
segments:
  - {straight: 1.5}
  - {arc: {radius: 0.6, angle: 180}}
  - {straight: 1.5}
  - {arc: {radius: 0.6, angle: 180}}
"""


def _load(tmp_path, text: str) -> mut.Course:
    path = tmp_path / "course.yaml"
    path.write_text(text)
    return mut.load_course(path)


def _segment_length(segment: mut.SegmentSpec) -> float:
    if segment.straight is not None:
        return segment.straight
    return segment.arc.radius * math.radians(abs(segment.arc.angle))


def test_the_three_shipped_courses_load_and_are_robot_sized():
    files = mut.shipped_courses()
    assert [f.name for f in files] == ["oval.yaml", "s_bend.yaml", "tight.yaml"]
    for path in files:
        course = mut.load_course(path)
        line = mut.centreline(course)
        assert 2.0 <= line.length <= 8.0, path.name
        expected = sum(_segment_length(s) for s in course.segments)
        assert line.length == pytest.approx(expected, abs=mut.CLOSE_TOLERANCE), path.name
        if course.closed:
            np.testing.assert_array_equal(line.p_WP[0], line.p_WP[-1])
    tight = mut.load_course(files[2])
    assert min(s.arc.radius for s in tight.segments if s.arc) <= 0.3
    assert not mut.load_course(files[1]).closed


def test_a_contract_example_loads(tmp_path):
    course = _load(tmp_path, OVAL)
    assert course.closed and course.line_width == 0.03 and len(course.segments) == 4
    assert course.segments[1].arc == mut.ArcSpec(radius=0.6, angle=180.0)
    assert course.segments[0].straight == 1.5 and course.segments[0].arc is None


@pytest.mark.parametrize(
    "text, match",
    [
        (OVAL + "colour: red\n", "unknown key 'colour'"),
        (OVAL.replace("{straight: 1.5}", "{straigth: 1.5}", 1), r"unknown key 'segments\[0\]"),
        (OVAL.replace("radius: 0.6", "radius: .nan", 1), r"'segments\[1\].arc.radius' must be fin"),
        (OVAL.replace("radius: 0.6", "radius: 0", 1), r"'segments\[1\].arc.radius' must be pos"),
        (OVAL.replace("radius: 0.6", "radius: -0.6", 1), r"'segments\[1\].arc.radius' must be p"),
        (OVAL.replace("{straight: 1.5}", "{straight: 0}", 1), r"'segments\[0\].straight' must be"),
        (OVAL.replace("{straight: 1.5}", "{straight: -1}", 1), r"'segments\[0\].straight' must"),
        (OVAL.replace("angle: 180}", "angle: 0}", 1), r"'segments\[1\].arc.angle' must be non"),
        (
            OVAL.replace("{arc: {radius: 0.6, angle: 180}}", "{arc: {angle: 180}}", 1),
            r"missing key 'segments\[1\].arc.radius'",
        ),
        (OVAL.replace("{straight: 1.5}", "{}", 1), r"'segments\[0\]' must have exactly one"),
        (
            OVAL.replace("{straight: 1.5}", "{straight: 1.5, arc: {radius: 1, angle: 9}}", 1),
            r"'segments\[0\]' must have exactly one",
        ),
        (OVAL.replace("  - {straight: 1.5}\n", "", 1), "'closed' is true but the segments end"),
        ("closed: false\nsegments: []\n", "'segments' is empty"),
        ("closed: false\n", "'segments' is empty"),
        (OVAL.replace("line_width: 0.03", "line_width: 0"), "'line_width' must be positive"),
        (OVAL.replace("floor_margin: 0.5", "floor_margin: -1"), "'floor_margin' must be zero"),
        (OVAL.replace("yaw: 0.0", "yaw: .inf"), "'start.yaw' must be finite"),
        (OVAL.replace("closed: true", "closed: 1"), "'closed' must be true or false"),
    ],
)
def test_malformed_courses_are_rejected_naming_the_key(tmp_path, text, match):
    with pytest.raises(ConfigError, match=match) as error:
        _load(tmp_path, text)
    assert "course.yaml" in str(error.value)


def test_a_loop_that_misses_its_start_by_less_than_a_centimetre_is_closed(tmp_path):
    course = _load(tmp_path, OVAL.replace("- {straight: 1.5}\n", "- {straight: 1.505}\n", 1))
    line = mut.centreline(course)
    np.testing.assert_array_equal(line.p_WP[-1], line.p_WP[0])
    assert line.length == pytest.approx(3.005 + 1.2 * math.pi + 0.005, abs=1e-6)  # + the gap
    with pytest.raises(ConfigError, match="0.011 m from the start"):
        _load(tmp_path, OVAL.replace("- {straight: 1.5}\n", "- {straight: 1.511}\n", 1))


def test_the_centreline_follows_its_segments(tmp_path):
    course = _load(tmp_path, OVAL.replace("yaw: 0.0", "yaw: 90.0").replace("x: 0.0", "x: 1.0"))
    line = mut.centreline(course, spacing=0.01)
    assert line.length == pytest.approx(3.0 + 1.2 * math.pi)
    assert np.all(np.diff(line.s) <= 0.01 + 1e-12)
    # Up the first straight from (1, 0), then a left half turn about (0.4, 1.5).
    p, heading = line.pose_at(1.5)
    np.testing.assert_allclose(p, [1.0, 1.5], atol=1e-9)
    assert heading == pytest.approx(math.pi / 2)
    on_arc = (line.s > 1.5 + 1e-9) & (line.s < 1.5 + 0.6 * math.pi - 1e-9)
    radii = np.linalg.norm(line.p_WP[on_arc] - [0.4, 1.5], axis=1)
    np.testing.assert_allclose(radii, 0.6, atol=1e-9)
    np.testing.assert_allclose(line.curvature[on_arc], 1 / 0.6)
    assert line.heading[-1] - line.heading[0] == pytest.approx(2 * math.pi)
    lo, hi = line.bounds()
    np.testing.assert_allclose(lo, [-0.2, -0.6], atol=1e-4)
    np.testing.assert_allclose(hi, [1.0, 1.5 + 0.6], atol=1e-4)


def test_a_right_turn_curves_right(tmp_path):
    text = "segments:\n  - {arc: {radius: 0.5, angle: -90}}\n"
    line = mut.centreline(_load(tmp_path, text))
    np.testing.assert_allclose(line.p_WP[-1], [0.5, -0.5], atol=1e-9)
    assert line.heading[-1] == pytest.approx(-math.pi / 2)
    assert np.all(line.curvature[:-1] == -2.0)


def test_projection_distance_offset_and_arc_length(tmp_path):
    line = mut.centreline(_load(tmp_path, OVAL))
    left = line.project([0.7, 0.05])
    assert (left.s, left.distance, left.offset, left.heading) == pytest.approx((0.7, 0.05, 0.05, 0))
    right = line.project([0.7, -0.05, 0.3])  # a z is ignored
    assert right.offset == pytest.approx(-0.05)
    # The top of the first half turn, centre (1.5, 0.6): 0.1 m inside it, heading straight up.
    inside = line.project([2.0, 0.6])
    assert inside.s == pytest.approx(1.5 + 0.3 * math.pi, abs=1e-3)
    assert inside.distance == pytest.approx(0.1, abs=1e-4)
    assert inside.offset == pytest.approx(0.1, abs=1e-4)  # the inside of a left turn is left
    assert inside.heading == pytest.approx(math.pi / 2, abs=1e-3)
    np.testing.assert_allclose(inside.p_WF, [2.1, 0.6], atol=1e-4)
    np.testing.assert_allclose(
        line.distances([[0.7, 0.05], [2.0, 0.6], [0.0, 0.0]]), [0.05, 0.1, 0.0], atol=1e-4
    )


def test_advance_counts_crossing_the_start_of_a_loop_as_a_small_step(tmp_path):
    loop = mut.centreline(_load(tmp_path, OVAL))
    assert loop.advance(loop.length - 0.05, 0.05) == pytest.approx(0.1)
    assert loop.advance(0.05, loop.length - 0.05) == pytest.approx(-0.1)
    assert loop.advance(1.0, 2.0) == pytest.approx(1.0)
    p, _ = loop.pose_at(loop.length + 0.7)
    np.testing.assert_allclose(p, [0.7, 0.0], atol=1e-9)
    path = mut.centreline(mut.load_course(mut.shipped_courses()[1]))
    assert path.advance(path.length - 0.05, 0.05) == pytest.approx(0.1 - path.length)
    np.testing.assert_allclose(path.pose_at(path.length + 1.0)[0], path.p_WP[-1])


def test_check_course_takes_courses_built_in_code():
    course = mut.Course(segments=[mut.SegmentSpec(straight=2.0)])
    assert mut.check_course(course) is course
    with pytest.raises(ConfigError, match=r"in code: 'segments\[0\].straight' must be positive"):
        mut.check_course(mut.Course(segments=[mut.SegmentSpec(straight=math.inf)]), "in code")


def test_nearest_on_chords():
    a = np.array([[0.0, 0.0], [1.0, 0.0]])
    b = np.array([[1.0, 0.0], [1.0, 1.0]])
    index, t, d2 = mut.nearest_on_chords(np.array([[0.25, -0.5], [1.5, 0.75], [2.0, -1.0]]), a, b)
    np.testing.assert_array_equal(index, [0, 1, 0])
    np.testing.assert_allclose(t, [0.25, 0.75, 1.0])
    np.testing.assert_allclose(d2, [0.25, 0.25, 2.0])
