"""Exact casting of a planar fan of rays against triangles and analytic shapes.

The beams start at the sensor frame S's origin and lie in S's xy plane, at angles
``angle_min + i * angle_increment`` from its x axis. The geometry (``Shapes``, given in the
world frame W) is cast exactly in floating point, in two ways:

* Polyhedra are triangles (``box_triangles``, ``polygon_mesh_triangles``). A triangle can only
  be hit where it crosses S's xy plane, so each crossing triangle is cut to a 2D segment in
  that plane and the beams are intersected with the segments in 2D. Each segment is tested only
  against the beams within the angle it subtends from the origin (a few beams for a small
  triangle), so a mesh of thousands of triangles costs little more than its crossing ones. That
  loop is compiled with numba (``cache=True``): the first call in a fresh install compiles it
  (about 1 s); later processes load it (about 0.3 s on the first scan).
* Spheres, ellipsoids, cylinders, capsules and half spaces (``Primitives``) are intersected
  analytically in their own frame (a quadratic per surface), vectorised over shapes x beams.
  Shapes whose bounding sphere is farther than ``max_distance`` from S's origin or does not
  reach S's xy plane are skipped first.

A beam reports the distance to the first surface it crosses at a positive distance (from inside
a solid that is its exit). Reading these shapes from a SceneGraph is
``drake_sim.systems.sensors.scene_shapes``'s job.
"""

import dataclasses as dc

import numpy as np
from numba import njit

SPHERE, ELLIPSOID, CYLINDER, CAPSULE, HALF_SPACE = range(5)
"""Kinds of analytic primitives (``Primitives.kind``)."""

_SEGMENT_SLACK = 1e-9  # Relative slack on a segment's ends, so that shared edges leak no beam.


@dc.dataclass(frozen=True)
class Fan:
    """A planar fan of ``count`` beams in S's xy plane, uniformly spaced in angle (rad)."""

    angle_min: float  # rad, from S's x axis towards its y axis.
    angle_increment: float  # rad, between consecutive beams.
    count: int  # beams.

    def angles(self) -> np.ndarray:
        """Returns the beams' angles (rad)."""
        return self.angle_min + self.angle_increment * np.arange(self.count)


@dc.dataclass
class Primitives:
    """Analytic shapes with their poses in a frame A (world or sensor): kinds (P,), rotations
    ``R_AG`` (P, 3, 3), origins ``p_AG`` (P, 3), sizes (P, 3) in m (sphere: radius; ellipsoid:
    semi-axes; cylinder and capsule: radius, length; half space: unused) and bounding radii
    (P,) in m (inf for a half space)."""

    kind: np.ndarray
    R_AG: np.ndarray
    p_AG: np.ndarray
    size: np.ndarray
    radius: np.ndarray

    @staticmethod
    def empty() -> "Primitives":
        """Returns a set of no shapes."""
        return Primitives(
            np.zeros(0, int), np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
        )

    @staticmethod
    def concatenate(parts: "list[Primitives]") -> "Primitives":
        """Returns the shapes of all ``parts`` (all in the same frame)."""
        if not parts:
            return Primitives.empty()
        return Primitives(*(np.concatenate([getattr(p, f.name) for p in parts]) for f in _FIELDS))

    def posed(self, R_BA: np.ndarray, p_BA: np.ndarray) -> "Primitives":
        """Returns these shapes expressed in B, given A's pose in B."""
        return dc.replace(self, R_AG=R_BA @ self.R_AG, p_AG=self.p_AG @ R_BA.T + p_BA)


_FIELDS = dc.fields(Primitives)


@dc.dataclass
class Shapes:
    """Geometry in one frame A: triangles (T, 3, 3) (vertices, m) and analytic primitives."""

    triangles: np.ndarray
    primitives: Primitives

    @staticmethod
    def empty() -> "Shapes":
        """Returns no geometry."""
        return Shapes(np.zeros((0, 3, 3)), Primitives.empty())

    def posed(self, R_BA: np.ndarray, p_BA: np.ndarray) -> "Shapes":
        """Returns this geometry expressed in B, given A's pose in B (rotation, origin)."""
        return Shapes(self.triangles @ R_BA.T + p_BA, self.primitives.posed(R_BA, p_BA))

    @staticmethod
    def concatenate(parts: "list[Shapes]") -> "Shapes":
        """Returns the geometry of all ``parts`` (all in the same frame)."""
        if not parts:
            return Shapes.empty()
        return Shapes(
            np.concatenate([p.triangles for p in parts]),
            Primitives.concatenate([p.primitives for p in parts]),
        )


def cast_fan(shapes: Shapes, R_WS: np.ndarray, p_WS: np.ndarray, fan: Fan, max_distance: float):
    """Returns the distance (m) along each beam of ``fan`` to the first surface of ``shapes``
    (given in W), inf where there is none within ``max_distance``.

    Args:
        shapes: the geometry, expressed in the world frame W.
        R_WS: (3, 3) the sensor frame's orientation in W.
        p_WS: (3,) the sensor's origin in W, m.
        fan: the beams, in S's xy plane.
        max_distance: m, farther hits are reported as inf (and far shapes skipped).
    """
    ranges = np.full(fan.count, np.inf)
    if len(shapes.triangles):
        cast_triangles(shapes.triangles, R_WS, p_WS, fan, max_distance, ranges)
    if len(shapes.primitives.kind):
        R_SW = R_WS.T
        primitives_S = shapes.primitives.posed(R_SW, -R_SW @ p_WS)
        cast_primitives(primitives_S, fan, max_distance, ranges)
    ranges[ranges > max_distance] = np.inf
    return ranges


def cast_triangles(triangles_W, R_WS, p_WS, fan: Fan, max_distance: float, ranges) -> None:
    """Lowers ``ranges`` to the beams' first hits on triangles (T, 3, 3) given in W.

    Each triangle crossing S's xy plane (some vertex above it, some not) is cut to the segment
    where it crosses, then intersected in 2D with the beams within the angle it subtends
    (``_triangle_hits``, compiled).
    """
    angles = fan.angles()
    _triangle_hits(
        np.ascontiguousarray(triangles_W, dtype=float).reshape(-1, 9),
        np.ascontiguousarray(R_WS, dtype=float),
        np.ascontiguousarray(p_WS, dtype=float),
        float(fan.angle_min),
        float(fan.angle_increment),
        np.cos(angles),
        np.sin(angles),
        float(max_distance),
        ranges,
    )


@njit(cache=True)
def _triangle_hits(V, R_WS, p_WS, angle_min, increment, cos_beam, sin_beam, max_distance, out):
    """``cast_triangles``' loop: V (T, 9) vertices in W; ``out`` (n,) ranges, lowered in place."""
    two_pi = 2.0 * np.pi
    count = out.shape[0]
    xyz = np.empty((3, 3))  # the vertices in S
    for t in range(V.shape[0]):
        n_above = 0
        for k in range(3):
            dx = V[t, 3 * k] - p_WS[0]
            dy = V[t, 3 * k + 1] - p_WS[1]
            dz = V[t, 3 * k + 2] - p_WS[2]
            for axis in range(3):
                xyz[k, axis] = dx * R_WS[0, axis] + dy * R_WS[1, axis] + dz * R_WS[2, axis]
            if xyz[k, 2] > 0.0:
                n_above += 1
        if n_above == 0 or n_above == 3:
            continue
        lone = 0  # the vertex alone on its side of the plane: both its edges cross
        for k in range(3):
            if (xyz[k, 2] > 0.0) == (n_above == 1):
                lone = k
        i0, i1, i2 = lone, (lone + 1) % 3, (lone + 2) % 3
        w1 = xyz[i0, 2] / (xyz[i0, 2] - xyz[i1, 2])
        w2 = xyz[i0, 2] / (xyz[i0, 2] - xyz[i2, 2])
        ax = xyz[i0, 0] + w1 * (xyz[i1, 0] - xyz[i0, 0])
        ay = xyz[i0, 1] + w1 * (xyz[i1, 1] - xyz[i0, 1])
        ex = xyz[i0, 0] + w2 * (xyz[i2, 0] - xyz[i0, 0]) - ax
        ey = xyz[i0, 1] + w2 * (xyz[i2, 1] - xyz[i0, 1]) - ay
        e2 = ex * ex + ey * ey
        along = 0.0 if e2 == 0.0 else min(max(-(ax * ex + ay * ey) / e2, 0.0), 1.0)
        cx, cy = ax + along * ex, ay + along * ey
        if cx * cx + cy * cy > max_distance * max_distance:
            continue
        alpha = np.arctan2(ay, ax)
        delta = np.arctan2(ay + ey, ax + ex) - alpha
        delta = (delta + np.pi) % two_pi - np.pi
        start = (alpha + min(delta, 0.0) - angle_min) % two_pi
        span = abs(delta)
        # The subtended angles as beam indices; an interval that wraps past angle_min + 2 pi
        # is also tried 2 pi earlier.
        for shift in (0.0, two_pi):
            lo, hi = start - shift, start - shift + span
            if increment > 0.0:
                first = max(int(np.floor(lo / increment)), 0)
                last = min(int(np.ceil(hi / increment)), count - 1)
            else:
                first = 0 if lo <= 1e-12 and hi >= -1e-12 else count
                last = 0
            for i in range(first, last + 1):
                ux, uy = cos_beam[i], sin_beam[i]
                denominator = ux * ey - uy * ex
                if denominator == 0.0:
                    continue
                s = (ax * uy - ay * ux) / denominator
                if s < -_SEGMENT_SLACK or s > 1.0 + _SEGMENT_SLACK:
                    continue
                r = (ax * ey - ay * ex) / denominator
                if 0.0 < r < out[i]:
                    out[i] = r
            if hi < two_pi - increment - 1e-9:
                break


def cast_primitives(primitives_S: Primitives, fan: Fan, max_distance: float, ranges) -> None:
    """Lowers ``ranges`` to the beams' first hits on analytic shapes posed in S."""
    p = primitives_S
    reach = np.linalg.norm(p.p_AG, axis=1) - p.radius <= max_distance
    near_plane = np.abs(p.p_AG[:, 2]) <= p.radius
    keep = reach & near_plane
    if not keep.any():
        return
    theta = fan.angles()
    c, s = np.cos(theta), np.sin(theta)
    for kind in np.unique(p.kind[keep]):
        chosen = keep & (p.kind == kind)
        R, size = p.R_AG[chosen], p.size[chosen]
        o = -np.einsum("pji,pj->pi", R, p.p_AG[chosen])  # S's origin in G, (P, 3)
        d = c[None, :, None] * R[:, None, 0, :] + s[None, :, None] * R[:, None, 1, :]
        t = _HITS[kind](o[:, None, :], d, size[:, None, :])
        np.minimum(ranges, t.min(axis=0), out=ranges)


def _both_roots(A, B, C):
    """Both roots t of A t^2 + 2 B t + C = 0 (A > 0), elementwise; nan where there are none."""
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(B * B - A * C)
        return (-B - root) / A, (-B + root) / A


def _first_positive_root(A, B, C):
    """The smallest positive root of A t^2 + 2 B t + C = 0 (inf if none), elementwise."""
    t1, t2 = _both_roots(A, B, C)
    return np.where(t1 > 0.0, t1, np.where(t2 > 0.0, t2, np.inf))


def _positive(t, valid):
    return np.where(valid & (t > 0.0), t, np.inf)


def _hit_sphere(o, d, size):
    r = size[..., 0]
    return _first_positive_root(_dot(d, d), _dot(o, d), _dot(o, o) - r * r)


def _hit_ellipsoid(o, d, size):
    o, d = o / size, d / size  # the unit sphere, with the same ray parameter t
    return _first_positive_root(_dot(d, d), _dot(o, d), _dot(o, o) - 1.0)


def _side(o, d, r, half_length):
    """Both crossings of the infinite cylinder of radius r about z, kept where |z| <= h."""
    A = d[..., 0] ** 2 + d[..., 1] ** 2
    B = o[..., 0] * d[..., 0] + o[..., 1] * d[..., 1]
    C = o[..., 0] ** 2 + o[..., 1] ** 2 - r * r
    hits = []
    for t in _both_roots(A, B, C):
        with np.errstate(invalid="ignore"):
            z = o[..., 2] + t * d[..., 2]
        hits.append(_positive(t, np.abs(z) <= half_length))
    return np.minimum(*hits)


def _hit_cylinder(o, d, size):
    r, h = size[..., 0], 0.5 * size[..., 1]
    t = _side(o, d, r, h)
    for cap in (h, -h):
        with np.errstate(divide="ignore", invalid="ignore"):
            t_cap = (cap - o[..., 2]) / d[..., 2]
            x = o[..., 0] + t_cap * d[..., 0]
            y = o[..., 1] + t_cap * d[..., 1]
        t = np.minimum(t, _positive(t_cap, x * x + y * y <= r * r))
    return t


def _hit_capsule(o, d, size):
    r, h = size[..., 0], 0.5 * size[..., 1]
    t = _side(o, d, r, h)
    for end in (h, -h):
        o_end = o - np.stack([np.zeros_like(end), np.zeros_like(end), end], axis=-1)
        t = np.minimum(
            t, _first_positive_root(_dot(d, d), _dot(o_end, d), _dot(o_end, o_end) - r * r)
        )
    return t


def _hit_half_space(o, d, size):
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[..., 2] / d[..., 2]
    return _positive(t, np.isfinite(t))


def _dot(u, v):
    return np.einsum("...i,...i->...", u, v)


_HITS = {
    SPHERE: _hit_sphere,
    ELLIPSOID: _hit_ellipsoid,
    CYLINDER: _hit_cylinder,
    CAPSULE: _hit_capsule,
    HALF_SPACE: _hit_half_space,
}


def box_triangles(size) -> np.ndarray:
    """Returns the 12 triangles (12, 3, 3) of a box of ``size`` (m) centred on the origin."""
    h = 0.5 * np.asarray(size, dtype=float)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
    faces = [  # quads by corner index (bit 2: x, bit 1: y, bit 0: z)
        (0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3),
    ]  # fmt: skip
    triangles = [(q[0], q[1], q[2]) for q in faces] + [(q[0], q[2], q[3]) for q in faces]
    return corners[np.array(triangles)]


def polygon_mesh_triangles(mesh) -> np.ndarray:
    """Returns the triangles (T, 3, 3) of a Drake ``PolygonSurfaceMesh`` (fans of its faces)."""
    vertices = np.array([mesh.vertex(i) for i in range(mesh.num_vertices())])
    data, triangles, k = list(mesh.face_data()), [], 0
    while k < len(data):
        n, corners = data[k], data[k + 1 : k + 1 + data[k]]
        triangles += [(corners[0], corners[i], corners[i + 1]) for i in range(1, n - 1)]
        k += n + 1
    return vertices[np.array(triangles, dtype=np.int64)].reshape(-1, 3, 3)
