"""The Franka Panda's state layout and gripper constants, named once for the whole project.

A Panda configuration ``q`` has ``NUM_POSITIONS`` entries: the ``NUM_ARM_JOINTS`` arm joints
(rad, base to flange) then the ``NUM_FINGERS`` finger joints (m, each finger's distance from
the hand's centre). Its state is ``q`` then the velocities (``NUM_STATES`` entries).
"""

import math

NUM_ARM_JOINTS = 7
"""Arm joints, panda_joint1..7."""
NUM_FINGERS = 2
"""Finger joints, panda_finger_joint1 and 2."""
NUM_POSITIONS = NUM_ARM_JOINTS + NUM_FINGERS
"""Entries of a full Panda configuration: arm joints (rad) then fingers (m)."""
NUM_STATES = 2 * NUM_POSITIONS
"""Entries of a Panda state: positions then velocities."""

FINGER_OPEN = 0.04
"""m, each finger fully open (the Franka hand spans 8 cm)."""
FINGER_CLOSED = 0.0
"""m, each finger fully closed."""

READY_Q = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)
"""rad, Franka's "ready" arm configuration (the arm's start in every shipped scenario)."""

ARM_Q = slice(0, NUM_ARM_JOINTS)
"""The arm's positions in a configuration q (or a state x)."""
FINGER_Q = slice(NUM_ARM_JOINTS, NUM_POSITIONS)
"""The fingers' positions in q (or x)."""
ARM_V = slice(NUM_POSITIONS, NUM_POSITIONS + NUM_ARM_JOINTS)
"""The arm's velocities in a state x."""
FINGER_V = slice(NUM_POSITIONS + NUM_ARM_JOINTS, NUM_STATES)
"""The fingers' velocities in a state x."""
