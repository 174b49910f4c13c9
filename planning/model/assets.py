"""The Franka Panda description from the installed ``example-robot-data`` package, made Drake-ready.

``example-robot-data`` (a cmeel wheel) installs the Franka description under
``<site-packages>/cmeel.prefix/share/example-robot-data/robots/panda_description``: a URDF whose
visual meshes are COLLADA (``.dae``) and collision meshes STL, and an SRDF with the MoveIt
groups, named states and disabled collision pairs. Drake reads neither ``.dae`` nor ``.stl``,
so ``panda_urdf`` converts them once with trimesh (visual meshes to binary glTF, which keeps their
colours; collision meshes to OBJ) into ``cache_dir()/panda/<hash>/`` and writes a URDF beside
them whose mesh filenames are relative to it. The hash covers every input file, the trimesh
version and the options, so an upgrade of either package regenerates the cache. Nothing
generated is committed and no absolute path is written into the URDF.

``read_srdf`` returns the SRDF's disabled collision pairs and ``group_state`` configurations.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from drake_sim.base.resources import cache_dir

_DISTRIBUTION = "example-robot-data"
_DESCRIPTION = "cmeel.prefix/share/example-robot-data/robots/panda_description"
_PACKAGE_PREFIX = "package://example-robot-data/robots/panda_description/"

COLLISION_GEOMETRIES = ("convex_mesh", "primitives")
"""``convex_mesh``: the URDF's STL collision meshes, declared convex to Drake (each is a
hull-like mesh of 18 to 152 vertices); ``primitives``: the spheres and cylinders of the package's
``panda_collision.urdf`` (more conservative)."""


@dataclass
class SrdfInfo:
    """What the planning library uses from the Panda SRDF.

    Attributes:
        disabled_collisions: pairs of link names whose collisions are never checked.
        group_states: named joint configurations, name -> {joint name: position (rad or m)}.
    """

    disabled_collisions: list[tuple[str, str]] = field(default_factory=list)
    group_states: dict[str, dict[str, float]] = field(default_factory=dict)


def panda_description_dir() -> Path:
    """Returns the installed ``panda_description`` folder of ``example-robot-data``.

    Raises:
        FileNotFoundError: the package is not installed or does not hold the Panda.
    """
    try:
        dist = importlib.metadata.distribution(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError as e:
        raise FileNotFoundError(
            f"the Python package {_DISTRIBUTION!r} is not installed; `pip install -e .` installs it"
        ) from e
    path = Path(str(dist.locate_file(_DESCRIPTION)))
    if not (path / "urdf" / "panda.urdf").is_file():
        raise FileNotFoundError(f"{_DISTRIBUTION} does not hold the Panda at {path}")
    return path


def read_srdf(path: Path | None = None) -> SrdfInfo:
    """Reads disabled collision pairs and named group states from the Panda SRDF.

    Args:
        path: the SRDF file; the installed ``panda.srdf`` when None.
    """
    path = path or panda_description_dir() / "srdf" / "panda.srdf"
    root = ET.parse(path).getroot()
    info = SrdfInfo()
    for element in root.iter("disable_collisions"):
        info.disabled_collisions.append((element.get("link1"), element.get("link2")))
    for element in root.iter("group_state"):
        joints = {j.get("name"): float(j.get("value")) for j in element.iter("joint")}
        info.group_states[element.get("name")] = joints
    return info


def _hash_inputs(description: Path, collision_geometry: str) -> str:
    import trimesh

    digest = hashlib.sha256(Path(__file__).read_bytes())  # the converter's own code
    digest.update(f"trimesh {trimesh.__version__} {collision_geometry}\0".encode())
    for path in sorted((description / "urdf").glob("*.urdf")) + sorted(
        (description / "meshes").rglob("*")
    ):
        if path.is_file():
            digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _convert_mesh(source: Path, target: Path) -> None:
    """Converts one mesh file with trimesh, writing atomically."""
    import numpy as np
    import trimesh

    target.parent.mkdir(parents=True, exist_ok=True)
    loaded = trimesh.load(str(source))
    tmp = target.with_name(f".{target.stem}.tmp{os.getpid()}{target.suffix}")
    if target.suffix == ".obj":
        mesh = loaded.to_mesh() if isinstance(loaded, trimesh.Scene) else loaded
        # Geometry only: Drake uses collision meshes for their shape, never their material.
        tmp.write_text(trimesh.exchange.obj.export_obj(mesh, include_normals=False))
    else:
        # One self-contained glTF (buffers embedded): Meshcat shows .gltf, not .glb. glTF is
        # y-up and Drake turns it z-up on loading, so turn the z-up mesh y-up first.
        scene = loaded if isinstance(loaded, trimesh.Scene) else trimesh.Scene(loaded)
        scene.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
        files = trimesh.exchange.gltf.export_gltf(scene, embed_buffers=True)
        tmp.write_bytes(files["model.gltf"])
    tmp.replace(target)


def _rewrite_urdf(text: str, out_dir: Path, description: Path) -> str:
    """Converts every mesh the URDF names and points its filename at the converted copy."""
    ET.register_namespace("drake", "http://drake.mit.edu")
    root = ET.fromstring(text)
    for joint in root.iter("joint"):  # Drake ignores these, with a warning each.
        for element in joint.findall("safety_controller"):
            joint.remove(element)
    for mesh in root.iter("mesh"):
        uri = mesh.get("filename")
        if not uri.startswith(_PACKAGE_PREFIX):
            raise ValueError(f"unexpected mesh URI {uri!r} in the Panda URDF")
        relative = Path(uri[len(_PACKAGE_PREFIX) :])
        is_visual = relative.parts[1] == "visual"
        suffix = ".gltf" if is_visual else ".obj"
        converted = relative.with_suffix(suffix)
        if not (out_dir / converted).is_file():
            _convert_mesh(description / relative, out_dir / converted)
        mesh.set("filename", converted.as_posix())
        if not is_visual:
            ET.SubElement(mesh, "{http://drake.mit.edu}declare_convex")
    return ET.tostring(root, encoding="unicode")


def panda_urdf(collision_geometry: str = "convex_mesh") -> Path:
    """Returns a Drake-readable Panda URDF in the cache, generating it on first use.

    Args:
        collision_geometry: one of ``COLLISION_GEOMETRIES``.

    Returns:
        ``cache_dir()/panda/<hash>/urdf/panda.urdf``; its meshes sit in ``../meshes``.
    """
    if collision_geometry not in COLLISION_GEOMETRIES:
        raise ValueError(
            f"collision_geometry {collision_geometry!r} is not one of {COLLISION_GEOMETRIES}"
        )
    description = panda_description_dir()
    out_dir = cache_dir() / "panda" / _hash_inputs(description, collision_geometry)
    out = out_dir / "urdf" / "panda.urdf"
    if out.is_file():
        return out
    source = "panda.urdf" if collision_geometry == "convex_mesh" else "panda_collision.urdf"
    text = _rewrite_urdf((description / "urdf" / source).read_text(), out_dir, description)
    # Mesh filenames are relative to the URDF's folder: "../meshes/...".
    text = text.replace('filename="meshes/', 'filename="../meshes/')
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".panda.tmp{os.getpid()}.urdf")
    tmp.write_text(text)
    tmp.replace(out)
    return out
