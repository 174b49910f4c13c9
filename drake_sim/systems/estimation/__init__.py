"""State estimation: LeafSystems that estimate the robot's pose from its sensors."""
