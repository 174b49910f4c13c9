"""A plan's joint positions, velocities and accelerations against time, as a PNG.

``plot_plan`` samples the plan's trajectory and draws each joint with its limits dashed in its
colour: the velocity and acceleration limits the plan was timed within, and the position limits
given, or for a Panda plan the Panda description's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_plan(plan, filename: Path | str, dt: float = 0.01, *, position_limits=None) -> None:
    """Writes a PNG of the joint positions (rad), velocities (rad/s) and accelerations
    (rad/s^2) of ``plan`` against time (s), each joint's limits drawn as dashed lines of its
    colour.

    Args:
        plan: the ``planning.plan.Plan``.
        filename: the PNG to write.
        dt: sampling period, s.
        position_limits: (lower (n,), upper (n,)) joint limits, rad; for a Panda plan, the
            Panda description's when None (none drawn for other robots).

    Raises:
        RuntimeError: matplotlib is not installed.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise RuntimeError("Plan.plot needs matplotlib (pip install matplotlib)") from e
    if position_limits is None and plan.robot.get("name") == "panda":
        position_limits = _panda_position_limits()
    ts = np.append(np.arange(0.0, plan.duration, dt), plan.duration)
    samples = [np.array(x) for x in zip(*(plan.sample(t) for t in ts), strict=True)]
    limits = [position_limits, (-plan.max_velocity, plan.max_velocity)]
    limits.append((-plan.max_acceleration, plan.max_acceleration))
    units = ["position (rad)", "velocity (rad/s)", "acceleration (rad/s²)"]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for ax, values, limit, unit in zip(axes, samples, limits, units, strict=True):
        for j, name in enumerate(plan.robot["joints"]):
            (line,) = ax.plot(ts, values[:, j], label=name, linewidth=1.2)
            if limit is not None:
                for bound in limit:
                    ax.axhline(bound[j], color=line.get_color(), ls="--", lw=0.7)
        ax.set_ylabel(f"joint {unit}")
        ax.grid(True, alpha=0.3)
    axes[0].plot(plan.times, plan.waypoints, "k.", markersize=3)
    axes[0].set_title("dashed: limits; dots: waypoints", fontsize=9)
    axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(filename, dpi=100)
    plt.close(fig)


def _panda_position_limits() -> tuple[np.ndarray, np.ndarray]:
    """The Panda description's arm joint limits (lower, upper), rad."""
    from planning.model.model_config import RobotModelConfig
    from planning.model.planning_model import robot_model

    panda = robot_model(RobotModelConfig())
    return panda.lower.copy(), panda.upper.copy()
