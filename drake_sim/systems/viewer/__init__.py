"""LeafSystems that talk to Meshcat: keyboard teleop, trails drawn behind the robot, and the
mapping view (the map, the scan, the estimated pose)."""
