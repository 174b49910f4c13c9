"""drake_sim.systems.pushes: PushSchedule sums the pushes active at the time, and applies them at
its point on its body."""

import numpy as np
from pydrake.multibody.tree import BodyIndex

import drake_sim.systems.pushes as mut
from diagrams.walle_balance_scenario import Push


def test_push_schedule_adds_overlapping_pushes():
    pushes = [Push(time=1.0, force=[1.0, 0, 0], duration=0.5), Push(1.2, [0, 2.0, 0], 0.1)]
    dut = mut.PushSchedule(body_index=BodyIndex(3), p_BoBq_B=[0, 0, 0.4], pushes=pushes)
    np.testing.assert_array_equal(dut.force_at(0.99), [0, 0, 0])
    np.testing.assert_array_equal(dut.force_at(1.25), [1.0, 2.0, 0])
    np.testing.assert_array_equal(dut.force_at(1.5), [0, 0, 0])
    context = dut.CreateDefaultContext()
    context.SetTime(1.1)
    (force,) = dut.get_output_port().Eval(context)
    assert int(force.body_index) == 3
    np.testing.assert_allclose(force.p_BoBq_B, [0, 0, 0.4])
    np.testing.assert_allclose(force.F_Bq_W.translational(), [1.0, 0, 0])
    np.testing.assert_allclose(force.F_Bq_W.rotational(), [0, 0, 0])
