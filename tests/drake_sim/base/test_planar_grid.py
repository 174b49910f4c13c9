"""``PlanarGrid``: world points to cells and back on a rotated, shifted grid."""

import dataclasses as dc
import math

import numpy as np
import pytest

import drake_sim.base.planar_grid as mut


@dc.dataclass
class _Grid(mut.PlanarGrid):
    shape: tuple[int, int] = (3, 4)
    resolution: float = 0.5
    origin: tuple[float, float, float] = (1.0, -2.0, math.pi / 2)  # columns run along world +y


def test_to_grid_and_to_world_are_inverse():
    dut = _Grid()
    np.testing.assert_allclose(dut.to_grid([1.0, -2.0]), [0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(dut.to_grid([1.0, -1.0]), [2.0, 0.0], atol=1e-15)  # 1 m along x'
    np.testing.assert_allclose(dut.to_grid([0.5, -2.0]), [0.0, 1.0], atol=1e-15)  # 0.5 m along y'
    points = np.random.default_rng(0).normal(size=(5, 2, 2))
    np.testing.assert_allclose(dut.to_world(dut.to_grid(points)), points, atol=1e-12)


def test_cell_of_floors_and_inside_masks():
    dut = _Grid()
    rows, cols = dut.cell_of([[0.9, -0.9], [1.1, -2.1]])
    np.testing.assert_array_equal(rows, [0, -1])  # 0.1 m along y': row 0; -0.1 m: row -1
    np.testing.assert_array_equal(cols, [2, -1])
    assert rows.dtype == np.int64
    np.testing.assert_array_equal(dut.inside([0, -1, 2, 3], [3, 0, 4, 0]), [1, 0, 0, 0])


def test_centres_are_the_cells_centres_in_the_world():
    dut = _Grid()
    xs, ys = dut.centres()
    assert xs.shape == ys.shape == dut.shape
    rows, cols = dut.cell_of(np.stack([xs, ys], -1))
    np.testing.assert_array_equal(rows, np.indices(dut.shape)[0])
    np.testing.assert_array_equal(cols, np.indices(dut.shape)[1])
    np.testing.assert_allclose((xs[0, 0], ys[0, 0]), (0.75, -1.75))


@pytest.mark.parametrize("dtype, outside", [(np.int8, -1), (np.uint8, 255)])
def test_values_at_reads_the_layer_and_outside_beyond(dtype, outside):
    dut = _Grid()
    layer = np.arange(12, dtype=dtype).reshape(dut.shape)
    xs, ys = dut.centres()
    values = dut.values_at(layer, [[xs[1, 2], ys[1, 2]], [100.0, 0.0]], outside)
    assert values.dtype == dtype
    np.testing.assert_array_equal(values, [6, outside])
