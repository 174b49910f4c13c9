"""A collision mesh cut into convex pieces, for a description with ``collision_meshes: pieces``.

Drake's proximity engine checks a mesh as its convex hull; MoveIt (FCL) checks the triangles
themselves. For a link whose mesh is far from convex the two disagree: the UR5's forearm hull
holds 55 % more volume than its mesh, and at MotionBenchMaker's folded wrist poses the hull
meets the wrist (7 mm deep) where the mesh does not, so 82 of the 689 UR5 problems start or end
"in collision" under the hull. Cut into pieces by CoACD (Wei, Liu, Zhang, Wang and Manocha,
"Approximate Convex Decomposition for 3D Meshes with Collision-Aware Concavity and Tree Search",
SIGGRAPH 2022), each piece checked as its own hull, the union of the pieces' hulls still holds
the whole mesh (every piece is a part of it, and a part lies in its own hull), only less of
what is not mesh: a path free of the pieces is free of the mesh.

Each piece is written as an OBJ of its hull's vertices and faces, named by the source's content
hash, the settings and the piece's number; the caller (``robot_files``) keys the whole
converted robot on this file and CoACD's version too, so new settings cut again.
"""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

CONCAVITY = 0.05
"""CoACD's concavity threshold (its default): how far, relative to the mesh's size, a piece may
stray from the mesh's surface."""
MAX_PIECES = 8
"""Pieces per mesh at most (CoACD merges the closest ones down to this)."""
SEARCH = {"mcts_iterations": 60, "mcts_max_depth": 2, "resolution": 1000}
"""CoACD's search, smaller than its defaults (150, 3, 2000): the UR5's forearm in 2.3 s instead
of 8.4 s, its pieces' hulls 0.76 of the mesh's hull against 0.78."""
MIN_GAP = 0.005
"""m: a closed mesh is cut only when its hull strays this far from it on average (the volume
between them over the hull's area). The UR5's forearm and upper arm (8.0 and 9.2 mm) are cut;
its shoulder, wrists and base (0.7 to 1.3 mm) and the Robotiq's fingers and palm (1.7 to
3.5 mm) are not: cutting those too (64 more pieces, each with its own spheres and hull) made
the UR5's MBM requests 5x slower at the median, where gaps well below the sphere cover's
15 mm slack change few verdicts. An open mesh (no volume to compare) stays whole."""


def worth_cutting(mesh) -> bool:
    """True when the trimesh ``mesh`` is closed and its convex hull strays more than
    ``MIN_GAP`` from it on average."""
    if not mesh.is_watertight or len(mesh.faces) < 4:
        return False
    hull = mesh.convex_hull
    return hull.area > 0.0 and (hull.volume - abs(mesh.volume)) / hull.area > MIN_GAP


def coacd_version() -> str:
    """The installed CoACD's version (part of the cache key).

    Raises:
        ConfigError: CoACD is not installed.
    """
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        raise ConfigError(
            "collision_meshes: pieces needs the coacd package (`pip install coacd`)"
        ) from None


def convex_pieces(scene, folder: Path, stem: str) -> list[Path]:
    """Cuts the mesh ``scene`` (``mesh_convert.load_mesh_scene``'s) into convex pieces and
    writes each as ``folder/<stem>-pieceK.obj`` (atomically; the same bytes for the same input:
    CoACD is seeded), when it is ``worth_cutting``.

    Returns:
        The piece files, in CoACD's order; none when the mesh is left whole.

    Raises:
        ConfigError: CoACD is missing, or found no pieces.
    """
    coacd_version()
    import coacd
    import trimesh

    mesh = scene.to_mesh()
    if not worth_cutting(mesh):
        return []
    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
        threshold=CONCAVITY,
        max_convex_hull=MAX_PIECES,
        seed=0,
        **SEARCH,
    )
    files = []
    for k, (vertices, faces) in enumerate(parts):
        hull = trimesh.Trimesh(vertices, faces).convex_hull
        data = trimesh.exchange.obj.export_obj(
            hull, include_normals=False, include_color=False, include_texture=False
        )
        files.append(write_atomic(folder / f"{stem}-piece{k}.obj", data, "mesh piece"))
    if not files:
        raise ConfigError(f"mesh {stem}: CoACD found no pieces")
    return files
