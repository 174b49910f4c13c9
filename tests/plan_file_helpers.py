"""Helpers of the plan file tests: walking and naming the fields of a plan's JSON tree."""


def walk(value, path=()):
    """Yields every (path, value) of a JSON tree, the root first; a path is a tuple of keys
    (str) and indices (int)."""
    yield path, value
    if isinstance(value, dict | list):
        for key, child in value.items() if isinstance(value, dict) else enumerate(value):
            yield from walk(child, (*path, key))


def field_name(path) -> str:
    """The schema's name of a field (``planning.io.plan_files``): ``scene.world[0].size[1]``."""
    name = ""
    for key in path:
        name += f"[{key}]" if isinstance(key, int) else (f".{key}" if name else key)
    return name


def json_type(value) -> str:
    """The JSON type of a decoded value: "None", "True"/"False", number, str, list or dict."""
    if isinstance(value, bool) or value is None:
        return repr(value)
    return {int: "number", float: "number", str: "str", list: "list", dict: "dict"}[type(value)]


def parent_of(data, path):
    """Returns (the container holding the field at path, its key)."""
    for key in path[:-1]:
        data = data[key]
    return data, path[-1]
