"""Systems that write what a simulation does to files other tools open (ROS 2 logs)."""
