"""PyBullet world of a Clearpath Husky in a warehouse hall: the ground robot's counterpart of the
drone arena.

The hall is ``cstep demo --robot husky``'s, as ``config/husky_hall.json`` states it (read here
from the package's ``data/husky_hall.json``, a link to that file): 10 m × 4 m, x ∈ [−1, 9],
y ∈ [−2, 2]; two pallet stacks at x ∈ [3, 4] from the side walls leave a 1.4 m door at
y ∈ [−0.7, 0.7]; a 360-beam LiDAR, 0.1–10 m. Walls, pallets and the floor (pybullet_data's
``plane.urdf``) are static. A task (:class:`Hall`) is a start pose and a goal; drawn ones lie
at least the file's margin (0.7 m, the demo drive's closest approach) from every wall and
pallet, the start on one side of the pallets and the goal on the other, so every drawn task
goes through the door.

The robot is pybullet_data's ``husky/husky.urdf`` as shipped (the file ``urdf/husky.urdf``, the
core's built-in Husky, was copied from). What the drive needs is read from it
(:class:`HuskyParams`): the wheel joints and their collision cylinders give the wheel radius
and the track, as the core's ``diff_drive`` model reads them. A command ``(v, ω)`` becomes rim
speeds ``v ∓ ω·track'/2`` (left, right) on the effective track ``track' = track × 1.875``, as
the Husky's ``diff_drive_controller`` converts it, scaled together so neither exceeds the top
speed, which each rim then approaches at no more than the acceleration bound; every wheel of a
side turns at its side's speed (skid steer), held by PyBullet's velocity motors. The bounds are
Clearpath's figures, the node's ``wheel_max_speed`` and ``wheel_max_acceleration`` defaults (the
URDF's continuous joints give none). A skid steer's wheels scrub sideways in a turn: Clearpath
calibrated the Husky's effective track at 1.875 times its geometric one, which the core's model
turns on (``wheel_separation_multiplier``). PyBullet's wheels, gripping sideways as firmly as
forward, scrubbed far more (spinning at top rim speed, 1.22–1.40 rad/s over headings: a
multiplier of 2.7–3.1); their sideways friction is scaled (:data:`WHEEL_SIDEWAYS_FRICTION`) so
that the simulated Husky spins as the calibrated one does. The slip still changes with the
turn's speed, which one multiplier cannot follow (at half the top rim speed the spin is
0.72–0.74 rad/s against the model's 0.93). ``experiments/husky/spin_calibration.py`` measures
both.

Physics at 240 Hz, control at 10 Hz (24 physics steps): the rate a LiDAR scans, the demo's.
The odometry is the root link's (``base_footprint``, on the ground): its pose, and its twist,
which :class:`~cstep_bridge.sim.drone.DroneState` turns into the body frame; the scan is taken
from that origin, as the scorer expects, in the plane of the chassis's top, where a Husky
carries its LiDAR.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pybullet as p
import pybullet_data

from ..resources import PACKAGE
from .drone import DroneState, G
from .world import PHYSICS_HZ, Lidar, PhysicsWorld, Rect, clearance

HUSKY_HALL_FILE = PACKAGE / "data" / "husky_hall.json"
"""Where the package keeps the hall's file."""
HUSKY_HALL: dict[str, Any] = json.loads(HUSKY_HALL_FILE.read_text())
"""The file's contents: ``hall`` (``bounds``, ``pallets``, ``wall_height``, ``pallet_height``),
``drive`` (the demo's ``route`` and ``speed``), ``lidar`` (``beams``, ``range_min``,
``range_max``) and ``draws`` (``margin``), metres."""
BOUNDS: Rect = tuple(HUSKY_HALL["hall"]["bounds"])
"""The hall's inner walls (x0, y0, x1, y1)."""
PALLETS: tuple[Rect, ...] = tuple(tuple(r) for r in HUSKY_HALL["hall"]["pallets"])
"""The pallet stacks, each (x0, y0, x1, y1)."""
HALL_LIDAR = Lidar(**HUSKY_HALL["lidar"])
"""The Husky's scanner: 360 beams, 0.1–10 m."""

HUSKY_URDF = Path(pybullet_data.getDataPath()) / "husky" / "husky.urdf"
"""The Husky as pybullet_data ships it."""
PLANE_URDF = Path(pybullet_data.getDataPath()) / "plane.urdf"
"""The floor."""

CONTROL_HZ = 10
"""Control steps per second."""
STEPS_PER_CONTROL = PHYSICS_HZ // CONTROL_HZ
"""Physics steps per control step (24)."""
MAX_SPEED = 1.0
"""Each rim's top speed (m/s): the Husky's published maximum speed, the node's
``wheel_max_speed``."""
MAX_ACCELERATION = 3.0
"""Each rim's acceleration bound (m/s²): the limit Clearpath's drive controller ships with,
the node's ``wheel_max_acceleration``."""
SEPARATION_MULTIPLIER = 1.875
"""The Husky's effective track over its geometric one: Clearpath's calibration
(``husky_control/config/control.yaml``, ``wheel_separation_multiplier``), the core's default for
a skid steer."""
WHEEL_SIDEWAYS_FRICTION = 0.63
"""The wheels' friction along their axles, as a fraction of along their rolling direction
(PyBullet's anisotropic friction): with it the simulated Husky, spinning at the top rim speed,
turns at 2·(1 m/s)/(1.875 × track), 1.87 rad/s, as the calibrated one does (1.75–2.02 rad/s
over headings; 1.22–1.40 rad/s with full sideways friction:
``experiments/husky/spin_calibration.py``)."""
WHEEL_TORQUE = 100.0
"""The wheel motors' torque bound (N·m): enough that the acceleration bound, not the motors,
limits the drive (the URDF gives no effort limit)."""


@dataclass(frozen=True)
class HuskyParams:
    """What the drive and the scanner need, read from the URDF."""

    wheel_radius: float
    """The wheels' collision cylinders' radius (m), their mean."""
    track: float
    """The distance between the left and the right wheels' centres (m), side means."""
    left_joints: tuple[str, ...]
    """The wheel joints on the left (+y) side."""
    right_joints: tuple[str, ...]
    """The wheel joints on the right side."""
    half_width: float
    """Half the width of the body and wheels (m): the clearance it needs beside it."""
    chassis_top: float
    """The height of the chassis's collision box's top above the root frame (m): the LiDAR's."""
    separation_multiplier: float
    """The effective track over the geometric one: :data:`SEPARATION_MULTIPLIER` for a skid
    steer (more than one wheel a side), 1 otherwise, as the core's default."""

    @classmethod
    def from_urdf(cls, path: Path | str = HUSKY_URDF) -> HuskyParams:
        """The parameters in the URDF at ``path``, read by the core's rules
        (``crates/cstep-core/src/model/wheeled.rs``): a wheel is a continuous or revolute joint
        whose child link's collision is a cylinder; the side is the sign of its y. Links are
        placed by their joints' translations (the joints above the wheels and the chassis must
        not be rotated)."""
        root = ET.parse(path).getroot()
        joints = {j.find("child").get("link"): j for j in root.findall("joint")}
        wheels, boxes = [], []
        for link in root.findall("link"):
            joint = joints.get(link.get("name"))
            turns = joint is not None and joint.get("type") in ("continuous", "revolute")
            for collision in link.findall("collision"):
                shape = collision.find("geometry")[0]
                where = _placed(link.get("name"), joints, path) + _xyz(collision.find("origin"))
                if shape.tag == "cylinder" and turns:
                    size = (float(shape.get("radius")), float(shape.get("length")))
                    wheels.append((joint.get("name"), where, *size))
                elif shape.tag == "box":
                    boxes.append((where, np.array([float(v) for v in shape.get("size").split()])))
        left = [w for w in wheels if w[1][1] > 0]
        right = [w for w in wheels if w[1][1] < 0]
        if not left or not right or not boxes:
            raise ValueError(
                f"{path}: expected wheels (continuous joints with collision cylinders) on both "
                f"sides and a chassis collision box; found {len(left)} left, {len(right)} right "
                f"wheels and {len(boxes)} boxes"
            )
        return cls(
            wheel_radius=float(np.mean([w[2] for w in wheels])),
            track=float(np.mean([w[1][1] for w in left]) - np.mean([w[1][1] for w in right])),
            left_joints=tuple(w[0] for w in left),
            right_joints=tuple(w[0] for w in right),
            half_width=float(
                max(
                    max(abs(w[1][1]) + w[3] / 2 for w in wheels),
                    max(abs(c[1]) + s[1] / 2 for c, s in boxes),
                )
            ),
            chassis_top=float(max(c[2] + s[2] / 2 for c, s in boxes)),
            separation_multiplier=SEPARATION_MULTIPLIER if max(len(left), len(right)) > 1 else 1.0,
        )

    @property
    def effective_track(self) -> float:
        """The track the drive turns on (m): ``ω = (v_right − v_left) / effective_track``."""
        return self.track * self.separation_multiplier

    @property
    def max_turn_rate(self) -> float:
        """The turn rate (rad/s) of the rims at top speed in opposite directions."""
        return 2 * MAX_SPEED / self.effective_track

    def rim_speeds(self, v: float, omega: float) -> np.ndarray:
        """The (left, right) rim speeds (m/s) of forward speed ``v`` and turn rate ``omega``,
        scaled together (the same turning radius) so neither exceeds :data:`MAX_SPEED`."""
        half = omega * self.effective_track / 2
        rims = np.array([v - half, v + half])
        fastest = np.abs(rims).max()
        return rims * (MAX_SPEED / fastest) if fastest > MAX_SPEED else rims


def _xyz(origin: ET.Element | None) -> np.ndarray:
    """An ``<origin>``'s translation (zero when absent)."""
    xyz = "0 0 0" if origin is None else origin.get("xyz", "0 0 0")
    return np.array([float(v) for v in xyz.split()])


def _placed(link: str, joints: dict[str, ET.Element], path: Path | str) -> np.ndarray:
    """Where ``link``'s frame lies in the root link's, with every joint at zero: the sum of the
    translations of the joints above it; a rotated one is refused."""
    where = np.zeros(3)
    while link in joints:
        joint = joints[link]
        origin = joint.find("origin")
        rpy = [float(v) for v in origin.get("rpy", "0 0 0").split()] if origin is not None else []
        if any(abs(a) > 1e-9 for a in rpy):
            raise ValueError(f"{path}: joint '{joint.get('name')}' is rotated; not read here")
        where += _xyz(origin)
        link = joint.find("parent").get("link")
    return where


@dataclass
class Hall:
    """One task in the hall: the robot's start pose and its goal (metres, radians, world
    frame). The default is the demo's drive: from its route's first point, facing +x, to its
    last."""

    start: np.ndarray = field(default_factory=lambda: np.array(HUSKY_HALL["drive"]["route"][0]))
    """The start (x, y) of the robot's origin."""
    yaw: float = 0.0
    """The start heading."""
    goal: np.ndarray = field(default_factory=lambda: np.array(HUSKY_HALL["drive"]["route"][-1]))
    """The goal (x, y)."""

    @staticmethod
    def sides() -> tuple[Rect, Rect]:
        """Where tasks are drawn: the areas before and beyond the pallets, the file's margin
        from every wall and pallet."""
        m = HUSKY_HALL["draws"]["margin"]
        x0, y0, x1, y1 = BOUNDS
        before = min(r[0] for r in PALLETS) - m
        beyond = max(r[2] for r in PALLETS) + m
        return (x0 + m, y0 + m, before, y1 - m), (beyond, y0 + m, x1 - m, y1 - m)

    @classmethod
    def random(cls, rng: np.random.Generator) -> Hall:
        """A task drawn from ``rng``: start and goal uniform on opposite sides of the pallets
        (which side is the start's, even odds), the heading uniform."""
        sides = cls.sides()
        first = int(rng.integers(2))
        start, goal = (_uniform_in(rng, sides[k]) for k in (first, 1 - first))
        return cls(start=start, yaw=float(rng.uniform(-math.pi, math.pi)), goal=goal)

    def through_door(self, xy: np.ndarray) -> int | None:
        """The index of the first of the positions ``xy`` (n × 2, the robot's origin) beyond the
        pallets on the goal's side (past the stacks' face there): where the robot came through
        the door, the only way past them; None if it never did. A drawn task starts on the
        other side, so this is the passage its task needs."""
        near, far = min(r[0] for r in PALLETS), max(r[2] for r in PALLETS)
        x = np.asarray(xy, dtype=float).reshape(-1, 2)[:, 0]
        first = np.flatnonzero(x > far if self.goal[0] > (near + far) / 2 else x < near)
        return int(first[0]) if first.size else None

    @staticmethod
    def clearance(xy: np.ndarray) -> float:
        """Distance (m) from a point to the nearest wall or pallet face (negative inside)."""
        return clearance(xy, BOUNDS, PALLETS)


def _uniform_in(rng: np.random.Generator, rect: Rect) -> np.ndarray:
    """A point drawn uniformly in ``rect``."""
    x0, y0, x1, y1 = rect
    return np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])


class HuskySim(PhysicsWorld):
    """The Husky in the hall. ``step(v, omega)`` advances one 10 Hz control step.

    The hall never changes, so it is built once; a reset puts the robot back at rest at the
    task's start (loading the URDF again would also print PyBullet's warnings about its links
    without inertia each episode)."""

    def __init__(
        self, hall: Hall | None = None, gui: bool = False, urdf: Path | str = HUSKY_URDF
    ) -> None:
        """Builds the hall with the Husky of ``urdf`` at ``hall``'s start (None: the demo's
        task), headless unless ``gui``."""
        super().__init__(gui)
        self.urdf = str(urdf)
        self.params = HuskyParams.from_urdf(self.urdf)
        self.hall = hall or Hall()
        cid = self.client
        self._restart(G)
        p.loadURDF(str(PLANE_URDF), physicsClientId=cid)
        x0, y0, x1, y1 = BOUNDS
        t, h = 0.1, HUSKY_HALL["hall"]["wall_height"]
        self.obstacles = [
            self.add_box((x0 - t, y0 - t, 0), (x0, y1 + t, h)),
            self.add_box((x1, y0 - t, 0), (x1 + t, y1 + t, h)),
            self.add_box((x0, y0 - t, 0), (x1, y0, h)),
            self.add_box((x0, y1, 0), (x1, y1 + t, h)),
        ]
        top = HUSKY_HALL["hall"]["pallet_height"]
        for px0, py0, px1, py1 in PALLETS:
            box = self.add_box((px0, py0, 0), (px1, py1, top), (0.75, 0.55, 0.3, 1))
            self.obstacles.append(box)
        self.robot = p.loadURDF(self.urdf, physicsClientId=cid)
        index = {
            p.getJointInfo(self.robot, j, physicsClientId=cid)[1].decode(): j
            for j in range(p.getNumJoints(self.robot, physicsClientId=cid))
        }
        self.wheels = [index[n] for n in (*self.params.left_joints, *self.params.right_joints)]
        for wheel in self.wheels:
            p.changeDynamics(
                self.robot,
                wheel,
                anisotropicFriction=(1.0, WHEEL_SIDEWAYS_FRICTION, 1.0),
                physicsClientId=cid,
            )
        self.reset()

    def reset(self, hall: Hall | None = None) -> DroneState:
        """Puts the Husky at rest at ``hall``'s start (None: the current task's), its wheels
        and drive stopped, and the clock at 0."""
        if hall is not None:
            self.hall = hall
        cid = self.client
        p.resetBasePositionAndOrientation(
            self.robot,
            [*self.hall.start, 0.0],
            p.getQuaternionFromEuler([0.0, 0.0, self.hall.yaw]),
            physicsClientId=cid,
        )
        p.resetBaseVelocity(self.robot, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=cid)
        for j in self.wheels:
            p.resetJointState(self.robot, j, 0.0, 0.0, physicsClientId=cid)
        self.rims = np.zeros(2)
        self._drive()
        self.physics_steps = 0
        return self.state()

    @property
    def goal(self) -> np.ndarray:
        """The goal (x, y, z) on the ground, where the odometry's origin is."""
        return np.array([*self.hall.goal, 0.0])

    def state(self) -> DroneState:
        """The root link's pose and twist (world frame)."""
        return DroneState.of_base(self.robot, self.client)

    def scan(self, state: DroneState | None = None) -> np.ndarray:
        """The LiDAR's ranges (m) for bearings −π + i·2π/360 from the robot's heading, from its
        origin in the plane of the chassis's top; +inf where nothing is within 10 m."""
        s = state or self.state()
        origin = np.array([s.position[0], s.position[1], self.params.chassis_top])
        return self.lidar(origin, float(s.rpy[2]), HALL_LIDAR.range_min, HALL_LIDAR)

    def in_collision(self) -> bool:
        """True when the Husky touches a wall or a pallet (the floor does not count)."""
        cid = self.client
        return any(
            p.getContactPoints(bodyA=self.robot, bodyB=o, physicsClientId=cid)
            for o in self.obstacles
        )

    def min_obstacle_distance(self, state: DroneState | None = None) -> float:
        """Distance (m) from the robot's origin to the nearest wall or pallet face, in the
        plane."""
        s = state or self.state()
        return self.hall.clearance(s.position[:2])

    def _drive(self) -> None:
        """Sets every wheel's motor to its side's rim speed."""
        left, right = self.rims / self.params.wheel_radius
        n_left = len(self.params.left_joints)
        p.setJointMotorControlArray(
            self.robot,
            self.wheels,
            p.VELOCITY_CONTROL,
            targetVelocities=[left] * n_left + [right] * (len(self.wheels) - n_left),
            forces=[WHEEL_TORQUE] * len(self.wheels),
            physicsClientId=self.client,
        )

    def step(self, v: float, omega: float) -> DroneState:
        """One control step (0.1 s) toward forward speed ``v`` (m/s) and turn rate ``omega``
        (rad/s), within the rims' speed and acceleration bounds."""
        target = self.params.rim_speeds(v, omega)
        change = MAX_ACCELERATION / PHYSICS_HZ
        for _ in range(STEPS_PER_CONTROL):
            self.rims = self.rims + np.clip(target - self.rims, -change, change)
            self._drive()
            p.stepSimulation(physicsClientId=self.client)
            self.physics_steps += 1
        return self.state()
