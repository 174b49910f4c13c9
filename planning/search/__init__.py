"""Path search: inverse kinematics, RRT-Connect (one at a time and batched), shortcutting,
Cartesian paths, IRIS regions with GCS, and KinematicTrajectoryOptimization smoothing."""
