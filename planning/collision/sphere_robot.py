"""Sphere models of a robot's collision geometry and of held objects, cached on disk.

``robot_spheres`` covers every collision geometry of the given bodies (``sphere_cover``) and
returns the spheres in each body's frame. Drake checks a ``Convex`` or ``Mesh`` as the convex
hull of its vertices, so that hull (``Shape.GetConvexHull``) is what is covered; boxes are
covered as polytopes, cylinders through a circumscribed prism, spheres are kept as they are.
Covers are written to ``cache_dir()/spheres/<hash>.npy``, the hash taken over the covered
polytopes, their poses, the cover parameters and the cover code itself, so a changed mesh,
option or algorithm regenerates them. ``held_cover`` covers an object the robot holds, in its own
frame, and caches it the same way (``held-<hash>.npy``).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np
from pydrake.geometry import Box, Convex, Cylinder, Mesh, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.tree import BodyIndex

from drake_sim.base.resources import cache_dir
from planning.collision.sphere_cover import (
    SphereSet,
    box_polytope,
    cover_polytope,
    cylinder_polytope,
)

SPACING = 0.01  # m, grid of candidate centres and coarse samples
DENSE_SPACING = 0.002  # m, boundary grid that sets the final radii (eps <= 1.2 mm)
_CELLS = 15  # grid cells along the largest extent of a held object, at most
# Grid cells in a robot shape's bounding box, at most: a larger shape (a mobile base, a
# pedestal) gets a coarser grid, so that its cover stays within memory and seconds (every arm
# link seen, Panda and UR5, stays below it: at most 9,240 cells).
_MAX_GRID_CELLS = 12_000
# The cover algorithm's code (this module and sphere_cover): part of every cache key, so a change
# of the algorithm builds new covers without a hand-bumped version.
_COVER_CODE = b"".join(
    (Path(__file__).parent / name).read_bytes() for name in ("sphere_robot.py", "sphere_cover.py")
)


def shape_polytope(shape):
    """Returns (vertices, polygons, exact_sphere_radius, has_inner) describing a Drake shape:
    a polytope that contains it, or a sphere radius for a ``Sphere``.

    Raises:
        NotImplementedError: for shapes other than Convex, Mesh, Box, Cylinder, Sphere.
    """
    if isinstance(shape, Sphere):
        return None, None, shape.radius(), True
    if isinstance(shape, Box):
        v, f = box_polytope(shape.size())
        return v, f, None, True
    if isinstance(shape, Cylinder):
        v, f = cylinder_polytope(shape.radius(), shape.length())
        return v, f, None, False  # the prism's inner balls may leave the cylinder
    if isinstance(shape, Convex | Mesh):
        hull = shape.GetConvexHull()
        v = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
        data, polygons, k = hull.face_data(), [], 0
        while k < len(data):
            polygons.append(list(data[k + 1 : k + 1 + data[k]]))
            k += data[k] + 1
        return v, polygons, None, True
    raise NotImplementedError(f"no sphere cover for {type(shape).__name__}")


def cover_shape(shape, X_BG, slack: float, *, scaled: bool = False) -> SphereSet:
    """Covers a Drake shape posed at X_BG (a RigidTransform) by spheres in frame B.

    Args:
        scaled: grids scale with the shape (at least ``SPACING``, at most ``_CELLS`` cells
            along its largest extent), so that large held objects stay cheap to cover.
            Otherwise the grids are ``SPACING`` and ``DENSE_SPACING``, coarsened alike for a
            shape whose bounding box holds more than ``_MAX_GRID_CELLS`` cells (the cover stays
            conservative: its radii grow with the dense grid's step).
    """
    v, polygons, sphere_radius, has_inner = shape_polytope(shape)
    if sphere_radius is not None:
        cover = SphereSet(np.zeros((1, 3)), np.array([sphere_radius]), np.array([sphere_radius]))
    else:
        spacing, dense = SPACING, DENSE_SPACING
        extent = np.ptp(v, axis=0)
        if scaled:
            spacing = max(SPACING, float(extent.max()) / _CELLS)
        else:
            cells = float(np.prod(np.ceil(extent / SPACING)))
            if cells > _MAX_GRID_CELLS:
                spacing = SPACING * (cells / _MAX_GRID_CELLS) ** (1.0 / 3.0)
        dense = spacing * DENSE_SPACING / SPACING
        cover = cover_polytope(v, polygons, slack=slack, spacing=spacing, dense_spacing=dense)
        if not has_inner:
            cover.inner[:] = 0.0
    return cover.transformed(X_BG.rotation().matrix(), X_BG.translation())


def shape_hull(shape, X_BG) -> tuple[np.ndarray, float]:
    """(vertices (K, 3) in frame B, radius, m): a Drake shape posed at X_BG as the convex hull
    of the vertices swept by a ball of that radius, which contains it (``hull_kernel``): a
    ``Convex`` or ``Mesh`` as the hull Drake checks, a box as its corners, a cylinder as the
    prism around it (``shape_polytope``), a sphere as its centre and radius."""
    v, _, radius, _ = shape_polytope(shape)
    swept = 0.0
    if v is None:
        v, swept = np.zeros((1, 3)), float(radius)
    R, p = X_BG.rotation().matrix(), X_BG.translation()
    return np.ascontiguousarray(np.asarray(v, dtype=float) @ R.T + p), swept


def robot_hulls(plant, inspector, bodies) -> dict[int, list[tuple[np.ndarray, float]]]:
    """Each body's collision shapes as ``shape_hull``s in its frame (body index -> list)."""
    out = {}
    for body in bodies:
        geometries = plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(body)))
        out[int(body)] = [
            shape_hull(inspector.GetShape(g), inspector.GetPoseInFrame(g)) for g in geometries
        ]
    return out


def robot_spheres(plant, inspector, bodies, slack: float) -> dict[int, SphereSet]:
    """Covers the collision geometry of each body (body index -> spheres in its frame),
    reading the cache or writing it.

    Args:
        plant: the MultibodyPlant.
        inspector: a SceneGraphInspector of its SceneGraph (collision geometries' shapes, poses).
        bodies: body indices to cover.
        slack: see ``cover_polytope``, m.

    Raises:
        NotImplementedError: a geometry has a shape without a cover.
    """
    items = []  # (body, shape, X_BG)
    digest = hashlib.sha256(_COVER_CODE)  # the cover algorithm itself is an input
    digest.update(f"{slack} {SPACING} {DENSE_SPACING}".encode())
    for body in bodies:
        for g in plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(body))):
            shape, X_BG = inspector.GetShape(g), inspector.GetPoseInFrame(g)
            v, _, radius, _ = shape_polytope(shape)
            digest.update(f"{int(body)} {type(shape).__name__} {radius}".encode())
            digest.update(np.ascontiguousarray(X_BG.GetAsMatrix34()).tobytes())
            if v is not None:
                digest.update(np.ascontiguousarray(v).tobytes())
            items.append((int(body), shape, X_BG))
    path = cache_dir() / "spheres" / f"{digest.hexdigest()[:16]}.npy"
    cached = _load(path)
    if cached is not None:
        return cached
    covers: dict[int, list[SphereSet]] = {}
    for body, shape, X_BG in items:
        covers.setdefault(body, []).append(cover_shape(shape, X_BG, slack))
    out = {b: SphereSet.concat(sets) for b, sets in covers.items()}
    _save(path, out)
    return out


def held_cover(shape, slack: float) -> SphereSet:
    """``cover_shape(shape, identity, slack, scaled=True)`` for an object held by the robot,
    read from the cache or written to it (a box of a few centimetres takes ~6 ms to cover, then
    ~0.3 ms to read)."""
    v, _, radius, _ = shape_polytope(shape)
    digest = hashlib.sha256(_COVER_CODE)
    digest.update(f"held {slack} {SPACING} {DENSE_SPACING} {_CELLS}".encode())
    digest.update(f"{type(shape).__name__} {radius}".encode())
    if v is not None:
        digest.update(np.ascontiguousarray(v).tobytes())
    path = cache_dir() / "spheres" / f"held-{digest.hexdigest()[:16]}.npy"
    cached = _load(path)
    if cached is not None:
        return cached[0]
    cover = cover_shape(shape, RigidTransform(), slack, scaled=True)
    _save(path, {0: cover})
    return cover


def _load(path: Path) -> dict[int, SphereSet] | None:
    """The covers saved by ``_save`` (owner -> spheres), or None when there is no such file."""
    if not path.is_file():
        return None
    rows = np.load(path)  # one array: ~0.1 ms, against ~1 ms for an .npz of four
    owner = rows[:, 5].astype(int)
    return {
        int(b): SphereSet(rows[owner == b, :3], rows[owner == b, 3], rows[owner == b, 4])
        for b in np.unique(owner)
    }


def _save(path: Path, covers: dict[int, SphereSet]) -> None:
    """Writes the covers (owner -> spheres) as one .npy array, a row per sphere (x, y, z,
    radius, inner radius, owner), atomically (a temporary file, then a rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{os.getpid()}.npy")
    rows = np.column_stack(
        [
            np.vstack([s.p_BS for s in covers.values()]),
            np.concatenate([s.radius for s in covers.values()]),
            np.concatenate([s.inner for s in covers.values()]),
            np.concatenate([np.full(len(s.radius), b) for b, s in covers.items()]),
        ]
    )
    np.save(tmp, rows)
    tmp.replace(path)


def unfiltered_in_model(plant, inspector, bodies) -> set[tuple[int, int]]:
    """Pairs (a, b) of ``bodies`` (in that order) with a pair of collision geometries that the
    SceneGraph model does not filter. Read once: later changes go to the checker's own filter
    matrix (``allow_collision``, held objects) or concern shapes the checker adds, never the
    model's robot geometries."""
    geometries = {
        b: plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(b))) for b in bodies
    }
    return {
        (a, b)
        for i, a in enumerate(bodies)
        for b in bodies[i + 1 :]
        if any(not inspector.CollisionFiltered(g, h) for g in geometries[a] for h in geometries[b])
    }
