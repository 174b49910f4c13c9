"""The Franka Panda's joint and body names, for what reads the Panda's own files (plan files of
versions 1 and 2, MotionBenchMaker's Panda requests).

Everything else takes the robot from its description (``config/robots/panda.yaml``,
``planning.model.planning_model``); the stations build it the same way
(``diagrams.arm_station``).
"""

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
"""The seven arm joints, base to flange."""
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
"""The two finger joints (m from the hand's centre line each)."""
HAND_BODY = "panda_hand"
ATTACHMENT_BODY = "panda_attachment"
"""The body, welded to the hand, that carries attached objects
(``planning_model.attachment_body_name("panda")``)."""
