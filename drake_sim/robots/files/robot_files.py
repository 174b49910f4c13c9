"""A robot's files found and made Drake-ready: packages, xacro, meshes, in the cache, once.

A description (``planning.model.description.RobotDescription``) names its URDF or xacro by a
path relative to its YAML or by ``package://name/path``; inside the files, meshes are named by
``package://name/path``, ``file://`` URLs, relative or absolute paths, and xacro includes by
``$(find name)``. No ROS is needed: a package is found

1. in the description's ``package_paths`` (``{name: folder}``: a folder relative to the YAML, or
   a URI of a folder in another package, ``package://vamp_resources/ur5/meshes``), then
2. among ``BUILTIN_PACKAGES``: ``example-robot-data`` (the installed wheel's package folder,
   which holds ``robots/<robot>_description/``) and ``vamp_resources`` (the ``resources/``
   folder of the ``vamp-planner`` source distribution, which holds ``<robot>/<robot>.urdf``,
   ``.srdf`` and ``meshes/``; ``vamp_resources`` fetches it into the cache the first time it
   is named: pip from the package index, once).

``drake_urdf`` renders the xacro (with the description's ``xacro_args``; ``$(find name)``
resolved as above), converts every mesh the URDF names once (``mesh_convert``) and writes a URDF
beside them whose mesh filenames are relative, into ``cache_dir()/robots/<hash>/``. The hash
covers the rendered URDF, every mesh's bytes, this code and the trimesh version, so a changed
input or library converts again and an unchanged one costs a render and a hash. Every file is
written atomically, so processes converting at the same time do not clash. Elements Drake does
not use and warns about (``transmission``, ``gazebo``, ``safety_controller``, ``calibration``)
and references to materials defined nowhere (ROS shows its default colour, Drake refuses the
file) are left out of the copy; nothing else is changed.
"""

from __future__ import annotations

import copy
import hashlib
import importlib.metadata
import logging
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping
from pathlib import Path
from urllib.parse import unquote, urlparse

from drake_sim.base.config import read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import cache_dir
from drake_sim.robots.files import mesh_convert, mesh_pieces
from drake_sim.robots.files.xacro_files import render_xacro_file


def _example_robot_data() -> Path:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        raise ConfigError(
            "package example-robot-data: the Python package is not installed "
            "(`pip install example-robot-data`)"
        ) from None
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data")))


def _vamp_resources() -> Path:
    from drake_sim.robots.files import vamp_resources  # noqa: PLC0415 (it downloads: only when named)

    return vamp_resources.ensure_resources()


BUILTIN_PACKAGES: dict[str, Callable[[], Path]] = {
    "example-robot-data": _example_robot_data,
    "vamp_resources": _vamp_resources,
}
"""Packages found with no ``package_paths`` entry: name -> a function returning its folder."""

_log = logging.getLogger(__name__)

_IGNORED_ELEMENTS = ("transmission", "gazebo")
"""Top-level URDF elements left out of the Drake copy (ROS control and Gazebo only)."""
_IGNORED_JOINT_ELEMENTS = ("safety_controller", "calibration")
"""Joint elements left out of the Drake copy (Drake ignores them, with a warning each)."""


def resolve_package(name: str, package_paths: Mapping[str, str] | None = None) -> Path:
    """Returns the folder of package ``name``: from ``package_paths``, else built in.

    Args:
        name: the package name, as in ``package://name/...`` or ``$(find name)``.
        package_paths: ``{name: folder}`` (``package_map(description)`` gives a description's,
            its folders made absolute); a value may be a URI of a folder in another package
            (``package://vamp_resources/ur5/meshes``).

    Raises:
        ConfigError: the package is unknown (naming the packages known), or its folder does
            not exist.
    """
    package_paths = package_paths or {}
    if name in package_paths:
        value = str(package_paths[name])
        others = {key: path for key, path in package_paths.items() if key != name}
        folder = resolve_uri(value, Path("."), others)  # a path, or a folder in another package
        where = f"package_paths[{name!r}] = {value}"
    elif name in BUILTIN_PACKAGES:
        folder, where = BUILTIN_PACKAGES[name](), "built in"
    else:
        known = ", ".join(sorted(package_paths)) or "none"
        raise ConfigError(
            f"unknown package {name!r}: not in package_paths (known: {known}) nor built in "
            f"({', '.join(BUILTIN_PACKAGES)}); add it to package_paths"
        )
    if not folder.is_dir():
        raise ConfigError(f"package {name} ({where}): folder {folder} does not exist")
    return folder.resolve()


def package_map(description) -> dict[str, str]:
    """A description's ``package_paths`` with relative folders made absolute (relative to its
    YAML); URIs are kept."""
    base = description_base(description)
    return {
        str(name): value if _is_uri(str(value)) else str(base / Path(value).expanduser())
        for name, value in (description.package_paths or {}).items()
    }


def _is_uri(text: str) -> bool:
    return "://" in text or text.startswith("$(")


def resolve_uri(uri: str, base: Path, package_paths: Mapping[str, str] | None = None) -> Path:
    """Returns the file ``uri`` names (which may not exist): ``package://name/rel``,
    ``file:///abs``, ``$(find name)/rel``, an absolute path, or a path relative to ``base``.

    Raises:
        ConfigError: an unknown package, or a URL scheme other than ``package`` and ``file``.
    """
    text = str(uri).strip()
    found = re.fullmatch(r"\$\(find\s+([^)\s]+)\)(.*)", text)
    if found:
        return resolve_package(found[1], package_paths) / found[2].lstrip("/")
    if "://" in text:
        url = urlparse(text)
        if url.scheme == "package":
            return resolve_package(url.netloc, package_paths) / unquote(url.path).lstrip("/")
        if url.scheme == "file":
            return Path(unquote(url.netloc + url.path))
        raise ConfigError(f"{uri}: unsupported URL scheme {url.scheme!r} (package:// or file://)")
    return Path(base) / Path(text).expanduser()


def read_robot_file(path: Path, package_paths=None, xacro_args=None) -> str:
    """Returns the text of a URDF or SRDF file, rendered with xacro when it ends in ``.xacro``
    or declares the xacro namespace (TurtleBot3's ``.urdf`` files use ``$(arg)`` and ``${}``)
    (``drake_sim.robots.files.xacro_files``), ``$(find name)`` resolving through
    ``resolve_package(name, package_paths)``.

    Raises:
        ConfigError: the file is missing or unreadable, or xacro fails (naming the file).
    """
    path = Path(path)
    if path.suffix != ".xacro":
        text = read_text(path, "robot file")
        if "xmlns:xacro" not in text:  # a .urdf with xacro in it (ROS 2 launch files run it)
            return text
    return render_xacro_file(
        path,
        xacro_args=xacro_args,
        find_package=lambda name: resolve_package(name, package_paths),
    ).text


def description_base(description) -> Path:
    """The folder a description's relative paths are relative to: its YAML's."""
    return Path(description.source).resolve().parent


def urdf_file(description) -> Path:
    """The URDF or xacro file a description names, resolved (it exists).

    Raises:
        ConfigError: an unknown package, or the file does not exist.
    """
    path = resolve_uri(description.urdf, description_base(description), package_map(description))
    if not path.is_file():
        raise ConfigError(f"{description.source}: urdf {description.urdf}: {path} does not exist")
    return path


def urdf_text(description) -> str:
    """The description's URDF as text (xacro rendered with its ``xacro_args``)."""
    return read_robot_file(
        urdf_file(description), package_map(description), getattr(description, "xacro_args", None)
    )


def drake_urdf(description, text: str | None = None, *, warn: bool = True) -> Path:
    """Returns a Drake-ready copy of the description's URDF in the cache, converting on first use.

    Args:
        description: a ``RobotDescription``.
        text: the URDF's text when the caller has rendered it already (``urdf_text``).
        warn: whether missing visual meshes are a warning line (False: the caller has warned
            about this description already).

    Returns:
        ``cache_dir()/robots/<hash>/<robot name>.urdf``; its meshes sit in ``meshes/`` beside
        it, named ``<stem>-<content hash>.obj|.gltf`` and referred to by relative paths.

    A visual mesh that cannot be found (its package unknown, its file missing: a checkout
    without its meshes) is left out, with one warning line naming each: the link is simulated
    and checked as before, shown without it. A missing collision mesh is an error.

    Raises:
        ConfigError: the URDF is not XML, a collision mesh's package is unknown or its file
            missing, a mesh file is unreadable.
    """
    source = urdf_file(description)
    text = urdf_text(description) if text is None else text
    root = _parse_urdf(text, source)
    missing: list[tuple[ET.Element, str]] = []
    meshes = _mesh_elements(root, source, package_map(description), missing)
    if missing:
        _drop_visuals(root, [mesh for mesh, _ in missing])
    if missing and warn:
        _log.warning(
            "%s: visual meshes not found, shown without them: %s",
            source,
            "; ".join(where for _, where in missing),
        )
    digest = hashlib.sha256(Path(__file__).read_bytes() + Path(mesh_convert.__file__).read_bytes())
    digest.update(f"trimesh {mesh_convert.trimesh_version()}\0".encode() + text.encode())
    digest.update(f"{len(missing)} visual meshes missing".encode())
    pieces = getattr(description, "collision_meshes", "hull") == "pieces"
    if pieces:  # CoACD, its settings and this code cut the meshes
        digest.update(Path(mesh_pieces.__file__).read_bytes())
        digest.update(f"coacd {mesh_pieces.coacd_version()}\0".encode())
    content: dict[Path, str] = {}
    for _, _, path in meshes:
        if path not in content:
            content[path] = hashlib.sha256(path.read_bytes()).hexdigest()
        digest.update(f"\0{path.name}\0{content[path]}".encode())
    out_dir = cache_dir() / "robots" / digest.hexdigest()[:20]
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", root.get("name") or source.stem) or "robot"
    out = out_dir / f"{name}.urdf"
    if out.is_file():
        return out
    _strip_ignored(root)
    scenes: dict[Path, object] = {}
    cut: dict[Path, list[str]] = {}
    parents = {child: parent for parent in root.iter() for child in parent}
    for element, kind, path in meshes:
        if path not in scenes:
            scenes[path] = mesh_convert.load_mesh_scene(path)
        if pieces and kind == "collision":
            if path not in cut:
                stem = f"{path.stem}-{content[path][:12]}"
                files = mesh_pieces.convex_pieces(scenes[path], out_dir / "meshes", stem)
                cut[path] = [f"meshes/{f.name}" for f in files]
            if cut[path]:  # else left whole, converted as any mesh
                _split_collision(element, cut[path], parents)
                continue
        visual = kind == "visual" and mesh_convert.has_appearance(scenes[path])
        relative = f"meshes/{path.stem}-{content[path][:12]}{'.gltf' if visual else '.obj'}"
        if not (out_dir / relative).is_file():
            mesh_convert.convert_mesh(path, out_dir / relative, scenes[path])
        element.set("filename", relative)
    ET.register_namespace("drake", "http://drake.mit.edu")
    write_atomic(out, ET.tostring(root, encoding="unicode"), "converted URDF")
    return out


def _split_collision(mesh: ET.Element, files: list[str], parents: dict) -> None:
    """Replaces the ``<collision>`` holding ``mesh`` by one per piece file, in its place, each
    with the same origin and scale (a name gets ``_pieceK`` appended: Drake wants names unique
    on a body)."""
    collision = parents[parents[mesh]]
    link = parents[collision]
    at = list(link).index(collision)
    link.remove(collision)
    for k, name in enumerate(files):
        mesh.set("filename", name)
        piece = copy.deepcopy(collision)
        if collision.get("name"):
            piece.set("name", f"{collision.get('name')}_piece{k}")
        link.insert(at + k, piece)


def mesh_files(description, text: str | None = None) -> list[Path]:
    """Returns every mesh file the description's URDF names, resolved, each once, in file order.

    Args:
        description: a ``RobotDescription``.
        text: the URDF's text when the caller has rendered it already (``urdf_text``).

    Raises:
        ConfigError: as ``drake_urdf``, for a mesh that cannot be found.
    """
    source = urdf_file(description)
    root = _parse_urdf(urdf_text(description) if text is None else text, source)
    found = _mesh_elements(root, source, package_map(description))
    return list(dict.fromkeys(path for _, _, path in found))


def _parse_urdf(text: str, source: Path) -> ET.Element:
    try:
        return ET.fromstring(text)
    except ET.ParseError as e:
        raise ConfigError(f"{source}: not a URDF ({e})") from None


def _mesh_elements(root: ET.Element, source: Path, package_paths, missing=None) -> list:
    """``(mesh element, "visual"|"collision", file)`` for every mesh of every link; relative
    filenames are relative to the URDF (or xacro) file's folder. With a list ``missing``, a
    visual mesh that cannot be found is appended there as ``(mesh element, description)``
    instead of being an error.

    Raises:
        ConfigError: a mesh without a filename, an unknown package, or a missing file.
    """
    found = []
    for link in root.iter("link"):
        for kind in ("visual", "collision"):
            for shape in link.findall(kind):
                for mesh in shape.iter("mesh"):
                    uri = mesh.get("filename")
                    where = f"{source}: link {link.get('name')!r} {kind} mesh"
                    if not uri:
                        raise ConfigError(f"{where} has no filename")
                    try:
                        path = resolve_uri(uri, source.parent, package_paths).resolve()
                        if not path.is_file():
                            raise ConfigError(f"file {path} does not exist")
                    except ConfigError as e:
                        if kind == "visual" and missing is not None:
                            missing.append((mesh, f"link {link.get('name')!r} {uri}"))
                            continue
                        raise ConfigError(f"{where} {uri}: {e}") from None
                    found.append((mesh, kind, path))
    return found


def _drop_visuals(root: ET.Element, meshes: list[ET.Element]) -> None:
    """Removes the ``<visual>`` elements holding ``meshes``."""
    parents = {child: parent for parent in root.iter() for child in parent}
    for mesh in meshes:
        visual = parents[parents[mesh]]
        parents[visual].remove(visual)


def _strip_ignored(root: ET.Element) -> None:
    """Leaves out what Drake warns about or refuses while ROS does not: ``_IGNORED_ELEMENTS``,
    ``_IGNORED_JOINT_ELEMENTS``, and a visual's reference to a material no element defines
    (urdfdom shows the default colour; Drake refuses the file)."""
    for element in [e for e in root if e.tag in _IGNORED_ELEMENTS]:
        root.remove(element)
    for joint in root.iter("joint"):
        for element in [e for e in joint if e.tag in _IGNORED_JOINT_ELEMENTS]:
            joint.remove(element)
    defined = {m.get("name") for m in root.iter("material") if len(m)}
    for visual in root.iter("visual"):
        for material in visual.findall("material"):
            if not len(material) and material.get("name") not in defined:
                visual.remove(material)
