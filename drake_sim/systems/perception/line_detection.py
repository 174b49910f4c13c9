"""Finding a white line on a dark floor in a camera image: plain functions on numpy arrays.

``detect_line(rgb, info, X_GC, config)`` measures where the line is relative to a robot from
one colour image, the camera's pinhole intrinsics ``info`` and the camera's pose X_GC over the
ground. G is the robot's ground frame: its origin on the floor under the robot's reference point,
x forward along the robot's heading, y to its left and z up (``camera_pose_over_ground`` makes
X_GC from the robot body's pose and the camera's pose on it). C is Drake's camera frame (+z
forward along the optical axis, +x right, +y down).

The method:

1. **Pixels of the line.** The floor's level is the image's median grey, the line's the
   brightest 3 x 3 neighbourhood of grey pixels (colourful pixels, such as the background beyond
   the floor's edge, are never the line). Too little contrast between them: no line. Pixels
   brighter than halfway are the line's, once isolated ones (noise) are dropped; each keeps a
   weight from 0 (floor) to 1 (line), so the antialiased edges place the line to a fraction of a
   pixel.
2. **Onto the floor.** Each pixel's centre is back-projected along its ray (pinhole model) to
   the ground plane z = 0 of G, and the ground area its footprint covers is kept, so a far pixel
   (a large patch of floor) weighs more than a near one (a small patch). Pixels above the
   horizon or beyond ``max_range`` are dropped.
3. **The nearest piece of line.** The line pixels are grouped in 8-connected components; pieces
   shorter than ``min_length`` on the floor are noise. The piece with the point nearest to the
   robot is the line (another part of a loop further away is not).
4. **A curve through it.** A circle (or, for a short piece, a straight line) is fitted by
   weighted least squares (Pratt's algebraic fit, which turns smoothly into a line as the
   curvature goes to zero): first to the points within ``seed_radius`` of the nearest point,
   then, round by round, to the points within ``gate`` of the last fit and within a reach that
   grows to ``fit_length`` (so a tight curve is followed, not cut). Each point weighs its pixel
   weight times its footprint area times ``exp(-range / near_scale)``: the near field counts most.
5. **At the robot.** The fitted circle's nearest point to G's origin (followed back under the
   robot, which the camera cannot see) gives the line's lateral offset, its heading relative
   to the robot, and its curvature. Where the curvature changes (a straight meeting a turn) the
   one circle through what the camera sees ahead is a compromise: it finds the turn ahead
   early, with a heading a few degrees off at the robot.

Measured on 80 x 60 images rendered by VTK (camera 0.25 m up, pitched 60 degrees down, 80
degrees vertical field of view), where the curvature is the same under the robot as ahead of
it: offsets within 3 mm (median under 1 mm), headings within 1.5 degrees (median under 0.5),
curvature within about 0.1 /m; unchanged with Gaussian noise of 15 grey levels and 1 % salt and
pepper. About 7 ms per image.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.sensors import CameraInfo

from drake_sim.base.errors import ConfigError


@dc.dataclass
class LineDetectorConfig:
    """Thresholds and the shape of the fit. Grey levels are 0 to 255, lengths metres."""

    delay: float = 0.005  # s after each camera frame at which the LineDetector reads it.
    min_contrast: float = 60.0  # grey levels the line must stand above the floor's median.
    threshold: float = 0.5  # where between the floor's level and the line's a pixel is line.
    max_chroma: float = 30.0  # grey levels between a pixel's channels (3 x 3 mean) for grey.
    max_range: float = 1.2  # m, ground points further from G's origin are ignored.
    min_length: float = 0.05  # m, shorter pieces of bright pixels are noise.
    seed_radius: float = 0.08  # m, around the nearest point, for the line's first direction.
    fit_length: float = 0.3  # m, along the line from the nearest point, the fit's reach.
    gate: float = 0.04  # m, lateral distance from the previous fit for a point to be used.
    near_scale: float = 0.3  # m, weights fall off as exp(-range / near_scale).


def check_line_detector_config(config: LineDetectorConfig, where: str = "line_detector"):
    """Returns ``config`` if its values are usable; raises ``ConfigError`` naming the key."""
    for f in dc.fields(config):
        value = getattr(config, f.name)
        if not (math.isfinite(value) and (value > 0 or (f.name == "delay" and value == 0))):
            bound = "zero or positive" if f.name == "delay" else "positive"
            raise ConfigError(f"{where}: '{f.name}' must be {bound}, got {value!r}")
    if config.threshold >= 1:
        raise ConfigError(f"{where}: 'threshold' must be below 1, got {config.threshold!r}")
    return config


@dc.dataclass(frozen=True)
class LineMeasurement:
    """Where the line is relative to the robot, in its ground frame G (x forward, y left).

    ``offset`` is the signed distance from G's origin to the line, positive when the line is
    on the robot's left (steer left to reach it); ``heading`` the line's direction at its point
    nearest the robot, from G's x axis, positive to the left (the direction taken is the one
    going forward, away from the robot); ``curvature`` its curvature there, positive turning
    left. When ``found`` is false the numbers are zero and ``reason`` says why.
    """

    found: bool
    offset: float = 0.0  # m.
    heading: float = 0.0  # rad, in (-pi, pi].
    curvature: float = 0.0  # 1/m.
    distance: float = 0.0  # m, from G's origin to the nearest line pixel on the floor.
    reason: str = ""


def camera_pose_over_ground(X_WB: RigidTransform, X_BC: RigidTransform) -> RigidTransform:
    """Returns X_GC: the camera's pose in the ground frame G under a robot body B.

    G's origin is the point of the floor (z = 0 in W) below B's origin; its x axis is B's x axis
    projected onto the floor, z up. So X_GC follows B's roll, pitch and height but not its yaw
    or position: what a camera on a balancing robot needs to back-project its pixels.
    """
    R_WB = X_WB.rotation().matrix()
    yaw = math.atan2(R_WB[1, 0], R_WB[0, 0])
    R_GB = RotationMatrix.MakeZRotation(-yaw) @ X_WB.rotation()
    X_GB = RigidTransform(R_GB, [0.0, 0.0, X_WB.translation()[2]])
    return X_GB @ X_BC


def ground_points(info: CameraInfo, X_GC: RigidTransform, max_range: float):
    """Back-projects every pixel onto the ground plane z = 0 of G.

    Returns:
        p_GQ: (height, width, 2) x, y of each pixel centre's ground point, m (NaN where the ray
            misses the ground, or meets it further than ``max_range`` from G's origin).
        area: (height, width) the ground area each pixel's footprint covers, m^2 (NaN likewise).
    """
    w, h = info.width(), info.height()
    centres = _back_project(*np.meshgrid(np.arange(w), np.arange(h)), info, X_GC)
    u, v = np.meshgrid(np.arange(w + 1) - 0.5, np.arange(h + 1) - 0.5)
    corners = _back_project(u, v, info, X_GC)
    d1 = corners[1:, 1:] - corners[:-1, :-1]
    d2 = corners[1:, :-1] - corners[:-1, 1:]
    area = 0.5 * np.abs(d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])
    far = ~(np.hypot(centres[..., 0], centres[..., 1]) <= max_range) | ~np.isfinite(area)
    centres[far] = np.nan
    area[far] = np.nan
    return centres, area


def _back_project(u, v, info: CameraInfo, X_GC: RigidTransform) -> np.ndarray:
    """Returns the (..., 2) ground points (z = 0 in G) of the rays through pixel coordinates
    (u, v), NaN where a ray does not go down to the ground."""
    d_C = np.stack(
        [(u - info.center_x()) / info.focal_x(), (v - info.center_y()) / info.focal_y()], axis=-1
    )
    d_C = np.concatenate([d_C, np.ones(d_C.shape[:-1] + (1,))], axis=-1)
    d_G = d_C @ X_GC.rotation().matrix().T
    p_GC = X_GC.translation()
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d_G[..., 2] < -1e-9, -p_GC[2] / d_G[..., 2], np.nan)
    return p_GC[:2] + t[..., None] * d_G[..., :2]


def line_pixels(rgb: np.ndarray, config: LineDetectorConfig):
    """Finds the bright grey pixels of an (h, w, 3 or 4) uint8 image.

    Returns:
        (mask, weight, reason): the (h, w) boolean mask of line pixels, the (h, w) weight of
        every pixel (0 at the floor's level to 1 at the line's), and "" or why there is no line.
    """
    rgb = np.asarray(rgb)[..., :3].astype(float)
    grey = rgb.mean(axis=-1)
    smooth = _box3(rgb)
    grey_ok = smooth.max(axis=-1) - smooth.min(axis=-1) <= config.max_chroma
    # The floor's level: the median of the grey pixels only, so that a coloured background seen
    # past the floor's edge (in turns, from a high camera) does not raise it.
    floor = float(np.median(grey[grey_ok])) if grey_ok.any() else float(np.median(grey))
    candidates = _box3(grey[..., None])[..., 0][grey_ok]
    peak = float(candidates.max()) if candidates.size else floor
    if peak - floor < config.min_contrast:
        empty = np.zeros(grey.shape, bool)
        return empty, np.zeros(grey.shape), f"no line: contrast {peak - floor:.0f} grey levels"
    mask = (grey > floor + config.threshold * (peak - floor)) & grey_ok
    neighbours = _box3(mask[..., None].astype(float))[..., 0] * 9 - mask
    mask &= neighbours >= 2  # drops isolated pixels and pairs: noise, not a line
    weight = np.clip((grey - floor) / (peak - floor), 0.0, 1.0)
    return mask, weight, ""


def _box3(image: np.ndarray) -> np.ndarray:
    """Returns the 3 x 3 mean of an (h, w, c) image (edges repeated)."""
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = image.shape[:2]
    total = sum(padded[i : i + h, j : j + w] for i in range(3) for j in range(3))
    return total / 9.0


def label_components(mask: np.ndarray) -> np.ndarray:
    """Labels the 8-connected components of a boolean image: 0 off the mask, 1, 2, ... on it
    (the order in which they are met scanning rows from the top)."""
    parent = [0]

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    runs, previous = [], []
    for r, row in enumerate(mask):
        edges = np.diff(np.concatenate([[0], row.astype(np.int8), [0]]))
        current = []
        for start, end in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
            label = 0
            for p_start, p_end, p_label in previous:
                if p_start <= end and p_end >= start:  # touching, diagonals included
                    if label == 0:
                        label = find(p_label)
                    else:
                        a, b = find(label), find(p_label)
                        parent[max(a, b)] = min(a, b)
                        label = min(a, b)
            if label == 0:
                label = len(parent)
                parent.append(label)
            current.append((start, end, label))
            runs.append((r, start, end, label))
        previous = current
    labels = np.zeros(mask.shape, int)
    roots = {}
    for r, start, end, label in runs:
        labels[r, start:end] = roots.setdefault(find(label), len(roots) + 1)
    return labels


def nearest_piece(labels: np.ndarray, p_GQ: np.ndarray, config: LineDetectorConfig):
    """Returns the mask of the component (see ``label_components``) with the ground point
    nearest G's origin among those at least ``min_length`` long on the floor, or None."""
    best, best_range = None, math.inf
    for label in range(1, int(labels.max()) + 1):
        points = p_GQ[labels == label]
        points = points[np.isfinite(points[:, 0])]
        if len(points) < 3:
            continue
        if np.linalg.norm(points.max(axis=0) - points.min(axis=0)) < config.min_length:
            continue
        nearest = float(np.min(np.hypot(points[:, 0], points[:, 1])))
        if nearest < best_range:
            best, best_range = label, nearest
    return None if best is None else labels == best


def fit_curve(points: np.ndarray, weights: np.ndarray, config: LineDetectorConfig):
    """Fits a circle (or a straight line) to the ground points of one piece of line.

    The curve is ``f(p) = A |p - p0|^2 + B (x - x0) + C (y - y0) + D = 0`` with
    ``B^2 + C^2 - 4 A D = 1``, Pratt's normalisation, under which ``|grad f| = 1`` on the curve, so
    ``f`` is the signed distance near it and A = 0 is a straight line (V. Pratt, "Direct
    least-squares fitting of algebraic surfaces", SIGGRAPH 1987). p0 is the point nearest G's
    origin. The fit starts from the principal axis of the points within ``seed_radius`` of p0
    and grows: each round keeps the points within ``gate`` of the last curve and within a reach
    of p0 that grows to ``fit_length``. A piece shorter than ``2 * seed_radius`` is fitted with a
    straight line (its curvature would be noise).

    Args:
        points: (n, 2) ground points in G, m.
        weights: (n,) their weights (pixel weight times footprint area).

    Returns:
        (p0, v, t0) with v = [A, B, C, D] and t0 the forward unit direction at p0, or None when
        too few points lie near p0.
    """
    ranges = np.hypot(points[:, 0], points[:, 1])
    p0 = points[np.argmin(ranges)]
    local = points - p0
    weights = weights * np.exp(-ranges / config.near_scale)
    used = np.hypot(local[:, 0], local[:, 1]) <= config.seed_radius
    if np.count_nonzero(used) < 3:
        return None
    v = _line_fit(local[used], weights[used])
    for reach in np.linspace(2 * config.seed_radius, config.fit_length, 4):
        gated = (np.abs(_implicit(v, local)) <= config.gate) & (
            np.hypot(local[:, 0], local[:, 1]) <= reach
        )
        if np.count_nonzero(gated) < 3:
            break
        used = gated
        span = np.max(np.hypot(local[used, 0], local[used, 1]))
        fit = _pratt_fit if span >= 2 * config.seed_radius else _line_fit
        v = fit(local[used], weights[used])
    t0 = np.array([-v[2], v[1]])  # the tangent at p0: grad f at p0 = (B, C) turned left
    return p0, v, t0 if t0[0] >= 0 else -t0


def _implicit(v: np.ndarray, local: np.ndarray) -> np.ndarray:
    return v[0] * np.einsum("ij,ij->i", local, local) + local @ v[1:3] + v[3]


def _line_fit(local: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The weighted total-least-squares line as [0, B, C, D] (|(B, C)| = 1)."""
    mean = np.average(local, axis=0, weights=weights)
    centred = local - mean
    _, vectors = np.linalg.eigh((centred * weights[:, None]).T @ centred)
    normal = vectors[:, 0]
    return np.array([0.0, normal[0], normal[1], -normal @ mean])


def _pratt_fit(local: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The weighted Pratt circle fit as [A, B, C, D] with B^2 + C^2 - 4 A D = 1."""
    Z = np.column_stack([np.einsum("ij,ij->i", local, local), local, np.ones(len(local))])
    M = (Z * weights[:, None]).T @ Z / np.sum(weights)
    N_inv = np.array([[0, 0, 0, -0.5], [0, 1, 0, 0], [0, 0, 1, 0], [-0.5, 0, 0, 0]])
    values, vectors = np.linalg.eig(N_inv @ M)
    values, vectors = np.real(values), np.real(vectors)
    norms = vectors[1] ** 2 + vectors[2] ** 2 - 4 * vectors[0] * vectors[3]
    ok = (norms > 1e-12) & (values > -1e-12)
    if not np.any(ok):
        return _line_fit(local, weights)
    i = np.flatnonzero(ok)[np.argmin(values[ok])]
    return vectors[:, i] / np.sqrt(norms[i])


def detect_line(
    rgb: np.ndarray,
    info: CameraInfo,
    X_GC: RigidTransform,
    config: LineDetectorConfig,
    ground: tuple[np.ndarray, np.ndarray] | None = None,
) -> LineMeasurement:
    """Measures the line's offset, heading and curvature relative to the robot from one image.

    Args:
        rgb: (h, w, 3 or 4) uint8 colour image of the camera ``info`` (Drake's ``ImageRgba8U``
            ``data`` will do).
        info: the camera's intrinsics (pixels).
        X_GC: the camera frame C's pose in the robot's ground frame G (see the module).
        config: thresholds and fit settings.
        ground: ``ground_points(info, X_GC, config.max_range)`` if already computed.

    Returns:
        The measurement, or ``found=False`` with the reason.
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[:2] != (info.height(), info.width()):
        return LineMeasurement(False, reason=f"no image of {info.width()}x{info.height()} pixels")
    mask, weight, reason = line_pixels(rgb, config)
    if reason:
        return LineMeasurement(False, reason=reason)
    p_GQ, area = ground if ground is not None else ground_points(info, X_GC, config.max_range)
    piece = nearest_piece(label_components(mask), p_GQ, config)
    if piece is None:
        return LineMeasurement(False, reason="no piece of line long enough on the floor")
    grown = _box3(piece[..., None].astype(float))[..., 0] > 0  # the antialiased edges too
    grown &= np.isfinite(area)
    fit = fit_curve(p_GQ[grown], weight[grown] * area[grown], config)
    if fit is None:
        return LineMeasurement(False, reason="too few line points near the robot")
    p0, v, t0 = fit
    return _at_robot(p0, v, t0, float(np.hypot(*p0)))


def _at_robot(p0: np.ndarray, v: np.ndarray, t0: np.ndarray, distance: float) -> LineMeasurement:
    """The measurement at the fitted curve's point F nearest G's origin Q, the curve taken in
    the direction of ``t0`` at p0 (see ``fit_curve``)."""
    A, grad0 = v[0], v[1:3]
    sign = 1.0 if (-grad0[1] * t0[0] + grad0[0] * t0[1]) >= 0 else -1.0  # t = sign * J grad f
    q = -p0  # Q in coordinates relative to p0
    if abs(A) > 1e-9:
        centre = -grad0 / (2 * A)
        radial = q - centre
        foot = centre + radial / (2 * abs(A) * max(np.hypot(*radial), 1e-12))
    else:
        foot = q - (grad0 @ q + v[3]) * grad0
    grad = 2 * A * foot + grad0
    tangent = sign * np.array([-grad[1], grad[0]]) / np.hypot(*grad)
    d = foot - q
    return LineMeasurement(
        found=True,
        offset=float(tangent[0] * d[1] - tangent[1] * d[0]),
        heading=math.atan2(tangent[1], tangent[0]),
        curvature=float(2 * A * sign),
        distance=distance,
    )
