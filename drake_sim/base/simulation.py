"""Starting a run's simulator: the one sequence every app's run class needs."""

from collections.abc import Callable

from pydrake.common import RandomGenerator
from pydrake.systems.analysis import Simulator


def start_simulator(diagram, seed: int, configure: Callable | None = None):
    """A ``Simulator`` of ``diagram`` with every random source of the context drawn from
    ``seed`` (sensor noise, calibration errors), initialised.

    Args:
        configure: called with the simulator before it is initialised (real-time rate,
            ``ApplySimulatorConfig``).

    Returns:
        (simulator, its mutable root context).
    """
    simulator = Simulator(diagram)
    if configure is not None:
        configure(simulator)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(context, RandomGenerator(seed))
    simulator.Initialize()
    return simulator, context
