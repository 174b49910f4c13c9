"""What every run report ends with: simulated and wall time, their ratio, and the random seed."""

import dataclasses as dc
import math


@dc.dataclass(kw_only=True)
class RunReport:
    """The fields every run's JSON report shares; subclasses add what the run did.

    Build one with ``**run_times(sim_time, wall_time, seed)`` among the subclass's fields.
    """

    sim_time_s: float  # s simulated.
    wall_time_s: float  # s of wall time.
    real_time_factor: float  # Simulated s per wall s; inf for a run that took no wall time.
    seed: int  # The random seed of everything random in the run.

    def to_dict(self) -> dict:
        """The report as a JSON-ready dict."""
        return dc.asdict(self)


def run_times(sim_time: float, wall_time: float, seed: int) -> dict:
    """The ``RunReport`` fields of a run that simulated ``sim_time`` s in ``wall_time`` s."""
    factor = sim_time / wall_time if wall_time > 0 else math.inf
    return dict(sim_time_s=sim_time, wall_time_s=wall_time, real_time_factor=factor, seed=seed)
