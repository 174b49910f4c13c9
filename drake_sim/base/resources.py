"""Where the project's data lives and how Drake finds it.

* ``models_dir()`` and ``config_dir()`` locate ``models/`` and ``config/`` from any working
  directory (they sit beside the installed ``drake_sim`` package in an editable install).
* ``models/`` is the ROS-style package ``drake_sim_models``: every model refers to another with
  ``package://drake_sim_models/<path>``; ``make_parser`` registers it.
* ``render_xacro`` turns a ``.xacro`` file into URDF text once per distinct input and caches the
  result under a hash of every input, so repeated runs and tests do not re-run xacro.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import yaml
from pydrake.multibody.parsing import Parser

PACKAGE_NAME = "drake_sim_models"
"""The package name under which ``models/`` is registered."""

_ROOT = Path(__file__).resolve().parents[2]


def models_dir() -> Path:
    """Returns the absolute path of the project's ``models/`` folder."""
    path = _ROOT / "models"
    if not (path / "package.xml").is_file():
        raise FileNotFoundError(
            f"models/ not found beside the drake_sim package (looked in {path}); "
            "install the project with `pip install -e .` from its checkout"
        )
    return path


def config_dir() -> Path:
    """Returns the absolute path of the project's ``config/`` folder."""
    return _ROOT / "config"


def cache_dir() -> Path:
    """Returns (and creates) the folder for generated files: ``$DRAKE_SIM_CACHE`` or
    ``~/.cache/drake_sim``."""
    path = Path(os.environ.get("DRAKE_SIM_CACHE", Path.home() / ".cache" / "drake_sim"))
    path.mkdir(parents=True, exist_ok=True)
    return path


def package_uri(relative_path: str) -> str:
    """Returns ``package://drake_sim_models/<relative_path>`` for a path inside ``models/``."""
    return f"package://{PACKAGE_NAME}/{relative_path.lstrip('/')}"


def resolve_uri(uri: str) -> Path:
    """Returns the file a ``package://drake_sim_models/...`` URI (or a plain path) names."""
    prefix = f"package://{PACKAGE_NAME}/"
    if uri.startswith(prefix):
        return models_dir() / uri[len(prefix) :]
    if uri.startswith("package://"):
        raise ValueError(f"unknown package in URI {uri!r}; only {prefix} is known")
    return Path(uri)


def params_yaml_file(prefix: str, params: dict) -> Path:
    """``params`` (every optional key filled in) as YAML in the cache, named ``<prefix>-<hash>``:
    the file a robot's xacro reads with ``xacro.load_yaml``. Written once per content."""
    text = yaml.safe_dump(params, sort_keys=True)
    name = f"{prefix}-{hashlib.sha256(text.encode()).hexdigest()[:16]}.yaml"
    path = cache_dir() / "robot_yaml" / name
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return path


def make_parser(plant, *, model_name_prefix: str | None = None) -> Parser:
    """Returns a Drake ``Parser`` for ``plant`` that resolves ``package://drake_sim_models``.

    Args:
        plant: the MultibodyPlant to add models to (its SceneGraph must be registered).
        model_name_prefix: optional prefix for every model instance the parser adds.
    """
    parser = Parser(plant) if model_name_prefix is None else Parser(plant, model_name_prefix)
    package_map = parser.package_map()
    if not package_map.Contains(PACKAGE_NAME):
        package_map.Add(PACKAGE_NAME, str(models_dir()))
    return parser


def _hash_inputs(xacro_file: Path, mappings: dict[str, str]) -> str:
    """Hashes the xacro files beside ``xacro_file``, the mappings, and any file they name."""
    import xacro

    digest = hashlib.sha256()
    digest.update(f"xacro {getattr(xacro, '__version__', '')}\n".encode())
    for path in sorted(xacro_file.parent.glob("*.xacro")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    digest.update(xacro_file.name.encode() + b"\0")
    for key in sorted(mappings):
        value = str(mappings[key])
        digest.update(f"{key}={value}\0".encode())
        if os.path.isfile(value):
            digest.update(Path(value).read_bytes() + b"\0")
    return digest.hexdigest()[:20]


def render_xacro(xacro_file: Path | str, mappings: dict[str, str] | None = None) -> Path:
    """Renders ``xacro_file`` with ``mappings`` (xacro ``$(arg ...)`` values) to a URDF file.

    The result is cached in ``cache_dir()/xacro`` under a hash of every ``.xacro`` file in the
    same folder, the mappings and the contents of any file a mapping names, so editing the
    xacro or the YAML it reads produces a new file while unchanged inputs reuse the old one.

    Returns:
        The path of the rendered URDF.
    """
    import xacro

    xacro_file = Path(xacro_file).resolve()
    mappings = {k: str(v) for k, v in (mappings or {}).items()}
    out_dir = cache_dir() / "xacro"
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = xacro_file.name.removesuffix(".xacro").removesuffix(".urdf")
    out = out_dir / f"{stem}-{_hash_inputs(xacro_file, mappings)}.urdf"
    if out.is_file():
        return out
    doc = xacro.process_file(str(xacro_file), mappings=mappings)
    text = doc.toprettyxml(indent="  ")
    tmp = out.with_suffix(f".tmp{os.getpid()}")
    tmp.write_text(text)
    tmp.replace(out)
    return out
