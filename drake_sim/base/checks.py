"""The value checks every config shares: one message for a number that must be finite and > 0."""

import math
from collections.abc import Iterable

from drake_sim.base.errors import ConfigError


def require_positive(where: str, values: Iterable[tuple[str, float]]) -> None:
    """Raises ``ConfigError`` naming ``where`` and the first ``(key, value)`` whose value is not
    a finite number > 0."""
    for key, value in values:
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f"{where}: '{key}' must be finite and > 0, got {value!r}")


def fields_of(config, keys: Iterable[str]) -> list[tuple[str, float]]:
    """``(key, value)`` of ``config``'s attributes ``keys``, for ``require_positive``."""
    return [(key, getattr(config, key)) for key in keys]
