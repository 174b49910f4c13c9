"""AMCL's odometry motion model: ``sample_motion_model_odometry`` (Probabilistic Robotics,
Table 5.6) with ROS's ``odom_model_type`` variants. Part of the particle filter
(``drake_sim.systems.estimation.particle_filter``).

The odometry's motion between two readings is split into a turn, a straight move and a turn
(``diff`` models) or a straight move, a sideways one and a turn (``omni`` models: a holonomic
base, ``odom_alpha5`` strafes), each perturbed per particle by zero-mean Gaussian noise whose
variance mixes ``odom_alpha1..4``. ROS 1's original ``diff`` and ``omni`` took that mix as the
standard deviation (their alphas are tuned for that); the ``-corrected`` models take its
square root. ROS drops the direction of a move under 1 cm (its first turn becomes 0), which
moves the particles along their heading when the base shifts sideways in a turn on the spot;
here such a move keeps its direction, with ROS's noise.
"""

import math

import numpy as np

from drake_sim.base.planar import wrap_angle
from drake_sim.systems.estimation.amcl_config import AmclConfig


def sample_motion(particles: np.ndarray, old, new, config: AmclConfig, rng) -> None:
    """Moves ``particles`` ((n, 3) [x, y, yaw], in place) by the odometry's motion from
    ``old`` to ``new`` ([x, y, yaw] in the odometry frame), each with its own noise drawn
    from ``rng``."""
    c = config
    dx, dy = new[0] - old[0], new[1] - old[1]
    trans = math.hypot(dx, dy)
    n = len(particles)
    noise = rng.standard_normal((3, n))
    p = particles

    def spread(mix: float) -> float:
        return math.sqrt(mix) if c.odom_model_type.endswith("-corrected") else mix

    if c.odom_model_type.startswith("omni"):
        turn = float(wrap_angle(new[2] - old[2]))
        a = c.odom_alpha1, c.odom_alpha2, c.odom_alpha3, c.odom_alpha4, c.odom_alpha5
        trans_hat = trans + noise[0] * spread(a[2] * trans**2 + a[0] * turn**2)
        turn_hat = turn + noise[1] * spread(a[3] * turn**2 + a[1] * trans**2)
        strafe_hat = noise[2] * spread(a[0] * turn**2 + a[4] * trans**2)
        bearing = math.atan2(dy, dx) - old[2] + p[:, 2]
        cos, sin = np.cos(bearing), np.sin(bearing)
        p[:, 0] += trans_hat * cos + strafe_hat * sin
        p[:, 1] += trans_hat * sin - strafe_hat * cos
        p[:, 2] = wrap_angle(p[:, 2] + turn_hat)
        return
    rot1 = float(wrap_angle(math.atan2(dy, dx) - old[2])) if trans > 0.0 else 0.0
    rot2 = float(wrap_angle(new[2] - old[2] - rot1))

    def as_noise(turn: float) -> float:  # backwards motion is a small turn, not a half turn
        return min(abs(turn), abs(float(wrap_angle(turn - math.pi))))

    if trans < 0.01:
        # A small move while turning (ROS drops its direction, rot1 = 0, and so moves the
        # particles along their heading: wrong by up to twice the move when the base shifts
        # sideways in a turn on the spot). The move keeps its direction here; the noise is
        # ROS's, all of the turn in rot2's.
        rot1_noise, rot2_noise = 0.0, as_noise(float(wrap_angle(new[2] - old[2])))
    else:
        rot1_noise, rot2_noise = as_noise(rot1), as_noise(rot2)
    rot1_hat = rot1 - noise[0] * spread(c.odom_alpha1 * rot1_noise**2 + c.odom_alpha2 * trans**2)
    trans_hat = trans - noise[1] * spread(
        c.odom_alpha3 * trans**2 + c.odom_alpha4 * (rot1_noise**2 + rot2_noise**2)
    )
    rot2_hat = rot2 - noise[2] * spread(c.odom_alpha1 * rot2_noise**2 + c.odom_alpha2 * trans**2)
    heading = p[:, 2] + rot1_hat
    p[:, 0] += trans_hat * np.cos(heading)
    p[:, 1] += trans_hat * np.sin(heading)
    p[:, 2] = wrap_angle(heading + rot2_hat)
