"""The course floor (drake_sim.worlds.course_floor): its image, its cached files, the plant."""

import dataclasses as dc
import math

import numpy as np
import pytest
from PIL import Image
from pydrake.geometry import HalfSpace, Mesh, Role
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import drake_sim.worlds.course_floor as mut
from drake_sim.base.errors import ConfigError
from drake_sim.worlds.course import Course, SegmentSpec, centreline, load_course, shipped_courses


@pytest.fixture(scope="module")
def s_bend() -> Course:
    return load_course(shipped_courses()[1])


def _grey_at(image: np.ndarray, layout: mut.FloorLayout, p_WQ) -> float:
    """The image's value at the floor point p_WQ (nearest pixel)."""
    column = int((p_WQ[0] - layout.x0) / layout.pixel)
    row = int(layout.rows - (p_WQ[1] - layout.y0) / layout.pixel)
    return float(image[row, column])


def test_the_layout_covers_the_line_and_its_margin_with_fine_pixels(s_bend):
    layout = mut.floor_layout(s_bend)
    assert layout.pixel == pytest.approx(s_bend.line_width / mut.PIXELS_ACROSS_LINE)
    lo, hi = centreline(s_bend).bounds()
    margin = s_bend.floor_margin + s_bend.line_width / 2
    assert layout.x0 == pytest.approx(lo[0] - margin) and layout.y0 == pytest.approx(lo[1] - margin)
    size = np.array(layout.size)
    assert np.all(size >= hi - lo + 2 * margin - 1e-9)
    assert np.all(size < hi - lo + 2 * margin + layout.pixel)


def test_a_floor_too_large_for_its_line_is_rejected():
    huge = Course(line_width=0.01, segments=[SegmentSpec(straight=30.0)])
    with pytest.raises(ConfigError, match="too large a floor for a 0.01 m 'line_width'"):
        mut.floor_layout(huge, "huge.yaml")
    coarse = mut.floor_layout(dc.replace(huge, line_width=0.03))  # 5 mm pixels still fit
    assert max(coarse.columns, coarse.rows) == mut.MAX_IMAGE_SIZE


def test_the_image_is_a_white_line_of_the_right_width_on_black(s_bend):
    layout = mut.floor_layout(s_bend)
    image = mut.draw_floor(s_bend, layout)
    assert image.shape == (layout.rows, layout.columns)
    line = centreline(s_bend)
    # The s-bend is not symmetric: its samples (and only they) land on white pixels, so the
    # image is neither mirrored nor turned.
    on = [_grey_at(image, layout, p) for p in line.p_WP[::20]]
    assert min(on) > 0.9 * mut.LINE_GREY
    for s in np.linspace(0.1, line.length - 0.1, 25):
        p, heading = line.pose_at(s)
        left = np.array([-math.sin(heading), math.cos(heading)])
        assert _grey_at(image, layout, p + 0.05 * left) == pytest.approx(mut.FLOOR_GREY)
    # Across the first straight (along x), the line covers line_width of floor: antialiased.
    column = image[:, int((0.25 - layout.x0) / layout.pixel)]
    covered = np.sum((column - mut.FLOOR_GREY) / (mut.LINE_GREY - mut.FLOOR_GREY)) * layout.pixel
    assert covered == pytest.approx(s_bend.line_width, rel=0.02)
    assert np.any((column > mut.FLOOR_GREY + 0.05) & (column < mut.LINE_GREY - 0.05))


def test_floor_files_are_cached_by_the_course_hash(s_bend):
    files = mut.floor_files(s_bend)
    assert files.folder.parent.name == "courses" and files.folder.name == mut.course_hash(s_bend)
    stamps = [path.stat().st_mtime_ns for path in (files.obj, files.mtl, files.png)]
    again = mut.floor_files(dc.replace(s_bend))  # an equal course
    assert again == files
    assert stamps == [path.stat().st_mtime_ns for path in (files.obj, files.mtl, files.png)]
    wider = dc.replace(s_bend, line_width=0.04)
    assert mut.course_hash(wider) != mut.course_hash(s_bend)
    other = mut.floor_files(wider)
    assert other.folder != files.folder and other.png.is_file()
    assert files.png.is_file()  # the old course's floor stays


def test_floor_files_hold_a_textured_quad_the_size_of_the_layout(s_bend):
    files = mut.floor_files(s_bend)
    layout = mut.floor_layout(s_bend)
    obj = files.obj.read_text()
    assert f"mtllib {files.mtl.name}" in obj and "usemtl floor" in obj
    vertices = np.array(
        [[float(v) for v in line.split()[1:]] for line in obj.splitlines() if line.startswith("v ")]
    )
    np.testing.assert_allclose(vertices.min(axis=0), [layout.x0, layout.y0, 0.0], atol=1e-6)
    np.testing.assert_allclose(
        vertices.max(axis=0)[:2], np.add([layout.x0, layout.y0], layout.size), atol=1e-6
    )
    assert f"map_Kd {files.png.name}" in files.mtl.read_text()
    with Image.open(files.png) as png:
        pixels = np.asarray(png.convert("L"), dtype=float) / 255
    assert pixels.shape == (layout.rows, layout.columns)
    np.testing.assert_allclose(pixels, mut.draw_floor(s_bend, layout), atol=1 / 255)


def test_add_course_floor_adds_a_visual_and_a_grippy_ground(s_bend):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=1e-3)
    files = mut.add_course_floor(plant, s_bend, mu_static=1.1, mu_dynamic=0.95)
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    frame = plant.GetBodyFrameIdOrThrow(plant.world_body().index())
    visual = inspector.GetGeometries(frame, Role.kPerception)
    assert len(visual) == 1 and inspector.GetName(visual[0]).endswith(mut.FLOOR_NAME)
    assert isinstance(inspector.GetShape(visual[0]), Mesh)
    assert str(inspector.GetShape(visual[0]).source().path()) == str(files.obj)
    assert inspector.GetGeometries(frame, Role.kIllustration) == visual
    (ground,) = inspector.GetGeometries(frame, Role.kProximity)
    assert isinstance(inspector.GetShape(ground), HalfSpace)
    friction = inspector.GetProximityProperties(ground).GetProperty("material", "coulomb_friction")
    assert (friction.static_friction(), friction.dynamic_friction()) == (1.1, 0.95)
