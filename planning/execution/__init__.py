"""Running plans in a simulated station: the commander LeafSystems and the action handles of
``MotionPlanningInterface``."""
