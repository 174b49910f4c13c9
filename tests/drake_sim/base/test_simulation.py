"""drake_sim.base.simulation: a seeded, configured, initialised simulator."""

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import RandomSource

from drake_sim.base.simulation import start_simulator


def noise_diagram():
    builder = DiagramBuilder()
    builder.AddSystem(RandomSource(RandomDistribution.kGaussian, 1, 0.1))
    return builder.Build()


def noise_at_start(seed: int) -> float:
    diagram = noise_diagram()
    _, context = start_simulator(diagram, seed)
    source = diagram.GetSystems()[0]
    return float(source.get_output_port(0).Eval(source.GetMyContextFromRoot(context))[0])


def test_the_seed_sets_every_random_source():
    assert noise_at_start(3) == noise_at_start(3)
    assert noise_at_start(3) != noise_at_start(4)


def test_configure_runs_before_initialisation():
    seen = []
    simulator, context = start_simulator(
        noise_diagram(), 0, lambda s: seen.append(s.get_target_realtime_rate())
    )
    assert seen == [0.0] and context is simulator.get_mutable_context()
    assert np.isfinite(context.get_time())
