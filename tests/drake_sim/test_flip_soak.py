"""Ten simulated minutes of flipping in the street: no NaN, never stuck, still flipping."""

import pytest

from tests.flip_helpers import flip_scenario, run_for


@pytest.mark.slow
def test_ten_minute_soak():
    run = run_for(600.0, scenario=flip_scenario(world=True))
    report = run.report()
    assert report.finite
    assert not report.stuck
    assert report.flips >= 250  # About one every two seconds, all the way through.
    assert report.longest_time_without_flip_s < 10.0
    status = run.log("status").data()
    times = run.log("status").sample_times()
    last_minute = times > times[-1] - 60.0
    assert status[2, last_minute][-1] - status[2, last_minute][0] >= 20  # Still flipping.
    assert report.max_lateral_deviation_m < 1.0
