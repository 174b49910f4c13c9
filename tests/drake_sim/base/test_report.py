"""RunReport and run_times: the shared tail of every run report."""

import dataclasses as dc
import json
import math

import drake_sim.base.report as mut


@dc.dataclass(kw_only=True)
class Example(mut.RunReport):
    distance_m: float


def test_run_times_and_the_report_dict():
    dut = Example(distance_m=2.5, **mut.run_times(10.0, 4.0, seed=3))
    assert dut.real_time_factor == 2.5
    data = json.loads(json.dumps(dut.to_dict()))
    assert data == {
        "sim_time_s": 10.0,
        "wall_time_s": 4.0,
        "real_time_factor": 2.5,
        "seed": 3,
        "distance_m": 2.5,
    }


def test_no_wall_time_is_an_infinite_factor():
    assert mut.run_times(1.0, 0.0, 0)["real_time_factor"] == math.inf
