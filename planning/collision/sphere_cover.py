"""Conservative sphere covers of convex shapes (the collision geometry of a robot link).

A convex polytope P (its vertices and polygon faces) is covered by spheres in two stages:

1. Greedy placement: candidate centres are points of a grid inside P, each with the radius
   ``depth + slack`` (depth: distance to P's boundary, so the sphere is the inscribed ball grown
   by ``slack``; a sample no grid point reaches, e.g. at a sharp corner, is a candidate of
   radius ``slack`` itself); the candidate covering most still-uncovered coarse samples
   (surface and interior points) is taken until every sample is covered (greedy set cover).
2. Conservative radii: every point of a dense barycentric grid on each boundary triangle (the
   hull's vertices included) goes to the chosen sphere it is deepest in, and each radius becomes
   the farthest assigned point plus the grid's covering bound ``eps``: on a triangle whose
   sub-triangles have longest edge e, every point is within e / sqrt(3) of a grid node (the
   circumradius bound of a triangle with no angle above 90 degrees, and half the longest edge
   otherwise), so the spheres' union contains P's whole boundary surface. Interior grid
   points are covered too (to the grid spacing), so an object can only be missed when it lies
   entirely inside P between those points.

Each sphere also has an inner radius, its depth: that ball lies inside P, so a collision of
inner balls is a certain collision of the shapes (used to reject without asking Drake).

References:
    T. Thomason, Z. Kingston, L. Kavraki, "Motions in Microseconds via Vectorized
    Sampling-Based Planning", ICRA 2024 (sphere-approximated robots for fast checks).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_MAX_COARSE = 4000  # coarse surface samples for the greedy placement, at most


@dataclass
class SphereSet:
    """Spheres in a body frame B.

    Attributes:
        p_BS: (S, 3) centres, m, in B.
        radius: (S,) outer radii, m: their union contains the shape.
        inner: (S,) inner radii, m: each inner ball lies inside the shape (0: none).
    """

    p_BS: np.ndarray
    radius: np.ndarray
    inner: np.ndarray

    @staticmethod
    def concat(sets: list[SphereSet]) -> SphereSet:
        if not sets:
            return SphereSet(np.zeros((0, 3)), np.zeros(0), np.zeros(0))
        return SphereSet(
            np.vstack([s.p_BS for s in sets]),
            np.concatenate([s.radius for s in sets]),
            np.concatenate([s.inner for s in sets]),
        )

    def transformed(self, R_AB: np.ndarray, p_AB: np.ndarray) -> SphereSet:
        """Returns the same spheres expressed in frame A, given X_AB."""
        return SphereSet(self.p_BS @ R_AB.T + p_AB, self.radius.copy(), self.inner.copy())


def polytope_triangles(vertices: np.ndarray, polygons: list[list[int]]) -> np.ndarray:
    """Fan-triangulates convex polygon faces; returns (T, 3, 3) triangle corners."""
    tris = [
        (vertices[face[0]], vertices[face[k]], vertices[face[k + 1]])
        for face in polygons
        for k in range(1, len(face) - 1)
    ]
    return np.asarray(tris, dtype=float)


def _planes(triangles: np.ndarray) -> np.ndarray:
    """Outward unit normals n and offsets d (n . x + d <= 0 inside), (T, 4), of the
    triangles' planes for a convex polytope (degenerate triangles dropped)."""
    centroid = triangles.reshape(-1, 3).mean(axis=0)
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    norm = np.linalg.norm(n, axis=1)
    keep = norm > 1e-12
    n = n[keep] / norm[keep, None]
    d = -np.einsum("ij,ij->i", n, triangles[keep, 0])
    flip = n @ centroid + d > 0
    n[flip], d[flip] = -n[flip], -d[flip]
    return np.column_stack([n, d])


def _surface_grid(triangles: np.ndarray, spacing: float) -> tuple[np.ndarray, float]:
    """Barycentric grid points on every triangle, with sub-edges at most ``spacing``; returns
    the points and the covering bound eps (every surface point is within eps of one)."""
    points, eps = [], 0.0
    for a, b, c in triangles:
        longest = max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b))
        n = max(1, int(np.ceil(longest / spacing)))
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        mask = i + j <= n
        u, v = i[mask][:, None] / n, j[mask][:, None] / n
        points.append(a + u * (b - a) + v * (c - a))
        eps = max(eps, longest / n / np.sqrt(3.0))
    return np.vstack(points), eps


def _interior_grid(planes: np.ndarray, lo, hi, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Grid points strictly inside the polytope and their depths (distance to the boundary)."""
    axes = [np.arange(lo[k] + spacing / 2, hi[k], spacing) for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    depth = -(grid @ planes[:, :3].T + planes[:, 3]).max(axis=1)
    inside = depth > 1e-9
    return grid[inside], depth[inside]


def cover_polytope(
    vertices: np.ndarray,
    polygons: list[list[int]],
    *,
    slack: float,
    spacing: float,
    dense_spacing: float,
) -> SphereSet:
    """Covers a convex polytope by spheres (see the module docstring).

    Args:
        vertices: (V, 3) vertices, m.
        polygons: faces as lists of vertex indices (convex polygons).
        slack: how far a sphere may reach beyond the inscribed ball at its centre, m (smaller:
            tighter and more spheres).
        spacing: grid step of candidate centres and coarse samples, m.
        dense_spacing: largest sub-edge of the boundary grid that sets the final radii, m.
    """
    vertices = np.asarray(vertices, dtype=float)
    triangles = polytope_triangles(vertices, polygons)
    planes = _planes(triangles)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    # A grid fine enough to put candidates inside thin shapes too.
    step = min(spacing, max(1e-4, 0.5 * float((hi - lo).min())))
    centres, depth = _interior_grid(planes, lo, hi, step)
    centroid = vertices.mean(axis=0)
    centroid_depth = max(0.0, -float((planes[:, :3] @ centroid + planes[:, 3]).max()))
    centres = np.vstack([centres, centroid])
    depth = np.concatenate([depth, [centroid_depth]])
    coarse, _ = _surface_grid(triangles, spacing)
    # The coarse samples only place the spheres (the dense pass below makes the cover
    # conservative), so a thinned set is enough; it bounds the cost on sliver triangles.
    coarse = coarse[:: max(1, len(coarse) // _MAX_COARSE)]
    samples = np.vstack([coarse, vertices, centres])
    reach = depth + slack
    covers = np.empty((len(centres), len(samples)), dtype=bool)
    s2 = (samples**2).sum(1)[None, :]
    for k in range(0, len(centres), 512):  # exactness is not needed here: radii are set below
        c = centres[k : k + 512]
        d2 = (c**2).sum(1)[:, None] + s2 - 2.0 * c @ samples.T
        covers[k : k + 512] = d2 <= (reach[k : k + 512] ** 2)[:, None]
    # Samples that no grid candidate reaches (sharp corners, farther than depth + slack from
    # every grid point) become candidates themselves: on the boundary, so of depth 0 (no inner
    # ball) and reach ``slack``; then every sample is covered, at worst by itself.
    lonely = samples[~covers.any(axis=0)]
    if len(lonely):
        extra = np.maximum(0.0, -(lonely @ planes[:, :3].T + planes[:, 3]).max(axis=1))
        centres, depth = np.vstack([centres, lonely]), np.concatenate([depth, extra])
        reach = depth + slack
        d = np.linalg.norm(lonely[:, None, :] - samples[None, :, :], axis=2)
        covers = np.vstack([covers, d <= reach[-len(lonely) :, None]])
    uncovered = np.ones(len(samples), dtype=bool)
    gain = covers.sum(axis=1)
    chosen = []
    while uncovered.any():
        best = int(np.argmax(gain))
        if gain[best] == 0:  # cannot happen with slack > 0; guards against a bad input
            raise ValueError("sphere cover did not converge")
        chosen.append(best)
        newly = covers[best] & uncovered
        uncovered &= ~newly
        gain -= covers[:, newly].sum(axis=1)
    c, r0, inner = centres[chosen], reach[chosen], depth[chosen]
    dense, eps = _surface_grid(triangles, dense_spacing)
    points = np.vstack([dense, vertices, centres])
    radius = np.zeros(len(c))
    c2 = (c**2).sum(axis=1)[None, :]
    for start in range(0, len(points), 20000):
        chunk = points[start : start + 20000]
        d2 = (chunk**2).sum(axis=1)[:, None] + c2 - 2.0 * chunk @ c.T
        owner = np.argmin(np.sqrt(np.maximum(d2, 0.0)) - r0[None, :], axis=1)
        exact = np.linalg.norm(chunk - c[owner], axis=1)  # the radius itself is exact
        np.maximum.at(radius, owner, exact)
    return SphereSet(c, radius + eps + 1e-9, np.maximum(inner - 1e-9, 0.0))


def box_polytope(size) -> tuple[np.ndarray, list[list[int]]]:
    """Vertices and faces of a box of full extents ``size`` centred at the origin."""
    h = np.asarray(size, dtype=float) / 2
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return signs * h, faces


def cylinder_polytope(radius: float, length: float, sides: int = 16):
    """A prism circumscribing a z-axis cylinder (so covering it covers the cylinder)."""
    outer = radius / np.cos(np.pi / sides)
    angles = 2 * np.pi * np.arange(sides) / sides
    ring = np.column_stack([outer * np.cos(angles), outer * np.sin(angles)])
    vertices = np.vstack(
        [
            np.column_stack([ring, np.full(sides, -length / 2)]),
            np.column_stack([ring, np.full(sides, length / 2)]),
        ]
    )
    faces = [list(range(sides))[::-1], list(range(sides, 2 * sides))]
    faces += [[k, (k + 1) % sides, sides + (k + 1) % sides, sides + k] for k in range(sides)]
    return vertices, faces
