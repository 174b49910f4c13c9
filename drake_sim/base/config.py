"""One way to load a YAML file into a typed schema, with one error for everything that can go wrong.

``load_typed`` reads a file (or a string), checks it against the schema key by key, then builds
the value with Drake's ``yaml_load_typed`` on top of ``defaults`` (a missing key keeps its
default). A missing or unreadable file, bytes that are not UTF-8, malformed YAML, an unknown
key, a value of the wrong type and a non-finite number all raise ``ConfigError`` naming the
file and the dotted key path (``robot.model.ee_frame``). Range checks stay with each schema.
``apply_overrides`` applies ``--set key=value`` overrides the same way; their keys, like the
parameter paths of sweep files, are dotted names with list indices (``scene.object.position[0]``,
``pushes[1].force[2]``), read by ``parse_key_path``.

Presets (``drake_sim.base.presets``): where a schema has a dataclass that declares a folder of
presets (``LidarConfig.PRESETS = "lidars"``), a file or an override may give a string instead
of its keys: a preset's name (``lidar: sick_tim571`` reads ``config/lidars/sick_tim571.yaml``)
or the path of a YAML file. The preset replaces the whole section (every key, its defaults
included); keys set after it (a later ``--set lidar.rate=10``) apply on top. An unknown name is
a ``ConfigError`` naming the file, the key, the name and the known presets.

Schemas are dataclasses (or Drake's own config structs) whose field types are read at run time,
so a schema module must not use ``from __future__ import annotations``.
"""

import dataclasses as dc
import math
import re
import types
import typing
from pathlib import Path

import yaml
from pydrake.common.yaml import yaml_load_typed

from drake_sim.base.errors import ConfigError
from drake_sim.base.presets import preset_file

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_Dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
_SEGMENT = re.compile(r"([^\[\]=]+)((?:\[[^\[\]]*\])*)")  # a name and its [i][j]...
_INDEX = re.compile(r"\[([^\[\]]*)\]")


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
    spans = {}
    if _has_presets(schema):
        _find_presets(schema, yaml.compose(text, Loader=_Loader), "", spans)
    if spans:  # each preset string becomes the preset's mapping, in place; the rest is unchanged
        for start, (end, kind, name, key) in sorted(spans.items(), reverse=True):
            value = load_typed(kind, filename=preset_file(kind, name, f"{where}: '{key}'"))
            text = text[:start] + _flow_yaml(_plain(value)) + text[end:]
        tree = parse_yaml(text, where)
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


def _has_presets(schema, seen=None) -> bool:
    """Whether a dataclass with ``PRESETS`` can stand anywhere in ``schema``."""
    seen = set() if seen is None else seen
    if schema in seen:
        return False
    seen.add(schema)
    fields = _fields(schema)
    if fields is not None and getattr(schema, "PRESETS", None):
        return True
    kinds = list(fields.values()) if fields is not None else typing.get_args(schema)
    return any(_has_presets(kind, seen) for kind in kinds)


def _find_presets(kind, node, key: str, spans: dict) -> None:
    """Adds ``start: (end, schema, name, key)`` to ``spans`` for each string in the composed
    YAML ``node`` that stands where ``kind`` has a dataclass with ``PRESETS``."""
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    fields = _fields(kind)
    if origin in (typing.Union, types.UnionType):
        for option in args:
            _find_presets(option, node, key, spans)
    elif fields is not None and isinstance(node, yaml.ScalarNode):
        if getattr(kind, "PRESETS", None) and node.tag == "tag:yaml.org,2002:str":
            spans[node.start_mark.index] = (node.end_mark.index, kind, node.value, key or "<root>")
    elif fields is not None and isinstance(node, yaml.MappingNode):
        for name_node, value_node in node.value:
            if name_node.value in fields:
                name = f"{key}.{name_node.value}" if key else name_node.value
                _find_presets(fields[name_node.value], value_node, name, spans)
    elif (origin in (list, tuple) or kind in (list, tuple)) and isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _find_presets(args[0] if args else None, item, f"{key}[{i}]", spans)
    elif (origin is dict or kind is dict) and args and isinstance(node, yaml.MappingNode):
        for name_node, value_node in node.value:
            _find_presets(args[1], value_node, f"{key}.{name_node.value}", spans)


def _flow_yaml(data) -> str:
    """``data`` as one line of flow-style YAML."""
    return yaml.dump(data, Dumper=_Dumper, default_flow_style=True, width=1 << 30).strip()


def parse_key_path(key: str, where: str = "key") -> tuple[str | int, ...]:
    """The steps of a dotted key with list indices: ``a.b[2].c`` is ``("a", "b", 2, "c")``,
    ``m[1][0]`` is ``("m", 1, 0)``. The one reader of ``--set`` keys and sweep parameter paths.

    Raises:
        ConfigError: "``where``: malformed key ..." for an empty name, an index that is not a
            whole number (a negative one included), or brackets that do not pair up.
    """
    steps = []
    for segment in key.split("."):
        match = _SEGMENT.fullmatch(segment.strip())
        if not segment.strip():
            why = "an empty name"
        elif segment.strip().startswith("["):
            why = f"no name before '{segment.strip()}'"
        elif "=" in segment:
            why = f"'=' in '{segment.strip()}'"
        elif match is None:
            why = f"brackets out of place in '{segment.strip()}'"
        else:
            why = None
        if why is not None:
            raise ConfigError(f"{where}: malformed key '{key}': {why} (expected a.b[2].c)")
        steps.append(match.group(1).strip())
        for text in _INDEX.findall(match.group(2)):
            text = text.strip()
            if re.fullmatch(r"-\d+", text):
                why = f"negative index [{text}] (items count from 0)"
            elif not (text.isascii() and text.isdigit()):
                why = f"index [{text}] is not a whole number (expected a.b[2].c)"
            if why is not None:
                raise ConfigError(f"{where}: malformed key '{key}': {why}")
            steps.append(int(text))
    return tuple(steps)


def format_key_path(steps) -> str:
    """The text of key path ``steps`` (``parse_key_path``'s inverse): ``a.b[2].c``."""
    text = ""
    for step in steps:
        text += f"[{step}]" if isinstance(step, int) else (f".{step}" if text else step)
    return text


def apply_overrides(schema, value, overrides, where: str = "--set"):
    """Applies ``KEY=VALUE`` overrides (dotted keys, YAML values) to ``value`` of ``schema``.

    A key may index lists (``scene.object.position[0]=0.55``, ``m[1][0]=2``,
    ``pushes[0].time=1.5``): that item alone is set and the rest of the list is kept; a mapping
    given for an item that is a section keeps the item's other keys, as for any section. An
    override may be a ``(label, "KEY=VALUE")`` pair: its errors then name ``label`` (the option
    that set it, e.g. ``--lidar nonsense``) instead of ``where`` and the text.

    Raises:
        ConfigError: for a malformed override, an unknown key, an index on a value that is not
            a list or past its end, or a bad value; naming the override.
    """
    for item in overrides:
        label, item = item if isinstance(item, tuple) else (None, item)
        key, sep, text = item.partition("=")
        at = label or f"{where} {item!r}"
        if not sep or not key.strip():
            raise ConfigError(f"{at}: expected KEY=VALUE")
        steps = parse_key_path(key, at)
        first = next((i for i, step in enumerate(steps) if isinstance(step, int)), None)
        if first is not None:  # the list is rewritten whole with its item replaced
            text = _list_with_item(value, steps, first, text, at)
            steps = steps[:first]
        for part in reversed(steps):
            text = f"{{{part}: {text}}}"
        value = load_typed(schema, data=text, defaults=value, where=at)
    return value


def _list_with_item(value, steps, first: int, text: str, where: str) -> str:
    """YAML text of the list at ``steps[:first]`` in ``value``, with the item at the rest of
    ``steps`` replaced by the YAML ``text``."""
    node = value
    for i, name in enumerate(steps[:first]):
        fields = _fields(type(node))
        if fields is not None and name in fields:
            node = getattr(node, name)
        elif isinstance(node, dict) and name in node:
            node = node[name]
        else:
            known = f" (known here: {', '.join(sorted(fields))})" if fields else ""
            raise ConfigError(f"{where}: unknown key '{format_key_path(steps[: i + 1])}'{known}")
    root = _plain(node)
    node, done = root, steps[:first]
    rest = steps[first:]
    for j, step in enumerate(rest):
        name = format_key_path(done)
        if isinstance(step, int):
            if not isinstance(node, list):
                raise ConfigError(f"{where}: '{name}' is {_kind(node)}, not a list (no [{step}])")
            if step >= len(node):
                count = f"{len(node)} item{'' if len(node) == 1 else 's'}"
                raise ConfigError(f"{where}: '{name}' has no item [{step}] (it has {count})")
        elif not isinstance(node, dict):
            raise ConfigError(f"{where}: '{name}' is {_kind(node)}, not a mapping (no '{step}')")
        elif step not in node and j < len(rest) - 1:
            raise ConfigError(f"{where}: unknown key '{name}.{step}'")
        done = (*done, step)
        if j == len(rest) - 1:
            old = node[step] if isinstance(step, int) or step in node else None
            node[step] = _merged(old, parse_yaml(text, where))
        else:
            node = node[step]
    return _flow_yaml(root)


def _merged(old, new):
    """``new``, with the keys of ``old`` it does not have when both are mappings (deeply): an
    item that is a section is overridden the way ``yaml_load_typed`` overrides a section."""
    if not (isinstance(old, dict) and isinstance(new, dict)):
        return new
    return {**old, **{k: _merged(old.get(k), v) for k, v in new.items()}}


def _plain(value):
    """``value`` as plain YAML data: dataclasses and Drake structs as mappings of their fields,
    tuples and arrays as lists, NumPy scalars as Python numbers."""
    fields = _fields(type(value))
    if fields is not None:
        return {name: _plain(getattr(value, name)) for name in fields}
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):  # NumPy arrays and scalars
        return _plain(value.tolist())
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
