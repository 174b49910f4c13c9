"""drake_sim.sweep.jobs: parameter paths resolved in a scenario (the job's own checks are in
test_runners.py, beside the runners they check against)."""

import dataclasses as dc

import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.sweep import jobs as mut


@dc.dataclass
class Inner:
    position: list[float] = dc.field(default_factory=lambda: [1.0, 2.0, 3.0])
    mass: float = 0.5


@dc.dataclass
class Outer:
    inner: Inner = dc.field(default_factory=Inner)
    rate: float = 10.0
    grid: list[list[float]] = dc.field(default_factory=lambda: [[1.0, 2.0], [3.0, 4.0]])
    items: list[Inner] = dc.field(default_factory=lambda: [Inner(mass=1.5)])


def test_resolve():
    dut = Outer()
    assert mut.resolve(dut, "rate", "w") == 10.0
    assert mut.resolve(dut, "inner.mass", "w") == 0.5
    assert mut.resolve(dut, "inner.position[2]", "w") == 3.0
    assert mut.resolve(dut, "grid[1][0]", "w") == 3.0
    assert mut.resolve(dut, "items[0].position[1]", "w") == 2.0
    assert mut.resolve(dut, "items[0].mass", "w") == 1.5
    with pytest.raises(ConfigError, match=r"w: unknown parameter path 'inner.bogus'.*mass"):
        mut.resolve(dut, "inner.bogus", "w")
    with pytest.raises(ConfigError, match="inner.position has no item 3"):
        mut.resolve(dut, "inner.position[3]", "w")
    with pytest.raises(ConfigError, match="is a section, not a value"):
        mut.resolve(dut, "inner", "w")
    with pytest.raises(ConfigError, match="unknown parameter path 'rate.x'"):
        mut.resolve(dut, "rate.x", "w")
    with pytest.raises(ConfigError, match=r"grid\[1\] has no item 2"):
        mut.resolve(dut, "grid[1][2]", "w")
    with pytest.raises(ConfigError, match="rate has no item 0"):
        mut.resolve(dut, "rate[0]", "w")
    with pytest.raises(ConfigError, match="is a section, not a value"):
        mut.resolve(dut, "items[0]", "w")
    with pytest.raises(ConfigError, match=r"w: parameter path: malformed key 'grid\[-1\]'"):
        mut.resolve(dut, "grid[-1]", "w")
