"""Files in and out: our scene YAML, MoveIt's PlanningScene files, and the MotionBenchMaker set."""
