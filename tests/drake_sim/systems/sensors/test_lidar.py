"""The 2D lidar (drake_sim.systems.sensors.lidar) against exact ranges computed here in 2D."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, HalfSpace, Mesh
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import FixedOffsetFrame, SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import drake_sim.systems.sensors.lidar as mut
from drake_sim.base.config import apply_overrides, load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir

SCAN_Z = 0.17  # m, the lidar's height in these scenes
HEIGHT = 0.3  # m, of the obstacles
EXACT = mut.LidarConfig(noise_sigma=0.0)
L_SHAPE = [(0.0, 0.0), (0.6, 0.0), (0.6, 0.2), (0.2, 0.2), (0.2, 0.6), (0.0, 0.6)]  # m, CCW


def _write_l_prism(path, outline=L_SHAPE, height=HEIGHT, scale=1.0):
    """An OBJ prism over the concave ``outline`` from z = 0 to ``height`` (quads on the sides,
    the caps as the two rectangles of the L)."""
    n = len(outline)
    lines = [f"v {x / scale} {y / scale} {z / scale}" for z in (0.0, height) for x, y in outline]
    lines += [f"f {i + 1} {(i + 1) % n + 1} {n + (i + 1) % n + 1} {n + i + 1}" for i in range(n)]
    for cap in ((0, 1, 2, 3), (0, 3, 4, 5)):
        lines.append("f " + " ".join(str(k + 1) for k in reversed(cap)))
        lines.append("f " + " ".join(str(n + k + 1) for k in cap))
    path.write_text("\n".join(lines) + "\n")
    return path


def _walls(half: float, thickness: float = 0.1):
    """Four walls around the origin, their inner faces ``half`` metres from it."""
    c = half + thickness / 2
    span = 2 * half + 2 * thickness
    return [
        (RigidTransform([x, y, HEIGHT / 2]), Box(*size, HEIGHT))
        for x, y, size in (
            (c, 0, (thickness, span)), (-c, 0, (thickness, span)),
            (0, c, (span, thickness)), (0, -c, (span, thickness)),
        )
    ]  # fmt: skip


class _Scene:
    """A plant without gravity: obstacles welded to the world, a free robot body carrying the
    lidar at SCAN_Z inside a 0.3 m box of its own, and an optional free obstacle."""

    def __init__(
        self,
        obstacles,
        *,
        config=EXACT,
        X_WB=None,
        X_BL=None,
        seed=0,
        ignore_robot=True,
        free_box=None,
        ground=False,
    ):
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=1e-3)
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
        friction = CoulombFriction()
        for i, (X_WG, shape) in enumerate(obstacles):
            plant.RegisterCollisionGeometry(
                plant.world_body(), X_WG, shape, f"obstacle{i}", friction
            )
        if ground:
            plant.RegisterCollisionGeometry(
                plant.world_body(), RigidTransform(), HalfSpace(), "ground", friction
            )
        inertia = SpatialInertia.SolidBoxWithMass(1.0, 0.3, 0.3, 0.3)
        self.robot = plant.AddModelInstance("robot")
        self.body = plant.AddRigidBody("base", self.robot, inertia)
        plant.RegisterCollisionGeometry(
            self.body, RigidTransform(), Box(0.3, 0.3, 0.3), "self", friction
        )
        self.free = None
        if free_box is not None:
            other = plant.AddModelInstance("crate")
            self.free = plant.AddRigidBody("crate", other, inertia)
            plant.RegisterCollisionGeometry(
                self.free, RigidTransform(), Box(*free_box), "crate", friction
            )
        mount = plant.AddFrame(
            FixedOffsetFrame("mount", self.body.body_frame(), RigidTransform([0.0, 0.0, 0.05]))
        )
        plant.Finalize()
        X_FL = RigidTransform([0.0, 0.0, -0.05]) @ (X_BL if X_BL is not None else RigidTransform())
        self.lidar = mut.add_lidar(
            builder, plant, scene_graph, frame=mount, X_FL=X_FL, config=config,
            ignore=[self.robot] if ignore_robot else [], seed=seed,
        )  # fmt: skip
        builder.ExportOutput(self.lidar.GetOutputPort("scan"), "scan")
        self.plant, self.diagram = plant, builder.Build()
        self.simulator = Simulator(self.diagram)
        self.context = self.simulator.get_mutable_context()
        X_WB = X_WB if X_WB is not None else RigidTransform([0.0, 0.0, SCAN_Z])
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        plant.SetFreeBodyPose(self.plant_context, self.body, X_WB)

    def scan(self) -> mut.LaserScan:
        return self.lidar.scan_now(self.lidar.GetMyContextFromRoot(self.context))

    def output(self) -> mut.LaserScan:
        return self.diagram.GetOutputPort("scan").Eval(self.context)


# Exact 2D references (independent of the module's code): beams from ``origin`` at ``angles``.


def _rect_ranges(origin, angles, centre, size, yaw):
    """Ray against a rotated rectangle, by the slab method in the rectangle's frame."""
    c, s = math.cos(yaw), math.sin(yaw)
    R = np.array([[c, s], [-s, c]])  # world to rectangle
    o = R @ (np.asarray(origin) - centre)
    d = np.column_stack([np.cos(angles), np.sin(angles)]) @ R.T
    half = np.asarray(size) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (-half - o) / d, (half - o) / d
    near = np.nanmax(np.minimum(t1, t2), axis=1)
    far = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((near <= far) & (near > 0), near, np.inf)


def _circle_ranges(origin, angles, centre, radius):
    o = np.asarray(centre) - origin
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    b = d @ o
    disc = b * b - (o @ o - radius * radius)
    with np.errstate(invalid="ignore"):
        t = b - np.sqrt(disc)
    return np.where((disc >= 0) & (t > 0), t, np.inf)


def _polygon_ranges(origin, angles, points):
    """Ray against every edge of a closed polygon, one beam and edge at a time."""
    out = np.full(len(angles), np.inf)
    pts = np.asarray(points, float) - origin
    for k, angle in enumerate(angles):
        u = np.array([math.cos(angle), math.sin(angle)])
        for i in range(len(pts)):
            a, e = pts[i], pts[(i + 1) % len(pts)] - pts[i]
            den = u[0] * e[1] - u[1] * e[0]
            if abs(den) < 1e-15:
                continue
            t = (a[0] * e[1] - a[1] * e[0]) / den
            s = (a[0] * u[1] - a[1] * u[0]) / den
            if -1e-12 <= s <= 1 + 1e-12 and t > 0:
                out[k] = min(out[k], t)
    return out


def _limited(ranges, config):
    return np.where((ranges >= config.range_min) & (ranges <= config.range_max), ranges, np.inf)


def _assert_exact(measured, exact):
    assert np.array_equal(np.isfinite(measured), np.isfinite(exact))
    finite = np.isfinite(exact)
    assert finite.sum() > 10
    np.testing.assert_allclose(measured[finite], exact[finite], rtol=0, atol=1e-6)


def test_box_cylinder_and_concave_mesh_exact(tmp_path):
    """A rotated box, a cylinder and an L-shaped mesh at known poses, seen from a rotated
    lidar: every beam within 1e-6 m of the exact range, the L's notch included."""
    mesh = _write_l_prism(tmp_path / "l.obj", scale=2.0)  # written at half size, scaled 2x
    box_pose, cyl_pose, l_pose = (1.2, 0.3, 0.5), (-0.8, 1.1), (-0.2, -1.5, 0.3)
    obstacles = [
        (RigidTransform(RotationMatrix.MakeZRotation(box_pose[2]), [*box_pose[:2], HEIGHT / 2]),
         Box(0.4, 0.7, HEIGHT)),
        (RigidTransform([*cyl_pose, HEIGHT / 2]), Cylinder(0.25, HEIGHT)),
        (RigidTransform(RotationMatrix.MakeZRotation(l_pose[2]), [*l_pose[:2], 0.0]),
         Mesh(str(mesh), 2.0)),
    ]  # fmt: skip
    yaw, origin = 0.4, np.array([0.1, -0.2])
    scene = _Scene(
        obstacles, X_WB=RigidTransform(RotationMatrix.MakeZRotation(yaw), [*origin, SCAN_Z])
    )
    scan = scene.scan()
    angles = scan.angles() + yaw
    c, s = math.cos(l_pose[2]), math.sin(l_pose[2])
    l_world = [(l_pose[0] + c * x - s * y, l_pose[1] + s * x + c * y) for x, y in L_SHAPE]
    exact = np.minimum.reduce(
        [
            _rect_ranges(origin, angles, box_pose[:2], (0.4, 0.7), box_pose[2]),
            _circle_ranges(origin, angles, cyl_pose, 0.25),
            _polygon_ranges(origin, angles, l_world),
        ]
    )
    _assert_exact(scan.ranges, _limited(exact, EXACT))
    # Some beams reach into the L's notch, beyond its convex hull.
    hull_gap = _polygon_ranges(origin, angles, [l_world[i] for i in (0, 1, 2, 4, 5)])
    into_notch = np.isfinite(exact) & (exact > hull_gap + 0.05)
    assert into_notch.sum() >= 3


def test_noise_statistics_and_accuracy_band():
    """With the default noise (sigma 0.01 m) the residuals have mean ~0 and std within 15 % of
    sigma. Gaussian noise puts only ~96 % of beams within 2 sigma + 1 mm; the exactness of the
    noise-free ranges is tested above."""
    config = mut.LidarConfig()
    obstacles = _walls(2.0)
    exact_scene = _Scene(obstacles, config=EXACT)
    exact = exact_scene.scan().ranges
    noisy = _Scene(obstacles, config=config, seed=3)
    residuals = []
    for k in range(10):
        noisy.context.SetTime(k / config.rate)
        residuals.append(noisy.scan().ranges - exact)
    residuals = np.concatenate(residuals)
    assert np.all(np.isfinite(residuals))  # the walls are within range everywhere
    sigma = config.noise_sigma
    assert abs(residuals.mean()) < 4 * sigma / math.sqrt(len(residuals))
    assert residuals.std() == pytest.approx(sigma, rel=0.15)
    within = np.mean(np.abs(residuals) <= 2 * sigma + 1e-3)
    assert 0.93 < within < 0.99


def test_resolution_rounds_ranges():
    config = dc.replace(EXACT, resolution=0.05)
    scene = _Scene([(RigidTransform([1.0, 0.0, HEIGHT / 2]), Box(0.2, 3.0, HEIGHT))], config=config)
    ranges = scene.scan().ranges
    finite = ranges[np.isfinite(ranges)]
    np.testing.assert_allclose(finite / 0.05, np.round(finite / 0.05), atol=1e-9)
    assert ranges[180] == pytest.approx(0.9)


def test_own_robot_is_not_seen_unless_asked():
    obstacles = [(RigidTransform([2.0, 0.0, HEIGHT / 2]), Box(0.2, 6.0, HEIGHT))]
    seen = _Scene(obstacles).scan().ranges
    assert seen[180] == pytest.approx(1.9)  # beam 180 points along +x
    assert np.isinf(seen[0])  # nothing behind
    blind = _Scene(obstacles, ignore_robot=False).scan().ranges
    # Its own 0.3 m box is 0.15 m away: at least range_min (0.12), so every beam hits it.
    assert np.all(blind <= math.sqrt(2) * 0.15 + 1e-9)


def test_range_limits():
    """Beyond range_max and nearer than range_min a beam reports inf."""
    config = dc.replace(EXACT, range_min=0.5, range_max=2.0)
    obstacles = [
        (RigidTransform([0.4, 0.0, HEIGHT / 2]), Box(0.2, 0.2, HEIGHT)),  # face at 0.3 m
        (RigidTransform([-2.2, 0.0, HEIGHT / 2]), Box(0.2, 0.2, HEIGHT)),  # face at 2.1 m
        (RigidTransform([0.0, 1.9, HEIGHT / 2]), Box(0.2, 0.2, HEIGHT)),  # face at 1.8 m
    ]
    scene = _Scene(obstacles, config=config)
    scan = scene.scan()
    assert np.isinf(scan.ranges[180]) and np.isinf(scan.ranges[0])
    # The true distances are there: 0.3 m (too near) ahead; 2.1 m (too far) is not.
    exact = scene.lidar.exact_ranges(scene.lidar.GetMyContextFromRoot(scene.context))
    assert exact[180] == pytest.approx(0.3) and np.isinf(exact[0])
    assert scan.ranges[270] == pytest.approx(1.8)
    assert scan.range_min == 0.5 and scan.range_max == 2.0


def test_tilted_lidar_sees_the_ground():
    """Pitched down by 10 degrees at SCAN_Z, the forward beam meets the floor at
    SCAN_Z / sin(10 deg); the backward beam rises and sees nothing."""
    pitch = math.radians(10.0)
    X_BL = RigidTransform(RollPitchYaw(0.0, pitch, 0.0), [0.0, 0.0, 0.0])
    scan = _Scene([], X_BL=X_BL, ground=True).scan()
    assert scan.ranges[180] == pytest.approx(SCAN_Z / math.sin(pitch), abs=1e-9)
    assert np.isinf(scan.ranges[0])
    # A beam at angle a from forward drops at rate cos(a) sin(pitch).
    a = scan.angles()[200]
    assert scan.ranges[200] == pytest.approx(SCAN_Z / (math.cos(a) * math.sin(pitch)), abs=1e-9)


def test_moving_body_is_seen_where_it_is_now():
    scene = _Scene([], free_box=(0.2, 0.2, HEIGHT))
    plant = scene.plant
    plant.SetFreeBodyPose(scene.plant_context, scene.free, RigidTransform([1.0, 0.0, SCAN_Z]))
    assert scene.scan().ranges[180] == pytest.approx(0.9)
    plant.SetFreeBodyPose(scene.plant_context, scene.free, RigidTransform([0.0, 1.5, SCAN_Z]))
    scan = scene.scan()
    assert np.isinf(scan.ranges[180])
    assert scan.ranges[270] == pytest.approx(1.4)


def test_scans_at_the_rate_and_held_between():
    config = dc.replace(EXACT, rate=5.0)
    obstacles = [(RigidTransform([1.0, 0.0, HEIGHT / 2]), Box(0.2, 3.0, HEIGHT))]
    scene = _Scene(obstacles, config=config)
    assert math.isnan(scene.output().time)  # before the simulator initialises
    times = []
    for t in (0.0, 0.1, 0.19, 0.21, 0.55, 0.99):
        scene.simulator.AdvanceTo(t)
        times.append(scene.output().time)
    np.testing.assert_allclose(times, [0.0, 0.0, 0.0, 0.2, 0.4, 0.8], atol=1e-12)
    assert scene.output().ranges[180] == pytest.approx(0.9)


def test_seeded_and_reproducible():
    obstacles = _walls(1.5)
    config = mut.LidarConfig()
    runs = []
    for seed in (5, 5, 6):
        scene = _Scene(obstacles, config=config, seed=seed)
        scene.simulator.AdvanceTo(0.5)
        runs.append(scene.output().ranges.copy())
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


def test_laser_scan_value():
    scan = mut.LaserScan(1.5, -math.pi / 2, math.pi / 2, 0.1, 5.0, [1.0, np.inf, 2.0])
    np.testing.assert_allclose(scan.angles(), [-math.pi / 2, 0.0, math.pi / 2])
    np.testing.assert_allclose(scan.points(), [[0.0, -1.0], [0.0, 2.0]], atol=1e-12)
    assert scan.to_dict()["ranges"] == [1.0, None, 2.0]
    with pytest.raises(ValueError):
        scan.ranges[0] = 3.0  # read-only
    with pytest.raises(dc.FrozenInstanceError):
        scan.time = 2.0


def test_presets_and_fan():
    lds = mut.load_lidar_config(mut.lidar_preset_file("lds_01"))
    assert lds == mut.LidarConfig(angle_min_deg=-180.0)  # the defaults are the LDS-01
    assert lds.fan() == mut.LidarConfig().fan()
    angles = np.degrees(lds.fan().angles())
    np.testing.assert_allclose(angles[[0, 1, -1]], [-180.0, -179.0, 179.0])
    sick = mut.load_lidar_config(mut.lidar_preset_file("sick_tim571"))
    assert (sick.samples, sick.fov_deg, sick.range_min, sick.range_max) == (811, 270.0, 0.05, 25.0)
    angles = np.degrees(sick.fan().angles())
    np.testing.assert_allclose(angles[[0, 405, -1]], [-135.0, 0.0, 135.0], atol=1e-9)
    one = mut.LidarConfig(samples=1, fov_deg=10.0)
    np.testing.assert_allclose(one.fan().angles(), [math.radians(-5.0)])


def test_partial_fan_sees_only_its_sector():
    """A 270-degree scanner: a box straight behind it is outside its field of view."""
    config = dc.replace(EXACT, samples=271, fov_deg=270.0, range_max=5.0)
    obstacles = [
        (RigidTransform([-1.0, 0.0, HEIGHT / 2]), Box(0.2, 0.4, HEIGHT)),
        (RigidTransform([0.0, -1.0, HEIGHT / 2]), Box(0.4, 0.2, HEIGHT)),
    ]
    scan = _Scene(obstacles, config=config).scan()
    assert np.all(np.isinf(scan.ranges[np.abs(scan.angles()) < math.radians(70)]))
    assert scan.ranges[45] == pytest.approx(0.9)  # -90 degrees
    assert np.isinf(scan.ranges[0]) and np.isinf(scan.ranges[-1])  # +-135: misses both


@pytest.mark.parametrize(
    "text, key",
    [
        ("samples: 0", "samples"),
        ("fov_deg: 400", "fov_deg"),
        ("fov_deg: 0", "fov_deg"),
        ("range_min: 3.0\nrange_max: 2.0", "range_min"),
        ("range_min: -0.1", "range_min"),
        ("noise_sigma: -0.01", "noise_sigma"),
        ("rate: 0", "rate"),
        ("resolution: -1", "resolution"),
        ("rate: .nan", "rate"),
        ("range_max: .inf", "range_max"),
        ("beams: 360", "beams"),
        ("samples: 1.5", "samples"),
    ],
)
def test_bad_config_names_file_and_key(tmp_path, text, key):
    path = tmp_path / "lidar.yaml"
    path.write_text(text + "\n")
    with pytest.raises(ConfigError) as error:
        mut.load_lidar_config(path)
    message = str(error.value)
    assert str(path) in message and key in message and "\n" not in message


def test_bad_config_object_is_refused():
    with pytest.raises(ConfigError, match="range_min"):
        mut.Lidar(plant=None, frame=None, config=mut.LidarConfig(range_min=5.0))


@dc.dataclass
class _Scenario:
    lidar: mut.LidarConfig = dc.field(default_factory=mut.LidarConfig)


def test_lidar_config_by_name_or_path(tmp_path):
    sick = mut.lidar_config("sick_tim571")
    assert sick == mut.load_lidar_config(config_dir() / "lidars" / "sick_tim571.yaml")
    assert mut.lidar_config(mut.lidar_preset_file("sick_tim571")) == sick
    assert mut.lidar_config("lds_01") == mut.LidarConfig(angle_min_deg=-180.0)
    path = tmp_path / "slow.yaml"
    path.write_text("rate: 1.0\n")
    assert mut.lidar_config(path) == mut.LidarConfig(rate=1.0)
    assert mut.lidar_config(str(path)) == mut.LidarConfig(rate=1.0)
    with pytest.raises(ConfigError) as info:
        mut.lidar_config("lds_02", where="--lidar")
    message = str(info.value)
    assert message.startswith("--lidar: unknown lidars preset 'lds_02'")
    assert "lds_01" in message and "sick_tim571" in message
    path.write_text("rate: 0\n")
    with pytest.raises(ConfigError, match="'rate' must be positive"):
        mut.lidar_config(path)


def test_a_scenario_names_its_lidar():
    scenario = load_typed(_Scenario, data="lidar: lds_01  # the TurtleBot3's")
    assert scenario.lidar == mut.lidar_config("lds_01")
    scenario = apply_overrides(_Scenario, scenario, ["lidar=sick_tim571"])
    assert scenario.lidar == mut.lidar_config("sick_tim571")
    scenario = apply_overrides(_Scenario, scenario, ["lidar.noise_sigma=0.03"])
    assert scenario.lidar == dc.replace(mut.lidar_config("sick_tim571"), noise_sigma=0.03)
    with pytest.raises(ConfigError, match="'lidar': unknown lidars preset 'sick' .known: lds_01"):
        apply_overrides(_Scenario, scenario, ["lidar=sick"])
