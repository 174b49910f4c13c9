"""Perception: image processing that turns camera images into measurements (the line under
Wall-E), as plain functions and the LeafSystems that run them at the camera's rate."""
