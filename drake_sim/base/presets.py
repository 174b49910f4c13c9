"""Presets: named configurations of a config dataclass, one YAML file each under ``config/``.

A dataclass declares where its presets live with the class attribute ``PRESETS``, a folder of
``config/`` (``LidarConfig.PRESETS = "lidars"``: ``config/lidars/lds_01.yaml``,
``config/lidars/sick_tim571.yaml``). Those files are the one place a preset's numbers stand.
A scenario names one (``lidar: sick_tim571``, ``--set lidar=sick_tim571``) or gives the path of
a YAML file instead; ``drake_sim.base.config.load_typed`` reads either into the dataclass.
"""

from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir


def preset_names(schema) -> list[str]:
    """The names of ``schema``'s presets: the YAML files in ``config/<schema.PRESETS>/``."""
    return sorted(path.stem for path in (config_dir() / schema.PRESETS).glob("*.yaml"))


def preset_file(schema, name_or_path: str | Path, where: str = "preset") -> Path:
    """The file of a preset of ``schema`` (a dataclass with ``PRESETS``, a folder of config/).

    Args:
        name_or_path: a preset's name (``sick_tim571``: ``config/<PRESETS>/sick_tim571.yaml``),
            or a path (a ``Path``, or text with a ``/`` or ending in ``.yaml``/``.yml``), a
            relative one from the working directory if the file is there, else from config/.
        where: how messages name the field (``scenario.yaml: 'lidar'``).

    Raises:
        ConfigError: an unknown name (the message lists the known ones), or no such file.
    """
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or "/" in text or text.endswith((".yaml", ".yml")):
        path = Path(text)
        if not (path.is_absolute() or path.exists()):
            path = config_dir() / path
        if not path.is_file():
            raise ConfigError(f"{where}: no such {schema.PRESETS} file '{text}'")
        return path
    path = config_dir() / schema.PRESETS / f"{text}.yaml"
    if not text.strip() or not path.is_file():
        known = ", ".join(preset_names(schema)) or "none"
        raise ConfigError(
            f"{where}: unknown {schema.PRESETS} preset '{text}' (known: {known}; "
            f"or the path of a YAML file)"
        )
    return path
