"""The line detector as a Drake system: a camera's colour image in, the line's measurement out.

The image processing is ``drake_sim.systems.perception.line_detection.detect_line``; this
module runs it once per camera frame and holds the result in discrete state.
"""

import numpy as np
from pydrake.common.value import Value
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem
from pydrake.systems.sensors import ImageRgba8U

from drake_sim.base.errors import ConfigError
from drake_sim.systems.perception.line_detection import (
    LineDetectorConfig,
    LineMeasurement,
    check_line_detector_config,
    detect_line,
    ground_points,
)
from drake_sim.systems.sensors.camera import CameraConfig, camera_info, check_camera_config

# Layout of the ``measurement`` vector (see ``LineMeasurement`` for the meanings and signs).
FOUND = 0  # 1.0 when the line is seen, else 0.0 (and the rest is zero).
OFFSET = 1  # m, the line's lateral offset from the robot, positive on its left.
HEADING = 2  # rad, the line's direction relative to the robot's heading, positive left.
CURVATURE = 3  # 1/m, the line's curvature, positive turning left.
DISTANCE = 4  # m, from the robot to the nearest line point the camera sees.
MEASUREMENT_SIZE = 5


def measurement_vector(measurement: LineMeasurement) -> np.ndarray:
    """Returns ``measurement`` as the ``measurement`` port's vector."""
    m = measurement
    return np.array([float(m.found), m.offset, m.heading, m.curvature, m.distance])


class LineDetector(LeafSystem):
    """Measures the line under a robot from its camera's colour images, once per frame.

    .. pydrake_system::

        name: LineDetector
        input_ports:
        - color_image
        - camera_pose (optional)
        output_ports:
        - measurement

    ``color_image`` is the camera's ``ImageRgba8U`` (``RgbdSensorDiscrete.color_image_output_port``
    of a camera made by ``add_camera`` with the same ``camera`` config). ``camera_pose``, when
    connected, is X_GC (a ``RigidTransform``): the camera's pose in the robot's ground frame G,
    as ``camera_pose_over_ground`` computes it from the body's pose, for a robot that pitches;
    unconnected, the fixed ``X_GC`` given here is used. ``measurement`` is the vector laid out by
    ``FOUND``, ``OFFSET``, ``HEADING``, ``CURVATURE`` and ``DISTANCE``, all zero until the first
    detection.

    The detector updates ``camera.rate`` times a second, ``config.delay`` after each frame is
    taken (the camera samples at t = k / rate), so each measurement is that much older than the
    image it comes from, like a real detector's processing time.
    """

    def __init__(
        self,
        *,
        camera: CameraConfig,
        X_GC: RigidTransform,
        config: LineDetectorConfig,
    ):
        super().__init__()
        check_camera_config(camera)
        check_line_detector_config(config)
        period = 1.0 / camera.rate
        if config.delay >= period:
            raise ConfigError(f"line_detector: 'delay' must be less than a frame ({period} s)")
        self._info = camera_info(camera)
        self._X_GC = X_GC
        self._config = config
        self._ground = ground_points(self._info, X_GC, config.max_range)
        self._image = self.DeclareAbstractInputPort("color_image", Value(ImageRgba8U()))
        self._pose = self.DeclareAbstractInputPort("camera_pose", Value(RigidTransform()))
        self._state = self.DeclareDiscreteState(MEASUREMENT_SIZE)
        self.DeclarePeriodicDiscreteUpdateEvent(period, config.delay, self._update)
        self.DeclareStateOutputPort("measurement", self._state)

    def _update(self, context, discrete_state):
        image = self._image.Eval(context)
        if self._pose.HasValue(context):
            X_GC = self._pose.Eval(context)
            ground = None
        else:
            X_GC, ground = self._X_GC, self._ground
        measurement = detect_line(image.data, self._info, X_GC, self._config, ground)
        discrete_state.set_value(self._state, measurement_vector(measurement))

    @staticmethod
    def measurement(vector) -> LineMeasurement:
        """Returns the ``measurement`` port's vector as a ``LineMeasurement``."""
        v = np.asarray(vector, dtype=float)
        return LineMeasurement(
            found=bool(v[FOUND] > 0.5),
            offset=float(v[OFFSET]),
            heading=float(v[HEADING]),
            curvature=float(v[CURVATURE]),
            distance=float(v[DISTANCE]),
        )
