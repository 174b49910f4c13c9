"""Scheduled pushes: constant external forces on a body over given time windows.

A push is the disturbance a balancing robot must recover from (a shove at the top of Wall-E's
body, say); ``PushSchedule`` feeds the plant's ``applied_spatial_force`` input with the pushes
of a scenario.
"""

from collections.abc import Sequence

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.systems.framework import LeafSystem


class PushSchedule(LeafSystem):
    """Pushes a body at a point with constant forces over given time windows.

    .. pydrake_system::

        name: PushSchedule
        output_ports:
        - spatial_forces

    ``spatial_forces`` (a list of ``ExternallyAppliedSpatialForce``, for the plant's
    ``applied_spatial_force`` input) holds the sum of the pushes active at the current time
    (``push.time <= t < push.time + push.duration``), applied at ``p_BoBq_B`` on the body.

    Args:
        body_index: the pushed body's ``BodyIndex`` in the plant.
        p_BoBq_B: where on the body (m, body frame).
        pushes: each with ``time`` (s, when it starts), ``duration`` (s) and ``force`` (N,
            world frame), e.g. the scenario's ``diagrams.walle_balance_scenario.Push`` list.
    """

    def __init__(self, *, body_index, p_BoBq_B: np.ndarray, pushes: Sequence):
        super().__init__()
        self._body_index = body_index
        self._p_BoBq_B = np.asarray(p_BoBq_B, dtype=float)
        self._pushes = [(p.time, p.time + p.duration, np.asarray(p.force, float)) for p in pushes]
        self.DeclareAbstractOutputPort(
            "spatial_forces",
            lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]),
            self._calc,
            {self.time_ticket()},
        )

    def force_at(self, t: float) -> np.ndarray:
        """The total force (N, world frame) at time ``t`` (s)."""
        total = np.zeros(3)
        for start, end, force in self._pushes:
            if start <= t < end:
                total += force
        return total

    def _calc(self, context, output):
        push = ExternallyAppliedSpatialForce()
        push.body_index = self._body_index
        push.p_BoBq_B = self._p_BoBq_B
        push.F_Bq_W = SpatialForce(np.zeros(3), self.force_at(context.get_time()))
        output.set_value([push])
