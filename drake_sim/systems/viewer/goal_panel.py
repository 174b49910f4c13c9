"""Meshcat sliders and buttons standing in for RViz's "2D Nav Goal" and "2D Pose Estimate"
tools: set x, y and yaw with the sliders, then press a button."""

import math

import numpy as np
from pydrake.geometry import Meshcat

SLIDERS = ("x (m)", "y (m)", "yaw (deg)")
SEND_GOAL = "2D Nav Goal: drive to x, y, yaw"
SET_POSE = "2D Pose Estimate: robot is at x, y, yaw"
GLOBAL = "Global localization"
BUTTONS = (SEND_GOAL, SET_POSE, GLOBAL)
ACTIONS = {SEND_GOAL: "goal", SET_POSE: "pose", GLOBAL: "global"}


class GoalPanel:
    """The sliders and buttons in the Meshcat page; ``poll`` returns what was pressed since
    the last poll, as ``(action, pose)`` pairs: ``("goal", [x, y, yaw])``, ``("pose", [x, y,
    yaw])`` or ``("global", None)`` (yaw in rad)."""

    def __init__(self, *, meshcat: Meshcat, lower, upper, start=(0.0, 0.0, 0.0)):
        self._meshcat = meshcat
        limits = ((lower[0], upper[0], 0.05), (lower[1], upper[1], 0.05), (-180.0, 180.0, 5.0))
        values = (start[0], start[1], math.degrees(start[2]))
        for name, (low, high, step), value in zip(SLIDERS, limits, values, strict=True):
            meshcat.AddSlider(name, low, high, step, float(np.clip(value, low, high)))
        for name in BUTTONS:
            meshcat.AddButton(name)
        self._clicks = dict.fromkeys(BUTTONS, 0)

    def pose(self) -> np.ndarray:
        """``[x, y, yaw]`` (m, m, rad) set on the sliders."""
        x, y, yaw = (self._meshcat.GetSliderValue(name) for name in SLIDERS)
        return np.array([x, y, math.radians(yaw)])

    def poll(self) -> list[tuple[str, np.ndarray | None]]:
        """The presses since the last poll, in button order."""
        actions = []
        for name in BUTTONS:
            clicks = self._meshcat.GetButtonClicks(name)
            if clicks > self._clicks[name]:
                self._clicks[name] = clicks
                action = ACTIONS[name]
                actions.append((action, None if action == "global" else self.pose()))
        return actions

    def remove(self) -> None:
        """Takes the sliders and buttons off the page."""
        for name in SLIDERS:
            self._meshcat.DeleteSlider(name)
        for name in BUTTONS:
            self._meshcat.DeleteButton(name)
