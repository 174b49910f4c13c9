"""State estimation: LeafSystems (and the algorithms under them) that estimate the robot's pose
from its sensors: wheel odometry (flip-aware, and from encoders), Wall-E's pitch, and
scan-matching SLAM on a log-odds occupancy grid."""
