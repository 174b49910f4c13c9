"""One way to load a YAML file into a typed schema, with one error for everything that can go wrong.

``load_typed`` reads a file (or a string), checks it against the schema key by key, then builds
the value with Drake's ``yaml_load_typed`` on top of ``defaults`` (a missing key keeps its
default). A missing or unreadable file, bytes that are not UTF-8, malformed YAML, an unknown
key, a value of the wrong type and a non-finite number all raise ``ConfigError`` naming the
file and the dotted key path (``robot.model.ee_frame``). Range checks stay with each schema.
``apply_overrides`` applies ``--set key=value`` overrides the same way.

Schemas are dataclasses (or Drake's own config structs) whose field types are read at run time,
so a schema module must not use ``from __future__ import annotations``.
"""

import dataclasses as dc
import math
import types
import typing
from pathlib import Path

import yaml
from pydrake.common.yaml import yaml_load_typed

from drake_sim.base.errors import ConfigError

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_text(filename: Path | str, what: str = "file") -> str:
    """Returns the text of ``filename``.

    Raises:
        ConfigError: the path is missing, a directory, unreadable, or not UTF-8 text.
    """
    path = Path(filename)
    if not path.exists():
        raise ConfigError(f"{path}: no such {what}")
    if path.is_dir():
        raise ConfigError(f"{path}: is a directory, expected a {what}")
    try:
        return path.read_bytes().decode("utf-8")
    except OSError as e:
        raise ConfigError(f"{path}: cannot read {what} ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise ConfigError(f"{path}: not UTF-8 text (byte {e.start})") from None


def parse_yaml(text: str, where: str):
    """Parses YAML text; a syntax error becomes one ``ConfigError`` line with its position."""
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(e, "problem", None) or type(e).__name__
        raise ConfigError(f"{where}: malformed YAML{at}: {problem}") from None


def load_typed(schema, *, filename=None, data: str | None = None, defaults=None, where=None):
    """Loads YAML into ``schema`` on top of ``defaults`` (``schema()`` when None).

    Args:
        schema: a dataclass type (or a Drake config struct).
        filename: the YAML file; or ``data``, YAML text.
        defaults: the value that missing keys keep.
        where: how messages name the source (default: the file name, or "<yaml>").

    Raises:
        ConfigError: naming the file and the key, for anything that is not a valid ``schema``.
    """
    if (filename is None) == (data is None):
        raise TypeError("load_typed takes exactly one of filename and data")
    if where is None:
        where = str(filename) if filename is not None else "<yaml>"
    text = read_text(filename) if filename is not None else data
    tree = parse_yaml(text, where)
    if tree is None:
        tree = {}
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: expected a mapping of keys, got {_kind(tree)}")
    check_tree(schema, tree, where)
    try:
        return yaml_load_typed(
            schema=schema,
            data=text if text.strip() else "{}",
            defaults=defaults if defaults is not None else schema(),
        )
    except Exception as e:  # noqa: BLE001 (Drake raises many types; check_tree caught most)
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ConfigError(f"{where}: {first}") from None


def load_checked(schema, filename, check, *, what: str = "file", defaults=None):
    """Loads ``filename`` (a ``what``, for the error if it cannot be read) into ``schema`` with
    ``load_typed`` and returns ``check(value, str(filename))``: the one way robot and scenario
    files are read (unknown keys are errors; missing keys keep ``defaults``, the schema's own
    when None).

    Raises:
        ConfigError: naming the file and the key at fault.
    """
    where = str(filename)
    value = load_typed(schema, data=read_text(filename, what), defaults=defaults, where=where)
    return check(value, where)


def apply_overrides(schema, value, overrides, where: str = "--set"):
    """Applies ``KEY=VALUE`` overrides (dotted keys, YAML values) to ``value`` of ``schema``.

    Raises:
        ConfigError: for a malformed override, an unknown key or a bad value.
    """
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep or not key or any(not part for part in key.split(".")):
            raise ConfigError(f"{where} {item!r}: expected KEY=VALUE")
        for part in reversed(key.split(".")):
            text = f"{{{part}: {text}}}"
        value = load_typed(schema, data=text, defaults=value, where=f"{where} {item!r}")
    return value


def check_tree(schema, tree, where: str, path: str = "") -> None:
    """Raises ``ConfigError`` at the first key of the parsed YAML ``tree`` that ``schema`` does
    not have, or whose value cannot be of the field's type (non-finite numbers included)."""
    fields = _fields(schema)
    if fields is None:
        return
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: '{path or '<root>'}' must be a mapping, got {_kind(tree)}")
    for key, value in tree.items():
        name = f"{path}.{key}" if path else str(key)
        if key not in fields:
            known = ", ".join(sorted(fields))
            raise ConfigError(f"{where}: unknown key '{name}' (known here: {known})")
        _check_value(fields[key], value, where, name)


def _fields(schema) -> dict | None:
    if dc.is_dataclass(schema):
        hints = typing.get_type_hints(schema)
        return {f.name: hints[f.name] for f in dc.fields(schema)}
    drake_fields = getattr(schema, "__fields__", None)
    if drake_fields is not None:
        return {f.name: f.type for f in drake_fields}
    return None


def _check_value(kind, value, where: str, name: str) -> None:
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return
        options = [a for a in args if a is not type(None)]
        errors = []
        for option in options:
            try:
                _check_value(option, value, where, name)
                return
            except ConfigError as e:
                errors.append(e)
        raise errors[0]
    if kind is float or kind is int:
        if kind is float and isinstance(value, str):
            value = _float_text(value)  # YAML 1.1 reads 1e6 as text; Drake takes it as 1e6
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{where}: '{name}' must be a number, got {_kind(value)}")
        if kind is int and not isinstance(value, int):
            raise ConfigError(f"{where}: '{name}' must be an integer, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{where}: '{name}' must be finite, got {value!r}")
    elif kind is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: '{name}' must be true or false, got {_kind(value)}")
    elif kind is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: '{name}' must be a string, got {_kind(value)}")
    elif origin in (list, tuple) or kind in (list, tuple):
        if not isinstance(value, list):
            raise ConfigError(f"{where}: '{name}' must be a list, got {_kind(value)}")
        for i, item in enumerate(value):
            if args:
                _check_value(args[0], item, where, f"{name}[{i}]")
    elif origin is dict or kind is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: '{name}' must be a mapping, got {_kind(value)}")
        for key, item in value.items():
            if args:
                _check_value(args[1], item, where, f"{name}.{key}")
    elif _fields(kind) is not None:
        check_tree(kind, value, where, name)


def _float_text(text: str):
    try:
        return float(text)
    except ValueError:
        return text


def _kind(value) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"a boolean ({value})"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return f"{type(value).__name__} {value!r}"
