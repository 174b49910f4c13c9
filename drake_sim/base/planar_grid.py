"""The geometry of a grid of square cells posed in the plane: world points to cells and back.

A grid has ``shape`` (rows, cols), ``resolution`` (m per cell) and ``origin`` = (x, y, yaw)
(m, m, rad), the pose in the world of the lower-left corner of cell [0, 0]; the row index grows
with y and the column index with x in the origin's frame, so row 0 is the lowest y (the ROS
``nav_msgs/OccupancyGrid`` convention). ``OccupancyMap`` (``drake_sim.base.map_files``) and
the navigation's ``Costmap`` are such grids: ``PlanarGrid`` gives both the same conversions.

Grid units are cells: the point (column, row) = (c + 0.5, r + 0.5) is the centre of cell
[r, c], which spans [c, c + 1) x [r, r + 1).
"""

import math

import numpy as np


class PlanarGrid:
    """Conversions between world points and cells of a grid with ``shape``, ``resolution`` and
    ``origin`` attributes (see the module docstring)."""

    shape: tuple[int, int]
    resolution: float
    origin: tuple[float, float, float]

    def to_grid(self, xy) -> np.ndarray:
        """Returns world points ``xy`` (..., 2) m in grid units (..., 2): (column, row) as
        floats, so that cell [r, c] spans [c, c + 1) x [r, r + 1)."""
        xy = np.asarray(xy, dtype=float)
        x0, y0, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = xy[..., 0] - x0, xy[..., 1] - y0
        return np.stack([c * dx + s * dy, -s * dx + c * dy], -1) / self.resolution

    def to_world(self, grid) -> np.ndarray:
        """Returns grid points (..., 2) (column, row units, see ``to_grid``) in the world, m."""
        g = np.asarray(grid, dtype=float) * self.resolution
        x0, y0, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        return np.stack(
            [x0 + c * g[..., 0] - s * g[..., 1], y0 + s * g[..., 0] + c * g[..., 1]], -1
        )

    def cell_of(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Returns (rows, cols), int arrays of the cells holding world points ``xy`` (..., 2) m.

        Indices are not clipped: points outside the grid give indices outside [0, shape).
        """
        local = self.to_grid(xy)
        return np.floor(local[..., 1]).astype(np.int64), np.floor(local[..., 0]).astype(np.int64)

    def inside(self, rows, cols) -> np.ndarray:
        """Boolean mask: which (rows, cols) index a cell of the grid."""
        rows, cols = np.asarray(rows), np.asarray(cols)
        return (rows >= 0) & (rows < self.shape[0]) & (cols >= 0) & (cols < self.shape[1])

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """World coordinates (xs, ys), each (rows, cols) m, of every cell's centre."""
        rows, cols = np.indices(self.shape, dtype=float)
        world = self.to_world(np.stack([cols + 0.5, rows + 0.5], -1))
        return world[..., 0], world[..., 1]

    def values_at(self, layer: np.ndarray, xy, outside) -> np.ndarray:
        """The values of ``layer`` (the grid's shape) at the cells holding world points ``xy``
        (..., 2) m, in ``layer``'s dtype; ``outside`` for points beyond the grid."""
        rows, cols = self.cell_of(xy)
        ok = self.inside(rows, cols)
        values = np.full(rows.shape, outside, dtype=layer.dtype)
        values[ok] = layer[rows[ok], cols[ok]]
        return values
