"""Drake LeafSystems by role: ``sensors`` (IMU), ``control`` (diff drive, flip, wheel drivers),
``estimation`` (odometry) and ``viewer`` (Meshcat teleop and trails); ``axle`` holds the axle-frame
geometry they share."""
