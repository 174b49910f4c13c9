"""Scan-to-map matching by Gauss-Newton on interpolated occupancy maps, as hector_slam does.

Kohlbrecher, von Stryk, Meyer, Klingauf, "A Flexible and Scalable SLAM System with Full 3D
Motion Estimation", SSRR 2011. The scan's end points p_i (base frame, m) placed by the pose
xi = (x, y, yaw) land at S_i(xi) = R(yaw) p_i + (x, y) in the world; a good pose puts them on
occupied cells, so xi minimises

    E(xi) = sum_i w_i (1 - M(S_i(xi)))^2 + (xi - xi_0)^T W (xi - xi_0),

where M is the map's occupancy probability (hector) or a likelihood field around its occupied
cells (``MatchMap.from_grid``), bilinearly interpolated between cell centres (continuous, with a
gradient almost everywhere), w_i is 0 for end points on cells never seen (they say nothing
about the pose; counted, they would pull the scan back into the mapped area) and shares n among
the others, and the second term is a weak prior towards the odometry's prediction xi_0. One
Gauss-Newton step linearises M(S_i(xi + d)) ~ M(S_i) + grad M(S_i) dS_i/dxi d:

    (H + W) d = sum_i w_i J_i^T (1 - M(S_i)) - W (xi - xi_0),   H = sum_i w_i J_i^T J_i,
    J_i = grad M(S_i) [[1, 0, -sin(yaw) p_x - cos(yaw) p_y], [0, 1, cos(yaw) p_x - sin(yaw) p_y]],

and a step that raises E is halved (up to 4 times). The cost surface of a fine map is narrow
(about a cell wide), so matching runs coarse to fine over a pyramid of maps (hector keeps one
grid per level, each updated with every scan, which is what ``ScanMatchingSlam`` does). A
coarse level's optimum is off by up to a fraction of its cells, though (0.7 degrees for 5 cm
cells seen 2 m away: outside the next level's basin), while odometry between two scans is good
to a fraction of that, so each level starts from whichever of the coarser result and xi_0 it
scores better.

``MatchResult.hessian`` is the finest level's H (m^-2, rad^-2) at the result. It is *not* a good
measure of what the scan constrains: a wall seen at a grazing angle is a dotted line of hits
(36 cm apart at 3.5 m for 1 degree beams), and a scan from nearby, with the same beam pattern,
fits those dots best where it was taken, even along a featureless corridor. ``normal_spread``
measures it from the scan's own geometry instead: along a corridor the smallest eigenvalue of
its normals' spread is under 0.03 of the largest, in a room above 0.07 (measured in the tests),
and ``ScanMatchingSlam`` keeps the odometry's prediction along such a direction (solution
remapping; Zhang, Kaess, Singh, "On degeneracy of optimization-based state estimation
problems", ICRA 2016).
"""

import dataclasses as dc
import math
from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from drake_sim.base.planar import wrap_angle
from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid


class MatchMap:
    """One level of the pyramid: values in [0, 1] at cell centres, interpolated.

    Args:
        values: (rows, cols) occupancy probabilities or likelihoods; row index grows with y.
        resolution: m per cell.
        origin: (x, y) of the lower-left corner of cell [0, 0], m.
        known: (rows, cols) booleans, cells seen (default: all); points elsewhere weigh 0.
    """

    def __init__(
        self,
        values: np.ndarray,
        resolution: float,
        origin: tuple[float, float],
        known: np.ndarray | None = None,
    ):
        # Padded by one cell of 0.5 so that points just off the grid interpolate smoothly.
        self.values = np.pad(np.asarray(values, dtype=np.float64), 1, constant_values=0.5)
        known = np.ones(np.shape(values), bool) if known is None else np.asarray(known, bool)
        self.known = np.pad(known, 1, constant_values=False)
        self.resolution = float(resolution)
        self.origin = (float(origin[0]), float(origin[1]))

    @classmethod
    def from_grid(
        cls, grid: LogOddsGrid, smoothing: float = 0.0, *, field: float = 0.0, margin: int = 4
    ) -> "MatchMap":
        """A level made from ``grid`` over the cells seen so far plus ``margin`` (all else is
        unknown, 0.5, anyway).

        Args:
            smoothing: blur the probabilities with a Gaussian of this many cells (0: none).
            field: when positive, use a likelihood field instead of the probabilities:
                exp(-d^2 / (2 s^2)) with d the distance to the nearest occupied cell (log-odds
                above 0) and s = ``field`` cells (smooth and single-peaked around each wall).
        """
        rows, cols = grid.shape
        r0, r1, c0, c1 = 0, rows, 0, cols
        if grid.known_box is not None:
            rmin, rmax, cmin, cmax = grid.known_box
            r0, r1 = max(rmin - margin, 0), min(rmax + margin + 1, rows)
            c0, c1 = max(cmin - margin, 0), min(cmax + margin + 1, cols)
        log_odds = grid.log_odds[r0:r1, c0:c1]
        if field > 0:
            occupied = log_odds > 0
            if occupied.any():
                distance = ndimage.distance_transform_edt(~occupied)
                p = np.exp(-0.5 * (distance / field) ** 2)
            else:
                p = np.full(log_odds.shape, 0.5)
        else:
            p = 1.0 / (1.0 + np.exp(-log_odds.astype(np.float64)))
        if smoothing > 0:
            p = ndimage.gaussian_filter(p, smoothing, mode="nearest", truncate=3.0)
        origin = (grid.origin[0] + c0 * grid.resolution, grid.origin[1] + r0 * grid.resolution)
        known = ndimage.binary_dilation(log_odds != 0, np.ones((3, 3), bool))
        return cls(p, grid.resolution, origin, known)

    def interpolate(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bilinear value M (n,) and gradient dM/d(x, y) (n, 2), 1/m, at world points (n, 2)."""
        u = (xy[:, 0] - self.origin[0]) / self.resolution + 0.5  # +1 pad -0.5 centre
        v = (xy[:, 1] - self.origin[1]) / self.resolution + 0.5
        rows, cols = self.values.shape
        off = (u < 0.0) | (u > cols - 1.0) | (v < 0.0) | (v > rows - 1.0)
        u = np.clip(u, 0.0, cols - 1.0)
        v = np.clip(v, 0.0, rows - 1.0)
        j = np.minimum(u.astype(np.int64), cols - 2)
        i = np.minimum(v.astype(np.int64), rows - 2)
        fu, fv = u - j, v - i
        m00 = self.values[i, j]
        m01 = self.values[i, j + 1]
        m10 = self.values[i + 1, j]
        m11 = self.values[i + 1, j + 1]
        bottom = m00 + fu * (m01 - m00)
        top = m10 + fu * (m11 - m10)
        value = bottom + fv * (top - bottom)
        d_du = (1.0 - fv) * (m01 - m00) + fv * (m11 - m10)
        d_dv = top - bottom
        gradient = np.stack([d_du, d_dv], -1) / self.resolution
        gradient[off] = 0.0  # Beyond the padding: unknown, flat.
        return value, gradient

    def is_known(self, xy: np.ndarray) -> np.ndarray:
        """Whether the cells holding world points (n, 2) were seen (or touch a seen cell)."""
        j = np.floor((xy[:, 0] - self.origin[0]) / self.resolution).astype(np.int64) + 1
        i = np.floor((xy[:, 1] - self.origin[1]) / self.resolution).astype(np.int64) + 1
        rows, cols = self.known.shape
        inside = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
        known = np.zeros(len(xy), bool)
        known[inside] = self.known[i[inside], j[inside]]
        return known


@dc.dataclass
class MatchResult:
    """The outcome of ``match_scan``.

    Attributes:
        pose: (3,) x, y (m), yaw (rad) of the base in the world.
        hessian: (3, 3) H of the finest level at ``pose`` (weighted, without the prior).
        scores: (levels,) mean map value M of the end points on seen cells of each level at
            ``pose``, finest first (1: every point on an occupied cell; 0 when none is seen).
        iterations: Gauss-Newton steps taken over all levels.
    """

    pose: np.ndarray
    hessian: np.ndarray
    scores: np.ndarray
    iterations: int


def match_scan(
    maps: Sequence[MatchMap],
    points: np.ndarray,
    initial_pose,
    *,
    iterations: Sequence[int] | int = 4,
    prior_weight: Sequence[float] = (0.0, 0.0, 0.0),
    prior_pose=None,
    tolerance: float = 1e-5,
    hit_directions: np.ndarray | None = None,
    hit_offset: float = 0.0,
) -> MatchResult:
    """Finds the base pose that puts the scan's end points on the map's occupied cells.

    Args:
        maps: the pyramid, finest first (matching runs from the last, coarsest, to the first).
        points: (n, 2) scan end points in the base frame, m.
        initial_pose: (x, y, yaw) to start from (m, rad).
        iterations: Gauss-Newton steps per level (one number, or one per level, finest first).
        prior_weight: W's diagonal for (x, y, yaw): m^-2, m^-2, rad^-2.
        prior_pose: xi_0 (default ``initial_pose``).
        tolerance: a level stops once a step moves less than this (m, and rad).
        hit_directions, hit_offset: where the maps' grids put each hit (``LogOddsGrid``):
            ``hit_offset`` of a level's cell beyond the end point along the unit vector
            (n, 2, base frame). Each level reads the points where its grid put them.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if hit_directions is None or not hit_offset:
        level_points = [points] * len(maps)
    else:
        directions = np.asarray(hit_directions, dtype=np.float64).reshape(-1, 2)
        level_points = [points + hit_offset * m.resolution * directions for m in maps]
    pose = np.array(initial_pose, dtype=np.float64)
    prior = pose.copy() if prior_pose is None else np.array(prior_pose, dtype=np.float64)
    weight = np.diag(np.asarray(prior_weight, dtype=np.float64))
    if isinstance(iterations, int):
        iterations = [iterations] * len(maps)
    steps = 0
    for level in reversed(range(len(maps))):
        points = level_points[level]
        value, jacobian, w = _linearise(maps[level], points, pose)
        cost = _cost(value, w, pose, prior, weight)
        # Start from the better of the coarser level's result and the prediction (docstring).
        if level < len(maps) - 1 and np.any(pose != prior):
            at_prior = _linearise(maps[level], points, prior)
            prior_cost = _cost(at_prior[0], at_prior[2], prior, prior, weight)
            if prior_cost < cost:
                pose, cost = prior.copy(), prior_cost
                value, jacobian, w = at_prior
        for _ in range(iterations[level]):
            weighted = jacobian * w[:, None]
            hessian = weighted.T @ jacobian + weight
            gradient = weighted.T @ (1.0 - value) - weight @ _offset(pose, prior)
            try:
                delta = np.linalg.solve(hessian, gradient)
            except np.linalg.LinAlgError:
                break
            if not np.all(np.isfinite(delta)):
                break
            # Halve a step that makes things worse (a Gauss-Newton step can overshoot).
            for _ in range(4):
                trial = pose + delta
                trial[2] = wrap_angle(trial[2])
                at_trial = _linearise(maps[level], points, trial)
                trial_cost = _cost(at_trial[0], at_trial[2], trial, prior, weight)
                if trial_cost <= cost:
                    break
                delta = 0.5 * delta
            else:
                break
            pose, cost = trial, trial_cost
            value, jacobian, w = at_trial
            steps += 1
            if np.abs(delta).max() < tolerance:
                break
    _, jacobian, w = _linearise(maps[0], level_points[0], pose)
    scores = []
    for match_map, points in zip(maps, level_points, strict=True):
        value, _, w_level = _linearise(match_map, points, pose)
        scores.append(float(value @ w_level / len(points)) if w_level.any() else 0.0)
    return MatchResult(pose, (jacobian * w[:, None]).T @ jacobian, np.array(scores), steps)


def surface_normals(points: np.ndarray, *, k: int = 3, max_gap: float = 0.5) -> np.ndarray:
    """Unit normals (n, 2) of the surfaces under a scan's end points, pointing away from the
    sensor (into the obstacle), from the chord between the points k beams before and after;
    where that chord is longer than ``max_gap`` m (an edge, a lone point) the beam's own
    direction stands in.

    Args:
        points: (n, 2) end points in beam order, in the sensor frame, m.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    length = np.hypot(points[:, 0], points[:, 1])
    normals = points / np.maximum(length, 1e-12)[:, None]
    if len(points) < 2 * k + 1:
        return normals
    chord = np.roll(points, -k, axis=0) - np.roll(points, k, axis=0)
    chord_length = np.hypot(chord[:, 0], chord[:, 1])
    good = (chord_length > 1e-9) & (chord_length < max_gap)
    normal = np.stack([-chord[good, 1], chord[good, 0]], -1) / chord_length[good, None]
    flip = np.sum(normal * points[good], axis=1) < 0
    normal[flip] = -normal[flip]
    normals[good] = normal
    return normals


def normal_spread(points: np.ndarray, *, k: int = 3, max_gap: float = 0.5):
    """How the scan's surface normals spread over directions: eigenvalues (2,), ascending, and
    eigenvectors (2, 2) (columns, in the points' frame) of mean(n n^T) over the normals n of
    the end points (from the points k beams before and after, when they are within
    ``max_gap`` m). A small ratio of the eigenvalues means the surfaces all face one way (a
    corridor): the scan fixes the position across them and nothing along them.

    Args:
        points: (n, 2) end points in beam order, m.
    """
    if len(points) < 2 * k + 1:
        return np.zeros(2), np.eye(2)
    chord = np.roll(points, -k, axis=0) - np.roll(points, k, axis=0)
    length = np.hypot(chord[:, 0], chord[:, 1])
    good = (length > 1e-9) & (length < max_gap)
    if not good.any():
        return np.zeros(2), np.eye(2)
    tangent = chord[good] / length[good, None]
    normal = np.stack([-tangent[:, 1], tangent[:, 0]], -1)
    return np.linalg.eigh(normal.T @ normal / len(normal))


def depth_edges(points: np.ndarray, *, jump: float = 0.3, ratio: float = 3.0) -> int:
    """How many depth discontinuities a scan has: steps in range between consecutive end points
    (sensor frame, beam order) longer than ``jump`` m and ``ratio`` times the steps beside them
    (a wall seen at a grazing angle steps far but evenly). A door's jamb, a pillar, the end of a
    wall: each fixes the position along a corridor whose surfaces' normals all face across it.
    """
    if len(points) < 2:
        return 0
    steps = np.abs(np.diff(np.hypot(points[:, 0], points[:, 1])))
    beside = np.maximum(np.r_[0.0, steps[:-1]], np.r_[steps[1:], 0.0])
    return int(np.count_nonzero(steps > np.maximum(jump, ratio * beside)))


def transform_points(pose, points: np.ndarray) -> np.ndarray:
    """Points (n, 2) of a frame at ``pose`` (x, y, yaw) expressed in the world, m."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + np.asarray(pose[:2], dtype=np.float64)


def _offset(pose: np.ndarray, prior: np.ndarray) -> np.ndarray:
    offset = pose - prior
    offset[2] = wrap_angle(offset[2])
    return offset


def _cost(value, w, pose: np.ndarray, prior: np.ndarray, weight: np.ndarray) -> float:
    """E(xi) of the module docstring, end points weighted by ``w``."""
    offset = _offset(pose, prior)
    return float(w @ (1.0 - value) ** 2 + offset @ weight @ offset)


def _linearise(match_map: MatchMap, points: np.ndarray, pose: np.ndarray):
    """M at the transformed points (n,), the Jacobian of M with respect to the pose (n, 3) and
    the points' weights (n,): 0 on unknown cells, the others sharing a total of n."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world = transform_points(pose, points)
    value, grad = match_map.interpolate(world)
    known = match_map.is_known(world)
    count = known.sum()
    w = known * (len(points) / count) if count else known.astype(np.float64)
    d_yaw_x = -s * points[:, 0] - c * points[:, 1]
    d_yaw_y = c * points[:, 0] - s * points[:, 1]
    jacobian = np.stack([grad[:, 0], grad[:, 1], grad[:, 0] * d_yaw_x + grad[:, 1] * d_yaw_y], -1)
    return value, jacobian, w
