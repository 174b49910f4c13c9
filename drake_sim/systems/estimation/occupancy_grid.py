"""A log-odds occupancy grid built from 2D laser scans, and how to score a map against the truth.

``LogOddsGrid`` keeps l = log(p / (1 - p)) per cell (0: never seen). Inserting a scan adds
l_hit = log(p_hit / (1 - p_hit)) to the cell a beam's end point marks and l_miss (negative) to
every cell the beam crossed before it, once per scan each (a cell both crossed and hit in one
scan counts as hit, as in hector_slam's update markers); values are clamped so that a cell
can change its mind after a few scans. Beams without a return (``inf``) clear the space up to
``range_max``; NaN beams and beams shorter than ``range_min`` give no information.

Which cell a beam's end point marks is ``hit_offset`` (cells) beyond it, along the beam or along
the direction given per beam. With 0 (hector_slam's choice) it is the cell holding the end point.
An end point lies on the obstacle's face, though, and a face often lies on a cell edge (or within
the range noise of one), so for about half the beams the free cell in front of the face is
marked and the wall comes out a cell thick on the side it was seen from (measured: a third of a
SLAM map's occupied cells). With 0.5 along the surface's normal, a hit marks the first cell
whose centre is behind the face, the cell a ground-truth grid calls occupied (``arena_grid``:
a cell whose centre is inside an obstacle), whatever the angle the beam met the face at.

Ray tracing samples every beam at ``step`` (half a cell) from the sensor and collects the
cells under the samples, each once, in one compiled kernel (``grid_rays.crossed_cells``; no
sort, no array of all the samples): a 360-beam, 3.5 m scan on a 0.05 m grid costs about 0.5 ms
(``benchmarks/slam_benchmark.py``), and MIT CSAIL's 361-beam SICK scans, up to 50 m, 4 to 5
times less than the array version did (the cells bit for bit the same).

``occupancy_iou`` and ``known_fraction`` compare a map with a ground-truth ``OccupancyMap``
(different origins and resolutions allowed: cells are matched by their centres).
"""

import math

import numpy as np
from scipy import ndimage

from drake_sim.base.map_files import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from drake_sim.systems.estimation.grid_rays import crossed_cells


def log_odds(p: float) -> float:
    """log(p / (1 - p)) of a probability in (0, 1)."""
    return math.log(p / (1.0 - p))


class LogOddsGrid:
    """A square-celled log-odds occupancy grid, axis-aligned with the world.

    Args:
        resolution: cell size, m.
        size: (width, height) of the grid, m (rounded up to whole cells).
        origin: (x, y) of the lower-left corner of cell [0, 0] in the world, m. Row index grows
            with y, column index with x, as in ``OccupancyMap``.
        p_hit: probability a cell holding a beam's end point is occupied, in (0.5, 1).
        p_miss: probability a cell a beam crossed is occupied, in (0, 0.5).
        clamp: log-odds are kept in [-clamp, clamp].
        hit_offset: a beam's hit goes into the cell holding the point this many cells beyond
            its end point, in [0, 1) (see the module docstring).
    """

    def __init__(
        self,
        *,
        resolution: float,
        size: tuple[float, float],
        origin: tuple[float, float],
        p_hit: float = 0.7,
        p_miss: float = 0.4,
        clamp: float = 4.0,
        hit_offset: float = 0.0,
    ):
        if not resolution > 0:
            raise ValueError(f"resolution must be positive, got {resolution}")
        if not (0.5 < p_hit < 1 and 0 < p_miss < 0.5 and clamp > 0):
            raise ValueError(
                f"need 0.5 < p_hit < 1, 0 < p_miss < 0.5, clamp > 0 ({p_hit}, {p_miss})"
            )
        if not 0.0 <= hit_offset < 1.0:
            raise ValueError(f"hit_offset must be in [0, 1), got {hit_offset}")
        self.hit_offset = float(hit_offset)
        self.resolution = float(resolution)
        self.origin = (float(origin[0]), float(origin[1]))
        cols, rows = (max(1, math.ceil(s / resolution - 1e-9)) for s in size)
        self.log_odds = np.zeros((rows, cols), dtype=np.float32)
        self.l_hit, self.l_miss, self.clamp = log_odds(p_hit), log_odds(p_miss), float(clamp)
        self._stamp = self._is_hit = None  # Scratch arrays (see _unique), made when needed.
        # Rows and columns of the cells touched so far: [row_min, row_max, col_min, col_max].
        self.known_box = None
        # With ``track_changes``, what changed since ``take_changes`` last ran (see it).
        self.track_changes = False
        self._changes: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.changed_box = None
        self.version = 0  # Incremented by every insert_scan.

    def __getstate__(self):
        # Copies (a Drake abstract state is copied at every update) leave the scratch behind.
        return {**self.__dict__, "_stamp": None, "_is_hit": None}

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.log_odds.shape

    def probability(self) -> np.ndarray:
        """Occupancy probability of every cell, (rows, cols); 0.5 for cells never seen."""
        return 1.0 / (1.0 + np.exp(-self.log_odds))

    def insert_scan(
        self,
        sensor_pose,
        ranges,
        angles,
        range_max: float,
        *,
        range_min: float = 0.0,
        max_free_range: float | None = None,
        no_return_range: float | None = None,
        mask=None,
        hit_directions=None,
    ) -> None:
        """Adds one scan taken from ``sensor_pose`` (x, y, yaw in the world, m, m, rad).

        Args:
            ranges: (n,) m along each beam; ``inf`` = no return within ``range_max``.
            angles: (n,) beam angles in the sensor frame, rad.
            range_max: m; returns at or beyond it count as no return.
            range_min: m; shorter (finite) returns are ignored.
            max_free_range: m; beams clear space up to this distance at most (default
                ``range_max``).
            no_return_range: m; a beam with no return clears space this far at most (default:
                as far as the others).
            mask: optional (n,) booleans, False beams are ignored.
            hit_directions: optional (n, 2) unit vectors in the sensor frame along which each
                hit is put ``hit_offset`` cells beyond its end point (default: the beams; a
                scan matcher passes the surfaces' normals, see ``ScanMatchingSlam``).
        """
        ranges = np.asarray(ranges, dtype=float)
        angles = np.asarray(angles, dtype=float)
        use = ~np.isnan(ranges) & (ranges >= range_min)
        if mask is not None:
            use &= np.asarray(mask, dtype=bool)
        ranges, angles = ranges[use], angles[use]
        if hit_directions is not None:
            hit_directions = np.asarray(hit_directions, dtype=float).reshape(-1, 2)[use]
        hit = ranges < range_max
        free_limit = range_max if max_free_range is None else min(max_free_range, range_max)
        # Free space stops half a cell short of a hit, so the hit cell itself is not cleared.
        missing = free_limit if no_return_range is None else min(free_limit, no_return_range)
        free_length = np.where(hit, ranges - 0.5 * self.resolution, missing)
        free_length = np.minimum(free_length, free_limit)
        x, y, yaw = (float(v) for v in sensor_pose)
        c, s = np.cos(angles + yaw), np.sin(angles + yaw)
        step = 0.5 * self.resolution
        if self._stamp is None:
            self._stamp = np.zeros(self.log_odds.size, dtype=np.int32)
            self._is_hit = np.zeros(self.log_odds.size, dtype=bool)
        rows, cols = self.shape
        free_cells = crossed_cells(
            x, y, c, s, free_length, step, *self.origin, self.resolution, rows, cols, self._is_hit
        )
        hx, hy = x + c[hit] * ranges[hit], y + s[hit] * ranges[hit]
        if self.hit_offset:  # See the module docstring.
            if hit_directions is None:
                dx, dy = c[hit], s[hit]
            else:
                u, v = hit_directions[hit].T  # Sensor frame -> world.
                cy, sy = math.cos(yaw), math.sin(yaw)
                dx, dy = cy * u - sy * v, sy * u + cy * v
            hx = hx + self.hit_offset * self.resolution * dx
            hy = hy + self.hit_offset * self.resolution * dy
        hit_cells = self._unique(self._flat_cells(hx, hy))
        is_hit = self._is_hit
        is_hit[hit_cells] = True
        free_cells = free_cells[~is_hit[free_cells]]
        is_hit[hit_cells] = False
        flat = self.log_odds.reshape(-1)
        old_free, old_hit = flat[free_cells], flat[hit_cells]
        flat[free_cells] = np.maximum(old_free + self.l_miss, -self.clamp)
        flat[hit_cells] = np.minimum(old_hit + self.l_hit, self.clamp)
        if self.track_changes:
            self._changes.append(
                (
                    hit_cells[(old_hit <= 0) & (flat[hit_cells] > 0)],
                    free_cells[(old_free > 0) & (flat[free_cells] <= 0)],
                    np.concatenate([free_cells[old_free == 0], hit_cells[old_hit == 0]]),
                )
            )
        self._grow_box(np.concatenate([free_cells, hit_cells]))
        self.version += 1

    def clear(self) -> None:
        """Forgets every scan: all cells unknown again (the changes too)."""
        self.log_odds[:] = 0.0
        self.known_box = self.changed_box = None
        self._changes = []
        self.version += 1

    def extend(self, below: int, above: int, left: int, right: int) -> None:
        """Adds unknown cells: ``below`` rows under row 0 and ``above`` over the last row,
        ``left`` columns before column 0 and ``right`` after the last (the origin moves by the
        cells added below and left). What the grid holds stays where it is in the world; the
        changes not yet taken are dropped (their flat indices no longer hold: maps built from
        the grid must be built again)."""
        self.log_odds = np.pad(self.log_odds, ((below, above), (left, right)))
        self.origin = (
            round(self.origin[0] - left * self.resolution, 9),
            round(self.origin[1] - below * self.resolution, 9),
        )
        shift = [below, below, left, left]
        for name in ("known_box", "changed_box"):
            box = getattr(self, name)
            if box is not None:
                setattr(self, name, [v + d for v, d in zip(box, shift, strict=True)])
        self._changes = []
        self._stamp = self._is_hit = None
        self.version += 1

    def to_occupancy_map(
        self,
        *,
        occupied_thresh: float = 0.5,
        free_thresh: float = 0.5,
        crop: bool = True,
        margin: int = 2,
    ) -> OccupancyMap:
        """The grid as a trinary ``OccupancyMap``: 100 where p > occupied_thresh, 0 where
        p < free_thresh, -1 otherwise and where never seen (the defaults are hector_slam's:
        the sign of the log-odds). ``crop`` keeps the seen cells plus ``margin`` cells."""
        p = self.probability()
        cells = np.full(self.shape, UNKNOWN, dtype=np.int8)
        seen = self.log_odds != 0
        cells[seen & (p < free_thresh)] = FREE
        cells[seen & (p > occupied_thresh)] = OCCUPIED
        r0, c0 = 0, 0
        if crop and self.known_box is not None:
            rmin, rmax, cmin, cmax = self.known_box
            r0, c0 = max(rmin - margin, 0), max(cmin - margin, 0)
            r1, c1 = min(rmax + margin + 1, self.shape[0]), min(cmax + margin + 1, self.shape[1])
            cells = cells[r0:r1, c0:c1]
        # Rounded to 1e-9 m so that map files say -3.15, not -3.1499999999999986.
        x0 = round(self.origin[0] + c0 * self.resolution, 9)
        y0 = round(self.origin[1] + r0 * self.resolution, 9)
        return OccupancyMap(cells, self.resolution, (x0, y0, 0.0))

    def _flat_cells(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Flat indices of the cells holding the points; points off the grid are dropped."""
        rows, cols = self.shape
        j = np.floor((xs - self.origin[0]) / self.resolution).astype(np.int64)
        i = np.floor((ys - self.origin[1]) / self.resolution).astype(np.int64)
        ok = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
        return i[ok] * cols + j[ok]

    def _unique(self, flat: np.ndarray) -> np.ndarray:
        """The distinct values of ``flat`` in O(n): each cell keeps the last index written to
        it, and exactly one occurrence of each cell finds its own index there."""
        index = np.arange(flat.size, dtype=np.int32)
        self._stamp[flat] = index
        return flat[self._stamp[flat] == index]

    def take_changed_box(self) -> list[int] | None:
        """[row_min, row_max, col_min, col_max] of the cells changed since the last call (None:
        none), and starts again: what a map built from this grid must bring up to date."""
        box, self.changed_box = self.changed_box, None
        return box

    def take_changes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """With ``track_changes`` on, the flat indices (into ``log_odds.ravel()``) of the cells
        that became occupied (log-odds above 0), stopped being occupied, and were seen for the
        first time, since the last call (a cell may be listed more than once), and starts
        again; all empty with it off."""
        changes, self._changes = self._changes, []
        if not changes:
            empty = np.zeros(0, dtype=np.int64)
            return empty, empty, empty
        return tuple(np.concatenate(parts).astype(np.int64) for parts in zip(*changes, strict=True))

    def _grow_box(self, flat: np.ndarray) -> None:
        if flat.size == 0:
            return
        rows, cols = np.divmod(flat, self.shape[1])
        box = [int(rows.min()), int(rows.max()), int(cols.min()), int(cols.max())]
        self.known_box = _union(self.known_box, box)
        self.changed_box = _union(self.changed_box, box)


def grow_to_cover(grids: list[LogOddsGrid], points, step: float) -> bool:
    """Extends every grid of ``grids`` (one origin, cells dividing ``step``) by whole ``step``s
    (m) on each side where ``points`` ((n, 2), m, world) reach beyond it (or come within
    ``step`` of its edge), by at least a quarter of the grid's side there, so that a robot
    going on that way does not extend it again at once; True when they grew. The grids keep
    the cells they share (a lattice of ``step``), and nothing changes while the points stay
    inside."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if not len(points):
        return False
    grid = grids[0]
    rows, cols = grid.shape
    start = np.array(grid.origin)
    end = start + np.array([cols, rows]) * grid.resolution
    low, high = points.min(axis=0) - step, points.max(axis=0) + step
    lacking = np.concatenate([start - low, high - end])  # left, below, right, above
    if not np.any(lacking > 0):
        return False
    quarter = np.tile(0.25 * (end - start), 2)
    steps = np.where(lacking > 0, np.ceil(np.maximum(lacking, quarter) / step - 1e-9), 0)
    for each in grids:
        left, below, right, above = (int(round(n * step / each.resolution)) for n in steps)
        each.extend(below, above, left, right)
    return True


def _union(a: list[int] | None, b: list[int]) -> list[int]:
    """The smallest [row_min, row_max, col_min, col_max] box holding boxes ``a`` and ``b``."""
    if a is None:
        return list(b)
    return [min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])]


def observable(truth: OccupancyMap) -> tuple[np.ndarray, np.ndarray]:
    """Masks (free, surface) of the truth's cells a lidar can observe: its free cells, and its
    occupied cells that touch a free cell (8-neighbourhood), the surfaces of walls and
    obstacles. The inside of an obstacle is never seen by a scan."""
    free = truth.free()
    occupied = truth.occupied()
    near_free = ndimage.binary_dilation(free, structure=np.ones((3, 3), bool))
    return free, occupied & near_free


def occupancy_iou(
    occupancy_map: OccupancyMap, truth: OccupancyMap, tolerance_cells: int = 1
) -> float:
    """Intersection over union of the map's occupied surface cells A and the truth's B (an
    occupied cell with a free neighbour, see ``observable``: the inside of a solid is never
    seen by a scan, in either map), with a tolerance: (|A near B| + |B near A|) / (|A| + |B|),
    where "near" means within ``tolerance_cells`` cells of the truth's resolution (Chebyshev
    distance between cell centres). 1 when every wall is mapped where it is and nothing else
    is (the truth scores 1 against itself); an empty map scores 0."""
    _, a_mask = observable(occupancy_map)
    _, b_mask = observable(truth)
    if not a_mask.any() or not b_mask.any():
        return 0.0
    tolerance = tolerance_cells * truth.resolution
    a_xy = _centres_of(occupancy_map, a_mask)
    b_xy = _centres_of(truth, b_mask)
    a_near_b = _near(truth, b_mask, a_xy, tolerance)
    b_near_a = _near(occupancy_map, a_mask, b_xy, tolerance)
    return float((a_near_b.sum() + b_near_a.sum()) / (len(a_xy) + len(b_xy)))


def known_fraction(occupancy_map: OccupancyMap, truth: OccupancyMap) -> float:
    """Fraction of the truth's observable cells (free cells and occupied surface cells, see
    ``observable``) whose centres fall in a known (free or occupied) cell of the map."""
    free, surface = observable(truth)
    target = free | surface
    if not target.any():
        return 0.0
    values = occupancy_map.value_at(_centres_of(truth, target))
    return float(np.mean(values >= 0))


def _centres_of(grid: OccupancyMap, mask: np.ndarray) -> np.ndarray:
    xs, ys = grid.centres()
    return np.stack([xs[mask], ys[mask]], -1)


def _near(grid: OccupancyMap, mask: np.ndarray, xy: np.ndarray, tolerance: float) -> np.ndarray:
    """Which points lie within ``tolerance`` m (per axis, about) of a ``mask`` cell of ``grid``."""
    radius = max(0, int(math.floor(tolerance / grid.resolution + 0.5)))
    grown = ndimage.binary_dilation(mask, np.ones((2 * radius + 1,) * 2, bool)) if radius else mask
    rows, cols = grid.cell_of(xy)
    inside = grid.inside(rows, cols)
    near = np.zeros(len(xy), dtype=bool)
    near[inside] = grown[rows[inside], cols[inside]]
    return near
