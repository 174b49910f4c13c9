"""xacro rendered without ROS: ``$(find pkg)`` resolved from a package map.

A robot's URDF and SRDF often come as xacro (MoveIt's ``panda_arm_hand.srdf.xacro`` includes
``$(find moveit_resources_panda_moveit_config)/config/panda_arm.xacro``). xacro resolves
``$(find pkg)`` with ROS's package index; here ``render_xacro_file`` resolves it from
``package_paths`` (``{"name": folder}``), then from an optional ``find_package`` callable, and
otherwise fails with the package's name. The result keeps the list of files read, so a caller
can hash every input of a cached conversion.

xacro keeps its state in module globals, so renders are serialised by a lock.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from drake_sim.base.config import read_text
from drake_sim.base.errors import ConfigError

_LOCK = threading.Lock()


@dataclass(frozen=True)
class RenderedXacro:
    """The text xacro produced and the files it read.

    Attributes:
        text: the rendered XML.
        files: the xacro file first, then every file it included, in the order read.
    """

    text: str
    files: list[Path]


def xacro_value(value) -> str:
    """Returns a YAML scalar as xacro argument text (``True`` -> ``"true"``)."""
    return str(value).lower() if isinstance(value, bool) else str(value)


def render_xacro_file(
    path: Path | str,
    *,
    xacro_args: Mapping[str, object] | None = None,
    package_paths: Mapping[str, Path | str] | None = None,
    find_package: Callable[[str], Path | str] | None = None,
) -> RenderedXacro:
    """Renders a xacro file to text.

    Args:
        path: the ``.xacro`` file; relative includes are relative to the including file.
        xacro_args: values of ``$(arg name)`` (``name:=value`` on xacro's command line).
        package_paths: package name -> folder, for ``$(find name)``.
        find_package: called with a package name that ``package_paths`` lacks; returns its
            folder or raises ``ConfigError``.

    Raises:
        ConfigError: naming the file, for a missing file, an unknown package or any xacro error.
    """
    import xacro
    from xacro import substitution_args

    path = Path(path)
    read_text(path, "xacro file")  # a missing or unreadable file is a ConfigError
    packages = {name: str(folder) for name, folder in (package_paths or {}).items()}

    def find(name: str) -> str:
        if name in packages:
            return packages[name]
        if find_package is not None:
            return str(find_package(name))
        known = ", ".join(sorted(packages)) or "none"
        raise ConfigError(
            f"{path}: $(find {name}): no folder for package {name!r} (known: {known})"
        )

    mappings = {str(key): xacro_value(value) for key, value in (xacro_args or {}).items()}
    with _LOCK:
        saved, start = substitution_args._eval_find, len(xacro.all_includes)
        substitution_args._eval_find = find
        try:
            doc = xacro.process_file(str(path), mappings=mappings)
        except Exception as e:  # xacro raises many kinds, often wrapping ours
            cause = getattr(e, "exc", None)
            if isinstance(cause, ConfigError) or isinstance(e, ConfigError):
                raise ConfigError(str(cause if isinstance(cause, ConfigError) else e)) from None
            raise ConfigError(f"{path}: xacro failed: {e}") from None
        finally:
            substitution_args._eval_find = saved
            included = [Path(name) for name in xacro.all_includes[start:]]
            del xacro.all_includes[start:]
    return RenderedXacro(doc.toxml(), [path, *included])
