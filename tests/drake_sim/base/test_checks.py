"""drake_sim.base.checks: one message for numbers that must be finite and > 0."""

import dataclasses as dc
import math

import pytest

import drake_sim.base.checks as mut
from drake_sim.base.errors import ConfigError


@dc.dataclass
class Rates:
    rate: float = 5.0
    period: float = 0.1


def test_require_positive_names_the_first_bad_key():
    mut.require_positive("f.yaml", mut.fields_of(Rates(), ("rate", "period")))
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match=r"f.yaml: 'period' must be finite and > 0, got"):
            mut.require_positive("f.yaml", mut.fields_of(Rates(period=bad), ("rate", "period")))
    with pytest.raises(ConfigError, match="'rate'"):
        mut.require_positive("w", [("rate", 0.0), ("period", -1.0)])
