"""The AMCL node: localisation on a known map (``ParticleFilter``) as a Drake system.

Like ROS's ``amcl`` it takes each laser scan with the wheel odometry of the same instant,
updates the particle filter when the robot has moved enough, and publishes the pose. Its
``pose`` output is what ROS gets by chaining the ``map -> odom`` correction with the odometry:
the filter's estimate at its last update, moved on by the odometry since, so it is current
between updates. ``set_pose`` is RViz's "2D Pose Estimate" (``/initialpose``) and
``start_global_localization`` the ``global_localization`` service. The parameters are the ROS
node's (``AmclConfig`` in ``amcl_config``; values in ``config/amcl.yaml``), plus our
``refinement_*`` keys: an optional scan-to-map refinement of each update's estimate (not a ROS
parameter; see ``particle_filter``): with it, the navigation runs on the shipped maze, room and
warehouse ended every goal within 2.1 cm (5.9 cm without).

The filter (``drake_sim.systems.estimation.particle_filter``) costs about 2 ms per update with
2000 particles and 60 beams here, 3 to 5 ms with the refinement
(``benchmarks/amcl_benchmark.py``).
"""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.amcl_config import (
    AmclConfig,
    check_amcl_config,
    default_amcl_config_file,
    load_amcl_config,
)
from drake_sim.systems.estimation.particle_filter import ParticleFilter
from drake_sim.systems.estimation.slam import NO_SCAN, SCAN_DELAY
from drake_sim.systems.sensors.lidar import LaserScan

__all__ = [
    "Amcl",
    "AmclConfig",
    "ParticleFilter",
    "check_amcl_config",
    "default_amcl_config_file",
    "load_amcl_config",
]


class _AmclState:
    """What the AMCL system keeps between scans (its abstract state)."""

    def __init__(self, particle_filter: ParticleFilter, pose, covariance):
        self.filter = particle_filter
        self.pose = np.asarray(pose, dtype=float)  # the estimate [x, y, yaw] in the map frame,
        self.odometry = None  # ... valid at this odometry [x, y, yaw] (None: now)
        self.covariance = np.asarray(covariance, dtype=float)  # (3, 3)
        self.last_scan_time = -np.inf
        self.history: list[list[float]] = []  # [t, x, y, yaw, particle count] per update

    def __deepcopy__(self, memo):
        other = _AmclState.__new__(_AmclState)
        other.filter = self.filter.copy()
        other.pose, other.covariance = self.pose.copy(), self.covariance.copy()
        other.odometry = None if self.odometry is None else self.odometry.copy()
        other.last_scan_time = self.last_scan_time
        other.history = [row[:] for row in self.history]
        return other


class Amcl(LeafSystem):
    """Adaptive Monte Carlo localisation on ``map`` from a ``LaserScan`` stream and odometry.

    .. pydrake_system::

        name: Amcl
        input_ports:
        - scan
        - odometry
        output_ports:
        - pose
        - covariance
        - particles
        - localized

    ``scan`` is the ``Lidar``'s ``LaserScan``; ``odometry`` the robot's ``[x, y, yaw]`` from
    wheel odometry (m, m, rad) in any fixed frame. Each new scan is taken ``SCAN_DELAY`` after
    it was made (``period``: the lidar's). ``pose`` is the base's ``[x, y, yaw]`` in the map
    (world) frame: the estimate at the last filter update moved on by the odometry since;
    ``covariance`` the 9 entries (row-major) of its 3x3 covariance (m^2, rad^2); ``particles``
    the (n, 3) particle cloud (an abstract numpy array); ``localized`` 1 once the filter has
    settled on one pose (``localized``), else 0.

    Args:
        map: the ``OccupancyMap`` to localise on.
        config: the parameters; None: ``config/amcl.yaml``.
        period: s between scans.
        X_base_sensor: [x, y, yaw] of the lidar in the base frame (m, m, rad).
        seed: the filter's random seed.
        initial_pose: [x, y, yaw] (m, m, rad); None: the config's ``initial_pose_*``.
        initial_covariance: (3, 3) (m^2, rad^2); None: the config's ``initial_cov_*``.
        global_localization: start with particles over all the free space instead.

    Raises:
        ConfigError: bad parameters, or an initial pose or covariance that is not finite (or
            a covariance that is not symmetric positive semi-definite).
    """

    def __init__(
        self,
        *,
        map: OccupancyMap,  # noqa: A002 (the contract's name, as ROS's map topic)
        config: AmclConfig | None = None,
        period: float,
        X_base_sensor=(0.0, 0.0, 0.0),
        seed: int = 0,
        initial_pose=None,
        initial_covariance=None,
        global_localization: bool = False,
    ):
        super().__init__()
        if config is None:
            config = load_amcl_config(default_amcl_config_file())
        check_amcl_config(config)
        self._X_base_sensor = np.asarray(X_base_sensor, dtype=float).reshape(3)
        particle_filter = ParticleFilter(map, config, seed)
        if global_localization:
            particle_filter.global_localization()
        else:
            pose = config.initial_pose() if initial_pose is None else initial_pose
            cov = config.initial_covariance() if initial_covariance is None else initial_covariance
            particle_filter.set_pose(pose, cov)
        self._scan = self.DeclareAbstractInputPort("scan", AbstractValue.Make(NO_SCAN))
        self._odometry = self.DeclareVectorInputPort("odometry", 3)
        model = _AmclState(particle_filter, *particle_filter.estimate())
        self._state = self.DeclareAbstractState(AbstractValue.Make(model))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, SCAN_DELAY, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.DeclareVectorOutputPort("pose", 3, self._calc_pose, ticket | {self._odometry.ticket()})
        self.DeclareVectorOutputPort(
            "covariance",
            9,
            lambda context, out: out.SetFromVector(self._get(context).covariance.ravel()),
            ticket,
        )
        self.DeclareAbstractOutputPort(
            "particles",
            lambda: AbstractValue.Make(np.zeros((0, 3))),
            lambda context, out: out.set_value(self._get(context).filter.particles.copy()),
            ticket,
        )
        self.DeclareVectorOutputPort(
            "localized",
            1,
            lambda context, out: out.SetFromVector([float(self.localized(context))]),
            ticket,
        )

    def _get(self, context) -> _AmclState:
        return context.get_abstract_state(self._state).get_value()

    def particle_filter(self, context) -> ParticleFilter:
        """The filter (particles, weights, estimate) in ``context``; read only."""
        return self._get(context).filter

    def localized(self, context) -> bool:
        """Whether the filter has settled on one pose (``ParticleFilter.localized``): after
        ``start_global_localization`` a navigation run turns and drives short legs until it
        has (or a time limit passes) before it drives to its goals."""
        return self._get(context).filter.localized()

    def history(self, context) -> np.ndarray:
        """(n, 5) rows ``[t, x, y, yaw, particle count]``, one per filter update: the
        estimate at the scan's time ``t`` (s; m, m, rad)."""
        return np.array(self._get(context).history, dtype=float).reshape(-1, 5)

    def set_pose(self, context, pose, covariance) -> None:
        """Restarts the filter around ``pose`` [x, y, yaw] (m, m, rad) in the map frame with
        ``covariance`` (3, 3) (m^2, rad^2), as RViz's "2D Pose Estimate"; the pose holds at the
        odometry now (when the odometry input has a value), and the next scan updates.

        Raises:
            ConfigError: a pose or covariance that is not finite, or a bad covariance.
        """
        new = self._get(context).__deepcopy__(None)
        odometry = self._odometry_now(context)
        new.filter.set_pose(pose, covariance, odom_pose=odometry)
        self._restarted(context, new, odometry)

    def start_global_localization(self, context) -> None:
        """Spreads the particles over all the map's free space (ROS's ``global_localization``
        service); the next scan updates."""
        new = self._get(context).__deepcopy__(None)
        new.filter.global_localization()
        self._restarted(context, new, self._odometry_now(context))

    def _restarted(self, context, new: _AmclState, odometry) -> None:
        new.pose, new.covariance = new.filter.estimate()
        new.odometry = odometry
        context.get_mutable_abstract_state(self._state).set_value(new)

    def _odometry_now(self, context):
        if not self._odometry.HasValue(context):
            return None
        return np.array(self._odometry.Eval(context), dtype=float)

    def _initialize(self, context, state):
        new = self._get(context).__deepcopy__(None)
        new.odometry = self._odometry_now(context)
        state.get_mutable_abstract_state(self._state).set_value(new)

    def _update(self, context, state):
        scan: LaserScan = self._scan.Eval(context)
        current = self._get(context)
        if scan.ranges.size == 0 or not scan.time > current.last_scan_time:
            return
        odometry = np.array(self._odometry.Eval(context), dtype=float)
        new = current.__deepcopy__(None)
        new.last_scan_time = scan.time
        updated = new.filter.update(
            odometry,
            scan.ranges,
            scan.angles(),
            range_max=scan.range_max,
            range_min=scan.range_min,
            X_base_sensor=self._X_base_sensor,
        )
        if updated:
            new.pose, new.covariance = new.filter.estimate()
            new.odometry = odometry
            new.history.append([scan.time, *new.pose, len(new.filter.particles)])
        state.get_mutable_abstract_state(self._state).set_value(new)

    def _calc_pose(self, context, output):
        current = self._get(context)
        if current.odometry is None:
            output.SetFromVector(current.pose)
            return
        moved = relative_pose(current.odometry, self._odometry.Eval(context))
        output.SetFromVector(compose(current.pose, moved))
