"""The Panda as planning sees it: the installed assets (URDF, meshes, SRDF) and the plant built
from them, with the state layout and gripper constants named once."""
