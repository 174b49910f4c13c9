"""One mesh file made Drake-ready: read with trimesh, written as OBJ or glTF.

Drake 1.51 reads OBJ, glTF (``.gltf``, not ``.glb``: its Meshcat and its convex hulls refuse
``.glb``) and VTK; robot descriptions ship STL, COLLADA (``.dae``), OBJ and glTF/GLB. Every
format trimesh reads is converted here:

* collision meshes become OBJ, geometry only (Drake uses them for their shape; its proximity
  engine checks a mesh as its convex hull);
* visual meshes that carry an appearance (materials, textures, vertex or face colours: COLLADA,
  glTF, OBJ with a material) become one self-contained ``.gltf`` (buffers embedded), which keeps
  it; visual meshes without one (STL) become OBJ, so that the URDF's ``<material>`` colour, which
  Drake applies only to meshes without their own, still shows.

COLLADA's ``<unit meter="...">`` is applied (as RViz does); its ``up_axis`` is not (MoveIt's
geometric_shapes and RViz drop it too; every description checked declares ``Z_UP``). glTF is
y-up and Drake turns it z-up on loading: a glTF source is read z-up as Drake would read it, and
a glTF output is turned y-up first. The approach is ``planning.model.assets``'s for the Panda;
``drake_sim.robots.files.robot_files`` converts each file once into the cache.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

MESH_SUFFIXES = (".stl", ".dae", ".obj", ".gltf", ".glb", ".ply", ".off")
"""File suffixes (lower case) of the mesh formats a description may name."""


def trimesh_version() -> str:
    """The installed trimesh's version (part of every cache key: a new one converts again)."""
    import trimesh

    return trimesh.__version__


def load_mesh_scene(source: Path):
    """Reads ``source`` with trimesh as a ``trimesh.Scene``, in metres.

    Raises:
        ConfigError: the file cannot be read as a mesh, or holds no triangles.
    """
    import trimesh

    if source.suffix.lower() not in MESH_SUFFIXES:
        raise ConfigError(
            f"mesh {source}: unsupported format {source.suffix!r} "
            f"(supported: {', '.join(MESH_SUFFIXES)})"
        )
    try:
        loaded = trimesh.load(str(source), file_type=source.suffix.lower().lstrip("."))
    except Exception as e:  # trimesh raises many types for a bad file
        raise ConfigError(f"mesh {source} cannot be read ({type(e).__name__}: {e})") from None
    scene = loaded if isinstance(loaded, trimesh.Scene) else trimesh.Scene(loaded)
    if not any(len(getattr(g, "faces", ())) for g in scene.geometry.values()):
        raise ConfigError(f"mesh {source} holds no triangles")
    scale = _unit_scale(scene.units)  # the geometries' units, when they agree
    if scale != 1.0:
        scene.apply_scale(scale)
    if source.suffix.lower() in (".gltf", ".glb"):  # y-up, turned z-up as Drake reads it
        scene.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    return scene


def has_appearance(scene) -> bool:
    """Whether any geometry of ``scene`` carries colours, a material or a texture."""
    return any(
        getattr(getattr(g, "visual", None), "kind", None) is not None
        for g in scene.geometry.values()
    )


def convert_mesh(source: Path, target: Path, scene=None) -> Path:
    """Writes ``source`` (or its already loaded ``scene``) as ``target``, atomically.

    Args:
        source: the mesh file, any format of ``MESH_SUFFIXES``.
        target: a ``.obj`` (geometry only) or ``.gltf`` (appearance kept) path.
        scene: ``load_mesh_scene(source)`` when the caller has it already.

    Returns:
        ``target``. Two processes converting the same file write the same bytes; the rename
        is atomic, so a reader sees one whole file or none.

    Raises:
        ConfigError: the mesh cannot be read or the file cannot be written.
    """
    import trimesh

    scene = load_mesh_scene(source) if scene is None else scene
    if target.suffix == ".obj":
        mesh = scene.to_mesh() if len(scene.geometry) else trimesh.Trimesh()
        data = trimesh.exchange.obj.export_obj(
            mesh, include_normals=False, include_color=False, include_texture=False
        )
    elif target.suffix == ".gltf":
        scene = scene.copy()
        scene.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
        data = trimesh.exchange.gltf.export_gltf(scene, embed_buffers=True)["model.gltf"]
    else:
        raise ValueError(f"cannot convert to {target.suffix!r}: use .obj or .gltf")
    return write_atomic(target, data, "converted mesh")


def _unit_scale(units) -> float:
    """The factor to metres of trimesh's ``units`` metadata (``"meters"``, ``"0.001 * meters"``,
    ``"millimeters"``, ...); 1 when absent or unknown."""
    if not units:
        return 1.0
    text = str(units).strip()
    if "*" in text:
        factor, _, unit = text.partition("*")
        try:
            return float(factor) * _unit_scale(unit)
        except ValueError:
            return 1.0
    try:
        import trimesh

        return float(trimesh.units.unit_conversion(text, "meters"))
    except Exception:  # an unknown unit name: keep the numbers as they are
        return 1.0
