"""PyBullet world of the paper's drone experiment: arena, obstacle block, Crazyflie, 2D LiDAR, PID.

Geometry as the authors' prototype codes it (``config/paper_world.json``, which the Rust core's
``arena.rs`` reads too; :mod:`~cstep_bridge.sim.paper_world`): the inner area is
x ∈ [−0.5, 4.5], y ∈ [−1.75, 0.75], z ∈ [0, 2] (the paper's 5 m × 2.5 m × 2 m); the obstacle is
two 1.0 m × 0.5 m blocks centred at (1, ``block_y``) and (2, ``block_y``), i.e. one 2 m × 0.5 m
block spanning x ∈ [0.5, 2.5], y ∈ [``block_y`` − 0.25, ``block_y`` + 0.25], 2 m high, with
``block_y`` ~ U(−1, 0.3); start x ~ U(−0.3, 0), goal x ~ U(2.7, 4.2), both with y ~ U(−1.6, 0.4),
at 1 m altitude. The gaps beside the block are 0.2–1.8 m wide (the narrowest, 0.2 m above a
block at y = 0.3, passes the drone's 0.12 m diameter).

Deviations from the prototype, on purpose: the observation carries the goal (the prototype's
does not, so its agent cannot know where to go; the paper's text says the agents observe the
relative distance to the goal) and not the prototype's 15 past actions; the goal is kept
where it is drawn.

The drone is ``urdf/cf2x.urdf``. Each physics step (240 Hz) applies the thrust kf·ω² of every rotor
at its position and the yaw reaction torque km·(ω0² − ω1² + ω2² − ω3²) (rotors 0 and 2 clockwise),
with ω in rpm, clamped to the URDF's maximum. The waypoint controller is cascaded: the position
loop runs at the 30 Hz control rate (every 8 physics steps) and sets collective thrust and desired
attitude; the attitude loop runs every physics step, as a real flight controller's inner loop does
(a 30 Hz attitude loop cannot hold a 27 g airframe), and the mixer turns both into rotor speeds.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pybullet as p

from ..resources import drone_urdf
from .paper_world import ARENA
from .world import PHYSICS_HZ, PhysicsWorld, clearance, wall_distance

G = 9.8
CONTROL_HZ = 30
STEPS_PER_CONTROL = PHYSICS_HZ // CONTROL_HZ  # 8


@dataclass(frozen=True)
class DroneParams:
    """What the controller and the motor model need, read from the URDF."""

    mass: float
    inertia: tuple[float, float, float]
    kf: float
    km: float
    arm: float
    thrust2weight: float
    radius: float
    rotors: tuple[tuple[float, float, float], ...]

    @property
    def max_rpm(self) -> float:
        return math.sqrt(self.thrust2weight * self.mass * G / (4 * self.kf))

    @property
    def hover_rpm(self) -> float:
        return math.sqrt(self.mass * G / (4 * self.kf))

    @classmethod
    def from_urdf(cls, path: Path | str | None = None) -> DroneParams:
        """The parameters in the URDF at ``path`` (None: the Crazyflie's,
        :func:`~cstep_bridge.resources.drone_urdf`), read by the core's rules
        (``crates/cstep-core/src/model/urdf.rs``; ``tests/python/test_urdf_agreement.py`` checks
        that both sides read the same robot): the mass of all links, the inertia and collision
        extent of the base link (the one that is no joint's child)."""
        path = path or drone_urdf()
        root = ET.parse(path).getroot()
        props = root.find("properties")
        if props is None:
            raise ValueError(f"{path}: no <properties> element (kf, km, arm, thrust2weight)")
        links = root.findall("link")
        children = {j.find("child").get("link") for j in root.findall("joint")}
        bases = [link for link in links if link.get("name") not in children]
        if len(bases) != 1:
            raise ValueError(f"{path}: expected exactly one root link, found {len(bases)}")
        (base,) = bases
        mass = sum(float(m.get("value")) for m in root.findall("link/inertial/mass"))
        ine = base.find("inertial/inertia")
        rotors = []
        for i in range(4):
            joint = root.find(f"joint[@name='body_to_rotor{i}']")
            xyz = tuple(float(v) for v in joint.find("origin").get("xyz").split())
            rotors.append(xyz)
        return cls(
            mass=mass,
            inertia=(float(ine.get("ixx")), float(ine.get("iyy")), float(ine.get("izz"))),
            kf=float(props.get("kf")),
            km=float(props.get("km")),
            arm=float(props.get("arm")),
            thrust2weight=float(props.get("thrust2weight")),
            radius=_collision_radius(base, path),
            rotors=tuple(rotors),
        )


def _collision_radius(link: ET.Element, path: Path | str) -> float:
    """The horizontal radius that encloses ``link``'s collision shapes about its origin: each
    shape's half-width (a tilted one's bounding sphere) plus its horizontal offset."""
    radius = None
    for collision in link.findall("collision"):
        origin = collision.find("origin")
        xyz = [
            float(v)
            for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()
        ]
        rpy = [
            float(v)
            for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()
        ]
        geometry = collision.find("geometry")
        shape = geometry[0] if geometry is not None and len(geometry) else None
        if shape is None or shape.tag == "mesh":
            continue
        if shape.tag in ("cylinder", "capsule"):
            r, h = float(shape.get("radius")), float(shape.get("length")) / 2
            half_width, sphere = r, (math.hypot(r, h) if shape.tag == "cylinder" else h + r)
        elif shape.tag == "sphere":
            half_width = sphere = float(shape.get("radius"))
        else:  # box
            x, y, z = (float(v) for v in shape.get("size").split())
            half_width, sphere = math.hypot(x, y) / 2, math.hypot(x, y, z) / 2
        tilted = abs(rpy[0]) > 1e-9 or abs(rpy[1]) > 1e-9
        extent = math.hypot(xyz[0], xyz[1]) + (sphere if tilted else half_width)
        radius = extent if radius is None else max(radius, extent)
    if radius is None:
        raise ValueError(f"{path}: link '{link.get('name')}' has no collision shape")
    return radius


@dataclass
class Arena:
    """The arena of the drone experiment (metres, world frame)."""

    block_y: float = 0.0
    bounds: tuple[float, float, float, float] = tuple(ARENA["bounds"])
    block_x: tuple[float, float] = tuple(ARENA["block_x"])
    block_width: float = ARENA["block_width"]
    height: float = ARENA["height"]
    altitude: float = ARENA["altitude"]
    start: np.ndarray = field(
        default_factory=lambda: np.array([*ARENA["start"], ARENA["altitude"]])
    )
    goal: np.ndarray = field(default_factory=lambda: np.array([*ARENA["goal"], ARENA["altitude"]]))

    @property
    def block(self) -> tuple[float, float, float, float]:
        h = self.block_width / 2
        return (self.block_x[0], self.block_y - h, self.block_x[1], self.block_y + h)

    @classmethod
    def random(cls, rng: np.random.Generator) -> Arena:
        """One configuration drawn as the prototype draws it."""
        draws, z = ARENA["draws"], ARENA["altitude"]
        block_y = rng.uniform(*draws["block_y"])
        start = np.array([rng.uniform(*draws["start_x"]), rng.uniform(*draws["start_y"]), z])
        goal = np.array([rng.uniform(*draws["goal_x"]), rng.uniform(*draws["goal_y"]), z])
        return cls(block_y=block_y, start=start, goal=goal)

    def wall_distance(self, xy: np.ndarray) -> float:
        """Distance (m) from a point to the nearest of the four walls, 2D (not the block)."""
        return wall_distance(xy, self.bounds)

    def clearance(self, xy: np.ndarray) -> float:
        """Distance (m) from a point to the nearest wall or block face, 2D (negative inside)."""
        return clearance(xy, self.bounds, (self.block,))


@dataclass
class DroneState:
    """Kinematic state, world frame unless named body."""

    position: np.ndarray
    quaternion: np.ndarray  # x, y, z, w (PyBullet and ROS order)
    velocity: np.ndarray
    angular_velocity: np.ndarray
    rotation: np.ndarray  # body → world

    @classmethod
    def of_base(cls, body: int, client: int) -> DroneState:
        """The state of PyBullet body ``body``'s base (its root link) in ``client``."""
        pos, quat = p.getBasePositionAndOrientation(body, physicsClientId=client)
        vel, ang = p.getBaseVelocity(body, physicsClientId=client)
        rot = np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)
        return cls(np.array(pos), np.array(quat), np.array(vel), np.array(ang), rot)

    @property
    def rpy(self) -> np.ndarray:
        return np.array(p.getEulerFromQuaternion(self.quaternion))

    @property
    def body_velocity(self) -> np.ndarray:
        return self.rotation.T @ self.velocity

    @property
    def body_angular_velocity(self) -> np.ndarray:
        return self.rotation.T @ self.angular_velocity

    @property
    def tilt(self) -> float:
        """Angle (rad) between the body z axis and the vertical."""
        return float(math.acos(max(-1.0, min(1.0, self.rotation[2, 2]))))


class PIDController:
    """Cascaded waypoint controller: position PID (30 Hz) → thrust + attitude PD (240 Hz) → rpm."""

    def __init__(self, params: DroneParams) -> None:
        self.params = params
        # Horizontal: ω_n ≈ 3.5 rad/s, ζ = 0.5; a waypoint held 0.1 m ahead (the largest action)
        # settles at kp/kd · 0.1 m ≈ 0.34 m/s. No integral term horizontally: the waypoints are
        # offsets from the drone, so while it moves the error never settles and an integral
        # only winds up — with one (ki 0.5), a zero offset held after 3 s of flight drifted on
        # at 0.042 m/s for good, driven by a state the agent cannot observe. Vertically the
        # integral holds the altitude.
        self.kp = np.array([12.0, 12.0, 10.0])
        self.kd = np.array([3.5, 3.5, 6.0])
        self.ki = np.array([0.0, 0.0, 2.0])
        self.max_tilt = 0.5  # rad, commanded
        wn, zeta = 25.0, 0.8
        inertia = np.array(params.inertia)
        self.k_att = inertia * wn**2
        self.k_rate = inertia * 2 * zeta * wn
        self.reset()

    def reset(self) -> None:
        self.integral = np.zeros(3)
        self.thrust = self.params.mass * G
        self.r_des = np.eye(3)

    def position_loop(self, state: DroneState, target: np.ndarray, dt: float) -> None:
        """Sets collective thrust and desired attitude (yaw 0) for the waypoint ``target``."""
        err = target - state.position
        self.integral = np.clip(self.integral + err * dt, -0.5, 0.5)
        acc = self.kp * err - self.kd * state.velocity + self.ki * self.integral
        horiz = np.linalg.norm(acc[:2])
        limit = G * math.tan(self.max_tilt)
        if horiz > limit:
            acc[:2] *= limit / horiz
        acc[2] = max(acc[2] + G, 0.2 * G)
        force = self.params.mass * acc
        z_b = force / np.linalg.norm(force)
        # y_b = z_b × x_c with x_c = (1, 0, 0), and x_b = y_b × z_b, written out: np.cross on
        # 3-vectors cost more than the rest of the position loop.
        y_b = np.array([0.0, z_b[2], -z_b[1]])
        y_b /= np.linalg.norm(y_b)
        x_b = np.array(
            [
                y_b[1] * z_b[2] - y_b[2] * z_b[1],
                y_b[2] * z_b[0] - y_b[0] * z_b[2],
                y_b[0] * z_b[1] - y_b[1] * z_b[0],
            ]
        )
        self.r_des = np.column_stack([x_b, y_b, z_b])
        self.thrust = float(force @ state.rotation[:, 2])

    def rotor_rpm(self, state: DroneState) -> np.ndarray:
        """Attitude loop and mixer: rotor speeds (rpm) for the current setpoint.

        Runs at every physics step, so it works on scalars: numpy's per-call cost on 3-vectors
        was most of an env step. The attitude error is the vee of ½(R_dᵀR − RᵀR_d), and
        RᵀR_d = (R_dᵀR)ᵀ.
        """
        m = self.r_des.T @ state.rotation
        e_r = (
            0.5 * (m[2, 1] - m[1, 2]),
            0.5 * (m[0, 2] - m[2, 0]),
            0.5 * (m[1, 0] - m[0, 1]),
        )
        w = state.body_angular_velocity
        torque = [
            -ka * e - kr * wi for ka, e, kr, wi in zip(self.k_att, e_r, self.k_rate, w, strict=True)
        ]
        pr = self.params
        d = abs(pr.rotors[0][0])  # rotor offset along x and y
        a, b = torque[0] / d, torque[1] / d
        c = torque[2] * pr.kf / pr.km
        t = self.thrust
        forces = (t - a - b + c, t - a + b - c, t + a + b + c, t + a - b - c)
        top = pr.max_rpm
        return np.array([min(math.sqrt(max(f / 4, 0.0) / pr.kf), top) for f in forces])


class DroneSim(PhysicsWorld):
    """The drone in the arena. ``step(waypoint)`` advances one 30 Hz control step."""

    def __init__(
        self,
        arena: Arena | None = None,
        gui: bool = False,
        urdf: Path | str | None = None,
    ) -> None:
        """Builds ``arena`` (None: the default one) with the drone from ``urdf`` (None: the
        Crazyflie's, :func:`~cstep_bridge.resources.drone_urdf`), headless unless ``gui``."""
        super().__init__(gui)
        urdf = urdf or drone_urdf()
        self.params = DroneParams.from_urdf(urdf)
        self.urdf = str(urdf)
        self.controller = PIDController(self.params)
        self.arena = arena or Arena()
        self.obstacles: list[int] = []
        self.static: list[int] = []
        self.drone = -1
        self.rpm = np.zeros(4)
        self.reset(self.arena)

    # --- world ---------------------------------------------------------------------------
    def reset(self, arena: Arena | None = None) -> DroneState:
        """Rebuild the world for ``arena`` and put the drone at rest at its start."""
        if arena is not None:
            self.arena = arena
        cid = self.client
        self._restart(G)
        a = self.arena
        x0, y0, x1, y1 = a.bounds
        t, h = 0.1, a.height
        floor = self.add_box((x0 - t, y0 - t, -t), (x1 + t, y1 + t, 0.0), (0.8, 0.8, 0.8, 1))
        ceiling = self.add_box((x0 - t, y0 - t, h), (x1 + t, y1 + t, h + t), (0.8, 0.8, 0.8, 0.1))
        walls = [
            self.add_box((x0 - t, y0 - t, 0), (x0, y1 + t, h)),
            self.add_box((x1, y0 - t, 0), (x1 + t, y1 + t, h)),
            self.add_box((x0, y0 - t, 0), (x1, y0, h)),
            self.add_box((x0, y1, 0), (x1, y1 + t, h)),
        ]
        bx0, by0, bx1, by1 = a.block
        block = self.add_box((bx0, by0, 0), (bx1, by1, h), (0.8, 0.3, 0.2, 1))
        self.static = [floor, ceiling]
        self.view_ceiling = h
        self.obstacles = [*walls, block]
        self.block_id = block
        self.drone = p.loadURDF(
            self.urdf,
            a.start.tolist(),
            flags=p.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=cid,
        )
        self.controller.reset()
        self.target = a.start.copy()
        self.rpm = np.full(4, self.params.hover_rpm)
        return self.state()

    # --- state and sensors ---------------------------------------------------------------
    @property
    def goal(self) -> np.ndarray:
        """The arena's goal (x, y, z)."""
        return self.arena.goal

    def state(self) -> DroneState:
        return DroneState.of_base(self.drone, self.client)

    def scan(self, state: DroneState | None = None) -> np.ndarray:
        """LiDAR ranges (m) for bearings angle_min + i·increment in the body frame (yaw only:
        a levelled 2D scanner at the drone's centre); +inf where nothing is within 3 m (REP 117).
        """
        s = state or self.state()
        return self.lidar(s.position, s.rpy[2], self.params.radius + 0.01)

    def in_collision(self) -> bool:
        """True when the drone touches anything (walls, block, floor, ceiling)."""
        return bool(p.getContactPoints(bodyA=self.drone, physicsClientId=self.client))

    def min_obstacle_distance(self, state: DroneState | None = None) -> float:
        """Distance (m) from the drone's centre to the nearest wall or block face, in the plane."""
        s = state or self.state()
        return self.arena.clearance(s.position[:2])

    # --- stepping ------------------------------------------------------------------------
    def _apply_rotors(self, state: DroneState) -> None:
        pr, cid = self.params, self.client
        thrust = pr.kf * self.rpm**2
        for i, pos in enumerate(pr.rotors):
            p.applyExternalForce(
                self.drone, -1, [0, 0, thrust[i]], pos, p.LINK_FRAME, physicsClientId=cid
            )
        w2 = self.rpm**2
        yaw = pr.km * (w2[0] - w2[1] + w2[2] - w2[3])
        # World frame: PyBullet's LINK_FRAME torque on a base is unreliable across versions.
        torque = state.rotation @ np.array([0.0, 0.0, yaw])
        p.applyExternalTorque(self.drone, -1, torque.tolist(), p.WORLD_FRAME, physicsClientId=cid)

    def step(self, waypoint: np.ndarray) -> DroneState:
        """One control step (1/30 s): track ``waypoint`` (x, y, z) for 8 physics steps."""
        self.target = np.asarray(waypoint, dtype=float)
        state = self.state()
        self.controller.position_loop(state, self.target, 1.0 / CONTROL_HZ)
        for _ in range(STEPS_PER_CONTROL):
            self.rpm = self.controller.rotor_rpm(state)
            self._apply_rotors(state)
            p.stepSimulation(physicsClientId=self.client)
            self.physics_steps += 1
            state = self.state()
        return state
