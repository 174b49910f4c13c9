"""2D footprints (drake_sim.worlds.footprints): signed distances, ray distances, clearance,
2D ray casting and the occupied boundary of a grid."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_sim.worlds.footprints as mut
from drake_sim.worlds.arena import arena_footprints
from tests.drake_sim.worlds.test_arena import CONTRACT, _load


def test_signed_distance_of_rectangles_and_circles():
    rect = mut.Footprint("box", "b", (1.0, 0.0), (0.5, 0.25), math.pi / 2, 0.0, 0.3)
    points = np.array([[1.0, 0.0], [1.0, 0.6], [1.5, 0.0], [1.0, 1.0], [1.35, 0.8]])
    np.testing.assert_allclose(
        rect.signed_distance(points), [-0.25, 0.1, 0.25, 0.5, math.hypot(0.1, 0.3)]
    )
    circle = mut.Footprint("cylinder", "c", (0.0, 0.0), (0.2, 0.2), 0.0, 0.2, 0.3)
    np.testing.assert_allclose(
        circle.signed_distance(np.array([[0.0, 0.0], [0.0, 1.0]])), [-0.2, 0.8]
    )
    assert mut.clearance([rect, circle], np.array([0.5, 0.0])) == pytest.approx(0.25)
    assert mut.clearance([], np.zeros(2)) == np.inf


def test_ray_distances_are_exact_for_hand_computed_cases():
    rect = mut.Footprint("box", "b", (2.0, 0.0), (0.5, 0.5), math.pi / 4, 0.0, 0.3)
    circle = mut.Footprint("cylinder", "c", (0.0, 2.0), (0.5, 0.5), 0.0, 0.5, 0.3)
    origin = np.zeros(2)
    # A diamond: its nearest corner is sqrt(0.5) from its centre along x.
    assert rect.ray_distance(origin, np.array([1.0, 0.0])) == pytest.approx(2.0 - math.sqrt(0.5))
    assert circle.ray_distance(origin, np.array([0.0, 1.0])) == pytest.approx(1.5)
    assert circle.ray_distance(origin, np.array([0.0, -1.0])) == np.inf
    assert rect.ray_distance(origin, np.array([-1.0, 0.0])) == np.inf
    assert rect.ray_distance(np.array([2.0, 0.0]), np.array([0.0, 1.0])) == 0.0  # from inside
    # Grazing a circle's side: tangent at x = 0.5.
    assert circle.ray_distance(np.array([0.5, 0.0]), np.array([0.0, 1.0])) == pytest.approx(2.0)
    axis = mut.Footprint("wall", "w", (0.0, 1.0), (1.0, 0.1), 0.0, 0.0, 0.3)
    assert axis.ray_distance(origin, np.array([0.0, 1.0])) == pytest.approx(0.9)  # u_x = 0
    assert axis.ray_distance(np.array([2.0, 0.0]), np.array([0.0, 1.0])) == np.inf


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    st.floats(-2, 2),
    st.floats(-2, 2),
    st.floats(0.05, 1),
    st.floats(0.05, 1),
    st.floats(-4, 4),
    st.booleans(),
    st.floats(-math.pi, math.pi),
)
def test_a_ray_stops_on_the_surface(cx, cy, hx, hy, yaw, circle, angle):
    """Wherever a ray from outside stops, the shape's surface is; before it, outside."""
    shape = mut.Footprint(
        "cylinder" if circle else "box",
        "s",
        (cx, cy),
        (hx, hx) if circle else (hx, hy),
        0.0 if circle else yaw,
        hx if circle else 0.0,
        0.3,
    )
    origin = np.array([3.0, -2.5])
    u = np.array([math.cos(angle), math.sin(angle)])
    t = float(shape.ray_distance(origin, u))
    along = origin + np.linspace(0, min(t, 10.0), 200)[:-1, None] * u
    assert np.all(shape.signed_distance(along) > -1e-9)
    if math.isfinite(t):
        assert shape.signed_distance(origin + t * u) == pytest.approx(0.0, abs=1e-9)


def test_cast_rays_in_the_contract_arena(tmp_path):
    footprints = arena_footprints(_load(tmp_path, CONTRACT))
    angles = np.radians([0.0, 90.0, 180.0, -90.0, 45.0])
    ranges = mut.cast_rays(footprints, [[-2.0, -1.5], [-1.2, 0.0]], angles, 3.5)
    assert ranges.shape == (2, 5)
    # From the start: the inner wall's face at x = -0.025, the north wall (4 m: beyond range),
    # the west wall, the south wall, and the inner wall again along the diagonal.
    np.testing.assert_allclose(
        ranges[0], [1.975, np.inf, 1.0, 1.0, 1.975 * math.sqrt(2)], rtol=1e-12
    )
    assert ranges[1, 1] == pytest.approx(0.8 - 0.15)  # the cylinder, straight up


def test_occupied_boundary_marks_cells_next_to_free_ones():
    cells = np.zeros((6, 6), dtype=np.int8)
    cells[1:5, 1:5] = 100
    cells[:, 5] = -1
    boundary = mut.occupied_boundary(cells)
    assert not boundary[2:4, 2:4].any()
    assert boundary[1, 1:5].all() and boundary[1:5, 1].all() and boundary[4, 1:4].all()
    assert not boundary[2, 4]  # its neighbours are occupied or unknown, none free
    assert boundary[1, 4]  # row 0 is free
