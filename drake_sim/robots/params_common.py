"""What every robot's parameter schema shares: the checks of its numbers, scaling, and writing it.

A robot's parameters (``ddrive_params``, ``turtlebot3_params``, ``walle_params``) are a
dataclass of sections, each a dataclass of numbers in SI units, laid out as the robot's YAML
file. ``RobotParamsBase`` gives each schema ``scaled`` and ``to_dict``; ``number_fields`` and
``check_values`` walk the sections field by field, so that a rule for every value is written
once for every robot. A field whose default is NaN is required in the YAML.
"""

import dataclasses as dc
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Self

import yaml

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic


class RobotParamsBase:
    """Base of the robots' parameter dataclasses: ``scaled`` and ``to_dict`` from their fields.

    ``UNSCALED`` names the sections and fields that ``scaled`` leaves alone (what is neither a
    length nor a mass: torques, velocity limits, angles).
    """

    UNSCALED: tuple[str, ...] = ()
    FILES: tuple[str, ...] = ()
    """Sections that are not numbers (files, names): ``scaled`` and ``check_values`` skip them."""

    def scaled(self, *, length: float = 1.0, mass: float = 1.0) -> Self:
        """Returns a copy with every length multiplied by ``length`` and every mass (a field
        named ``mass``) by ``mass``; the sections and fields named in ``UNSCALED`` are copied
        as they are."""
        out = dc.replace(self)
        for section in dc.fields(self):
            block = dc.replace(getattr(self, section.name))
            if section.name not in self.UNSCALED + self.FILES:
                for field in dc.fields(block):
                    if field.name not in self.UNSCALED:
                        factor = mass if field.name == "mass" else length
                        setattr(block, field.name, getattr(block, field.name) * factor)
            setattr(out, section.name, block)
        return out

    def to_dict(self) -> dict:
        """Returns the parameters as plain nested dicts (the YAML layout)."""
        return dc.asdict(self)


def number_fields(params, filename: str) -> Iterator[tuple[str, float]]:
    """Yields ``("section.field", value)`` for every field of every section of ``params``, in
    order, each once its value has been found to be a number.

    Raises:
        ConfigError: naming the first value that is not an int or a float (a bool is not).
    """
    for section in dc.fields(params):
        if section.name in getattr(params, "FILES", ()):
            continue
        block = getattr(params, section.name)
        for field in dc.fields(block):
            value = getattr(block, field.name)
            key = f"{section.name}.{field.name}"
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{filename}: '{key}' must be a number, got {value!r}")
            yield key, value


def check_values(params, filename: str, positions: frozenset[str] = frozenset()) -> None:
    """Checks that every value is given (not NaN), finite, and > 0 unless its key
    (``"section.field"``) is one of the ``positions``, which may be zero or negative.

    Raises:
        ConfigError: naming the first bad key.
    """
    for key, value in number_fields(params, filename):
        if math.isnan(value):
            raise ConfigError(f"{filename}: missing key '{key}'")
        if not math.isfinite(value):
            raise ConfigError(f"{filename}: '{key}' must be finite, got {value!r}")
        if value <= 0 and key not in positions:
            raise ConfigError(f"{filename}: '{key}' must be > 0, got {value!r}")


def write_params(params: RobotParamsBase, filename: str | Path) -> None:
    """Writes ``params`` as a complete robot YAML file (atomically)."""
    write_atomic(filename, yaml.safe_dump(params.to_dict(), sort_keys=False), "robot file")
