"""GMapping's beam angles and "no echo" readings."""

import math

import numpy as np
import pytest

from drake_sim.base import laser_scans as mut
from drake_sim.base.errors import ConfigError


def test_gmapping_angles_follow_the_beam_count():
    for count, degrees in ((180, 1.0), (181, 1.0), (360, 0.5), (361, 0.5), (721, 0.25)):
        angles = mut.gmapping_angles(count)
        assert len(angles) == count
        assert angles[0] == pytest.approx(-math.pi / 2)
        assert np.diff(angles) == pytest.approx(np.full(count - 1, math.radians(degrees)))
    with pytest.raises(ConfigError, match="2 beams"):
        mut.gmapping_angles(1)


def test_no_echo_readings_become_no_return():
    r = mut.no_echo_to_inf([1.0, 81.91, float("nan"), -1.0, 79.9], 81.0)
    assert r[0] == 1.0 and r[4] == pytest.approx(79.9)
    assert np.all(np.isinf(r[1:4]))
