"""Simulated sensors: LeafSystems that turn the plant's state into what a real sensor reports
(IMU, camera, a 2D lidar by geometric ray casting)."""
