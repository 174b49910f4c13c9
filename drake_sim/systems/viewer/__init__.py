"""LeafSystems that talk to Meshcat: keyboard teleop and trails drawn behind the robot."""
