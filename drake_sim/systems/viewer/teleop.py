"""Keyboard teleoperation in Meshcat, like ROS's teleop_twist_keyboard."""

import dataclasses as dc

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.framework import BasicVector, LeafSystem


@dc.dataclass
class TeleopConfig:
    """Step sizes of the keyboard teleop; each key press adds one step."""

    rate: float = 20.0  # Hz, how often the buttons are polled.
    linear_step: float = 0.1  # m/s per press of W / S.
    angular_step: float = 0.5  # rad/s per press of A / D.


# (button label, key code, change in (v, omega) in steps); None clears both.
BUTTONS = (
    ("Faster forward (W)", "KeyW", (1, 0)),
    ("Faster backward (S)", "KeyS", (-1, 0)),
    ("Turn left (A)", "KeyA", (0, 1)),
    ("Turn right (D)", "KeyD", (0, -1)),
    ("Stop (Space)", "Space", None),
)


class MeshcatTeleop(LeafSystem):
    """Turns Meshcat button presses (or their keys) into a ``cmd_vel``-style command.

    .. pydrake_system::

        name: MeshcatTeleop
        output_ports:
        - command

    ``command`` is ``[v, omega]`` (m/s, rad/s) for a ``DiffDriveController``. W/S change the
    forward speed, A/D the turn rate, Space stops. The command and the button click counts
    seen so far are discrete state, polled at ``config.rate``.
    """

    def __init__(self, *, meshcat: Meshcat, config: TeleopConfig):
        super().__init__()
        self._meshcat = meshcat
        self._config = config
        for label, key, _ in BUTTONS:
            meshcat.AddButton(label, key)
        # [v, omega, clicks of each button].
        self._state = self.DeclareDiscreteState(BasicVector(np.zeros(2 + len(BUTTONS))))
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / config.rate, 0.0, self._poll)
        self.DeclareVectorOutputPort(
            "command",
            2,
            lambda context, out: out.SetFromVector(
                context.get_discrete_state(self._state).value()[:2]
            ),
            {self.discrete_state_ticket(self._state)},
        )

    def _poll(self, context, discrete_state):
        x = np.array(context.get_discrete_state(self._state).value())
        steps = np.array([self._config.linear_step, self._config.angular_step])
        for i, (label, _, change) in enumerate(BUTTONS):
            clicks = self._meshcat.GetButtonClicks(label)
            new = clicks - int(x[2 + i])
            if new > 0:
                x[:2] = 0.0 if change is None else x[:2] + new * steps * np.array(change)
            x[2 + i] = clicks
        discrete_state.set_value(self._state, x)

    def remove_buttons(self) -> None:
        """Deletes the buttons from Meshcat (call when the run ends)."""
        for label, _, _ in BUTTONS:
            self._meshcat.DeleteButton(label)
