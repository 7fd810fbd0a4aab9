"""The authoritative simulation: one MuJoCo world, a fixed physics step on a
simulated clock, robots spawned and removed while others run, sensors measured at
their own ScanInterval of simulated time.

This object is used from one thread only (the simulation thread, see
:mod:`usarsim.sim.runner`); readings leave it as :class:`Output` records.
"""

from __future__ import annotations

import dataclasses
import heapq
import itertools
import logging
import math
from dataclasses import dataclass, field
from typing import Any, Callable

import mujoco
import numpy as np

from usarsim.config.robot import RobotConfig
from usarsim.config.world import WorldConfig
from usarsim.errors import ConfigError, SimulationError
from usarsim.readings import CommandResult, EffecterState, PackageState, RobotStatus
from usarsim.sensors import Sensor, make_sensor
from usarsim.sim import builder, frames
from usarsim.sim.entities import Entities
from usarsim.sim.outputs import ItemDescription, Output
from usarsim.sim.view import RayCaster, RobotHandle, WorldView

log = logging.getLogger("usarsim.sim")

EPS = 1e-9
# No joint of a robot moves faster than this (m/s or rad/s): a robot beyond it has
# blown up numerically (wheels top out near 5 rad/s, a fall from 10 m reaches 14 m/s).
MAX_SANE_VELOCITY = 100.0
# At the rated mechanical power of all its motors a battery drains this much faster than
# at rest (one extra second per second): our model of UT2004's faster drain under load.
BATTERY_LOAD_FACTOR = 1.0
# Self-righting (DRIVE {Flip True}, protocol.md 8): UT2004's KRobot applied FlipTorque for
# FlipTime = 3 s to an overturned robot.  The torque here rolls the robot about the axis
# that brings its top up, sized to lift its weight at half its width or height, twice
# over (UT's FlipTorque 350 was in engine units), until it is within 25 degrees of upright.
FLIP_TIME_S = 3.0
FLIP_MARGIN = 2.0
OVERTURNED_COS = math.cos(math.radians(60.0))  # more than 60 degrees from upright
AERIAL_LEVEL_STIFFNESS = 20.0  # N m per rad of tilt per kg: hovering robots right themselves
# Forces the simulation sets by hand (self-righting, levelling, water) are renewed at least
# every 10 physics steps (40 ms).
EXTERNAL_FORCE_STEPS = 10
GAIT_STEPS = 5  # a walking robot's joint targets are renewed every 5 physics steps (20 ms)
HULL_CROSS_DRAG = 10.0  # a vessel's drag across its hull, relative to along it
HULL_PITCH_RIGHTING = 0.05  # its pitch righting, relative to its roll righting
def leg_ik(fx: float, fy: float, fz: float, upper: float, lower: float,
           knee_forward: bool = False) -> tuple[float, float, float]:
    """Hip pitch, hip roll and knee angles that put a foot at (fx, fy, fz) from its hip
    (USARSim frame: forward, right, down), for a leg of two segments whose knee bends
    backwards (or forwards, as a person's, with ``knee_forward``).  Positive pitch swings
    the leg forward, positive roll swings it left, a positive knee folds the lower leg
    forward.  The roll turns the plane in which pitch and knee move."""
    roll = -math.atan2(fy, fz)
    down = math.hypot(fy, fz)
    d = min(max(math.hypot(fx, down), abs(upper - lower) + 1e-6), (upper + lower) * 0.999)
    inner = math.acos(max(-1.0, min(1.0, (upper ** 2 + lower ** 2 - d ** 2) / (2 * upper * lower))))
    beta = math.acos(max(-1.0, min(1.0, (upper ** 2 + d ** 2 - lower ** 2) / (2 * upper * d))))
    if knee_forward:
        return math.atan2(fx, down) + beta, roll, inner - math.pi
    return math.atan2(fx, down) - beta, roll, math.pi - inner


def _smooth(x: float) -> float:
    """0 to 1 over x in [0, 1], with zero slope at both ends."""
    return 0.5 - 0.5 * math.cos(math.pi * min(1.0, max(0.0, x)))


def sane_velocity(robot: RobotConfig) -> float:
    """Above this speed (m/s or rad/s) a joint of ``robot`` has blown up: MAX_SANE_VELOCITY, or
    three times its top wheel speed for fast vehicles (a car's wheels spin at 180 rad/s)."""
    return max(MAX_SANE_VELOCITY, 3.0 * robot.max_speed_rad_s)


# What a physics step changes: kept before each stretch of steps to replay it on a blow-up.
STATE = int(mujoco.mjtState.mjSTATE_INTEGRATION)


@dataclass(eq=False)
class _Unit:
    """A scheduled measurement: one sensor, or all packed sensors of a type on a robot."""

    robot: "SimRobot"
    sensors: list[Sensor]
    interval: float
    t0: float
    key: str
    status: bool = False
    package: object = None  # a MissionPackage: MISSTA
    k: int = 0

    @property
    def due(self) -> float:
        return self.t0 + self.k * self.interval


@dataclass(eq=False)
class SimRobot:
    uid: int
    name: str
    config: RobotConfig
    prefix: str
    spawn_time: float
    handle: RobotHandle
    sensors: list[Sensor]
    units: list[_Unit] = field(default_factory=list)
    left: float = 0.0
    right: float = 0.0
    light: bool = False
    battery_empty: bool = False
    removed: bool = False
    resets: int = 0
    owner_index: int = 0
    spawn_qpos: np.ndarray | None = None
    # link joints: name -> (order, value) with order 0 position, 1 speed, 2 torque
    joints: dict = field(default_factory=dict)
    wheel_speed: dict = field(default_factory=dict)  # per-wheel speed set by a joint command
    speed: float = 0.0  # Ackermann: driven wheels' spin speed, rad/s
    front_steer: float = 0.0  # Ackermann: commanded axle angles, rad (positive: right)
    rear_steer: float = 0.0
    wheel_steer: dict = field(default_factory=dict)  # holonomic: wheel name -> angle
    fly: dict = field(default_factory=lambda: {"altitude": 0.0, "linear": 0.0, "lateral": 0.0, "rotational": 0.0})
    sail: dict = field(default_factory=lambda: {"propeller": 0.0, "rudder": 0.0, "stern_plane": 0.0})
    walk: dict = field(default_factory=lambda: {"linear": 0.0, "lateral": 0.0, "rotational": 0.0})
    # the cameras chosen by SET {Type Viewports} (protocol.md 5.4): the first is the one the
    # MultiView shows; empty: the robot's first camera
    viewports: tuple[str, ...] = ()
    # a walking robot's gait: its clock; how far it has set off (0 standing, 1 walking;
    # it fades in and out over half a period); the velocities it walks at (they follow
    # the command within half a period); each foot's place (forward, right, yaw) from
    # under its hip and where its swing began; the time the gait was last set
    gait_clock: float = 0.0
    gait_amp: float = 0.0
    gait_vel: tuple = (0.0, 0.0, 0.0)
    gait_last: float = 0.0
    feet: list = field(default_factory=list)
    swing_from: list = field(default_factory=list)
    in_water: bool = False

    battery_used_s: float = 0.0
    rated_power_w: float = 1.0
    flip_until: float = -1.0  # self-righting torque applied until this simulated time
    flip_sign: float = 0.0

    def battery_left(self, now: float | None = None) -> float:
        return max(0.0, self.config.battery_s - self.battery_used_s)


def describe_items(robot: RobotConfig, seed: int = 0) -> list[ItemDescription]:
    """The mounted items of a robot class as GETGEO/GETCONF describe them (also
    validates every sensor's configuration)."""
    out = []
    for item in robot.items:
        s = make_sensor(item, robot, seed, "describe")
        out.append(ItemDescription(s.TYPE, item.name, item.location, item.orientation, item.mount, s.conf_fields()))
    return out


class Simulation:
    def __init__(self, world: WorldConfig, *, seed: int = 0):
        self.world = world
        self.seed = seed
        self.dt = world.timestep_s
        self.spec = builder.world_spec(world)
        self.model = self.spec.compile()
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.step_count = 0
        self.robots: dict[int, SimRobot] = {}
        self._heap: list[tuple[float, int, _Unit]] = []
        self._seq = itertools.count()
        self.outbox: list[Output] = []
        self.entities = Entities(world)
        self.entities.resolve(self.model)
        self.caster = RayCaster(self.model, self.data, see_through=self.entities.see_through)
        self.physics_steps = 0
        self.resets = 0
        self._good_qpos: np.ndarray | None = None
        self._actuator_owner: np.ndarray | None = None
        self._owner_count = 1
        self._aerial = False
        self._sane = MAX_SANE_VELOCITY
        self._legged = False
        self._rollers: list = []
        self._roller_pushed: set[int] = set()
        # CONF fields that changed at run time (a camera's zoom), by (robot id, type, name);
        # read by the server thread (plain dict reads and replacements are atomic)
        self.live_conf: dict[tuple[int, str, str], tuple] = {}
        self._snapshot: np.ndarray | None = None
        # the MultiView (manual 3.2.6): how many robot cameras it shows at most
        self._multiview_cameras = 4
        self._multiview: list[tuple[int, str]] | None = None
        self._multiview_robots: set[int] = set()
        # called with the simulation at the end of every ``advance`` (on the simulation
        # thread, at the simulated instant the clock reached): the wireless links
        self.after_advance: list[Callable[["Simulation"], None]] = []

    # Clock -------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.step_count * self.dt

    def view(self) -> WorldView:
        return WorldView(self.model, self.data, self.time, self.caster, self.world, self.entities)

    # Model changes ------------------------------------------------------------
    def _rebuild(self) -> None:
        self.model, self.data = self.spec.recompile(self.model, self.data)
        self.entities.resolve(self.model)
        self.entities.update(self.data, self.time)
        mujoco.mj_forward(self.model, self.data)
        self.caster = RayCaster(self.model, self.data, see_through=self.entities.see_through)
        self._good_qpos = self.data.qpos.copy()
        view = self.view()
        for r in self.robots.values():
            self._configure(r, view)
        self._index_actuators()

    def _index_actuators(self) -> None:
        """Which robot each actuator belongs to (for the batteries' load), and each
        robot's rated mechanical power."""
        m = self.model
        owners = np.zeros(m.nu, dtype=np.intp)
        for i, r in enumerate(self.robots.values(), start=1):
            r.owner_index = i
            rated = 0.0
            for name, a in r.handle.actuator.items():
                owners[a] = i
                ln = r.config.link(name)
                if ln is not None:
                    rated += ln.max_torque * ln.max_speed
                else:
                    rated += r.config.wheel_torque_limit_nm * r.config.max_speed_rad_s
            lim = r.config.aerial
            for axis, a in r.handle.rotor.items():
                owners[a] = i
                if axis in ("linear", "lateral", "vertical"):
                    rated += lim.max_accel_m_s2 * r.config.mass_kg * lim.max_linear_m_s
            r.rated_power_w = max(rated, 1e-6)
        self._actuator_owner = owners
        self._owner_count = len(self.robots) + 1
        self._aerial = any(r.config.drive == "aerial" for r in self.robots.values())
        self._sane = max([MAX_SANE_VELOCITY] + [sane_velocity(r.config) for r in self.robots.values()])
        self._legged = any(r.config.gait is not None for r in self.robots.values())
        self._rollers = [s for r in self.robots.values() for s in r.sensors if s.TYPE == "RollerTable"]

    def _configure(self, r: SimRobot, view: WorldView) -> None:
        r.handle.resolve(self.model, r.config.wheels, r.config.links)
        for s in r.sensors:
            s.configure(view)
        self._apply_ctrl(r)
        for ln in r.config.links:
            self._apply_joint(r, ln)

    def spawn(self, uid: int, robot: RobotConfig, name: str, location, rotation, set_down: bool = False) -> SimRobot:
        """Add a robot at once, at the current simulated time; others keep their state.
        ``set_down`` (a start pose): a level robot is put with its lowest point its own
        ``spawn_clearance_m`` above the surface below the pose, so that it lands on its
        wheels, tracks or legs wherever the pose is; walking robots are always set down."""
        if uid in self.robots:
            raise SimulationError(f"robot id {uid} already exists")
        loc = tuple(float(v) for v in location)
        rot = tuple(float(v) for v in rotation)
        if not all(math.isfinite(v) for v in loc + rot):
            raise SimulationError(f"location and rotation must be finite numbers, got {loc} {rot}")
        fl = self.world.floor
        if not (abs(loc[0] - fl.center[0]) <= fl.size[0] / 2 and abs(loc[1] - fl.center[1]) <= fl.size[1] / 2):
            raise SimulationError(
                f"location {loc[0]:.2f},{loc[1]:.2f} is outside the world '{self.world.name}' "
                f"(x within {fl.center[0] - fl.size[0] / 2:.2f}..{fl.center[0] + fl.size[0] / 2:.2f}, "
                f"y within {fl.center[1] - fl.size[1] / 2:.2f}..{fl.center[1] + fl.size[1] / 2:.2f})")
        if not (-100.0 <= loc[2] <= 100.0):
            raise SimulationError(f"location z {loc[2]:.2f} is too far from the floor (allowed -100..100 m)")
        level = abs(rot[0]) < 1e-6 and abs(rot[1]) < 1e-6
        # a level robot put lower than it stands (its wheels in the floor) is lifted onto it
        if level and loc[2] > -robot.lowest_point_m:
            loc = (loc[0], loc[1], -robot.lowest_point_m - 0.005)
        # a robot at a start pose is set down on what lies below it (a vessel starts where
        # the pose is: in water), and a walking robot wherever it is put (a standing biped
        # would not survive a drop)
        if level and ((set_down and robot.drive != "nautical") or robot.gait is not None):
            ground = self._ground_below(loc)
            if ground is not None:
                loc = (loc[0], loc[1], ground - robot.lowest_point_m - robot.spawn_clearance_m)
        prefix = f"robot{uid}"
        try:
            sensors = [make_sensor(item, robot, self.seed, f"{uid}:{name}") for item in robot.items]
        except ConfigError as exc:
            raise SimulationError(str(exc)) from exc
        builder.add_robot(self.spec, robot, prefix, loc, rot)
        r = SimRobot(uid=uid, name=name, config=robot, prefix=prefix, spawn_time=self.time,
                     handle=RobotHandle(prefix), sensors=sensors)
        for s in sensors:
            s.handle = r.handle
        self.robots[uid] = r
        try:
            self._rebuild()
        except Exception:
            del self.robots[uid]
            builder.remove_robot(self.spec, prefix)
            self._rebuild()
            raise
        if robot.gait is not None:
            self._stand_up(r)
        view = self.view()
        for s in sensors:
            s.reset(view)
        h = r.handle
        r.spawn_qpos = self.data.qpos[h.root_qpos:h.root_qpos + 7].copy()
        self._good_qpos = self.data.qpos.copy()
        self._schedule_robot(r)
        log.info("spawned %s '%s' (id %d) at %.2f,%.2f,%.2f at t=%.3f", robot.class_name, name, uid, *loc, self.time)
        return r

    def _ground_below(self, loc) -> float | None:
        """The USARSim z of the first surface straight below ``loc`` (None: nothing)."""
        start = frames.to_mj_vec(loc)
        geom = np.array([-1], dtype=np.int32)
        dist = mujoco.mj_ray(self.model, self.data, start, np.array([0.0, 0.0, -1.0]), None, 1, -1, geom)
        return None if dist < 0 else loc[2] + dist

    def remove(self, uid: int) -> None:
        r = self.robots.pop(uid, None)
        if r is None:
            return
        r.removed = True
        for key in [k for k in self.live_conf if k[0] == uid]:
            del self.live_conf[key]
        builder.remove_robot(self.spec, r.prefix)
        self._rebuild()
        log.info("removed robot '%s' (id %d) at t=%.3f", r.name, uid, self.time)

    def _schedule_robot(self, r: SimRobot) -> None:
        """Every report of the robot on its own period, on the world's grid of that period
        (multiples of it in simulated time, from the first one at or after the spawn): the
        reports of all robots fall on the same instants, so the physics runs in long
        stretches between them."""
        t = self.time

        def on_grid(interval: float) -> float:
            return math.ceil(t / interval - 1e-6) * interval

        units = [_Unit(r, [], r.config.status_interval_s, on_grid(r.config.status_interval_s), "STA", status=True)]
        for pkg in r.config.mission_packages:
            units.append(_Unit(r, [], r.config.status_interval_s, on_grid(r.config.status_interval_s),
                               f"MISSTA:{pkg.name}", package=pkg))
        packed: dict[str, _Unit] = {}
        for s in r.sensors:
            if not s.PERIODIC:
                continue
            if s.PACKED:
                u = packed.get(s.TYPE)
                if u is None:
                    u = _Unit(r, [], s.config.scan_interval_s, on_grid(s.config.scan_interval_s), f"SEN:{s.TYPE}")
                    packed[s.TYPE] = u
                    units.append(u)
                u.sensors.append(s)
            else:
                units.append(_Unit(r, [s], s.config.scan_interval_s, on_grid(s.config.scan_interval_s),
                                   f"SEN:{s.TYPE}:{s.name}"))
        r.units = units
        for u in units:
            heapq.heappush(self._heap, (u.due, next(self._seq), u))

    # Commands -----------------------------------------------------------------
    def drive_skid(self, uid: int, left: float | None, right: float | None, normalized: bool = False,
                   light: bool | None = None) -> None:
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return
        if light is not None:
            r.light = bool(light)
        if r.config.drive != "skid":
            return
        vmax = r.config.max_speed_rad_s
        scale = vmax / 100.0 if normalized else 1.0
        if left is not None and math.isfinite(left):
            r.left = max(-vmax, min(vmax, left * scale))
        if right is not None and math.isfinite(right):
            r.right = max(-vmax, min(vmax, right * scale))
        if left is not None or right is not None:
            r.wheel_speed.clear()  # a skid DRIVE takes the wheels back from joint commands
        self._apply_ctrl(r)

    def flip(self, uid: int) -> bool:
        """Start righting an overturned robot; False (ignored) when it is upright."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return False
        up_z = float(self.data.xmat[r.handle.body_id][8])  # world z of the body's up axis
        if up_z > OVERTURNED_COS:
            return False
        r.flip_until = self.time + FLIP_TIME_S
        log.info("robot '%s' (id %d): self-righting for %.0f s", r.name, r.uid, FLIP_TIME_S)
        return True

    def _apply_flips(self) -> None:
        """Roll each robot being righted about its own forward axis (sideways is the easy way
        over) towards upright: a torque growing with its tilt, damped by its roll rate so
        that it does not roll on past upright; exactly upside down it rolls to its right."""
        d = self.data
        for r in self.robots.values():
            if r.flip_until < 0:
                continue
            b = r.handle.body_id
            rot = d.xmat[b].reshape(3, 3)
            up, forward = rot[:, 2], rot[:, 0]
            sense = float(np.cross(up, np.array([0.0, 0.0, 1.0])) @ forward)
            tilt = math.atan2(abs(sense), float(up[2]))  # angle from upright, 0..pi
            roll_rate = float(d.cvel[b][:3] @ forward)
            if self.time >= r.flip_until or (tilt < math.radians(25.0) and abs(roll_rate) < 0.5):
                r.flip_until = -1.0
                d.xfrc_applied[b, 3:] = 0.0
                continue
            sign = 1.0 if sense >= -1e-3 else -1.0
            dims = r.config.geometry.dimensions
            limit = FLIP_MARGIN * r.config.mass_kg * self.world.gravity_m_s2 * max(dims[1], dims[2]) / 2.0
            inertia = r.config.mass_kg * (dims[1] ** 2 + dims[2] ** 2) / 12.0
            k = limit / (math.pi / 2.0)
            damping = 2.0 * math.sqrt(k * inertia)
            torque = max(-limit, min(limit, sign * k * tilt - damping * roll_rate))
            d.xfrc_applied[b, 3:] = forward * torque

    def drive_aerial(self, uid: int, altitude: float | None, linear: float | None, lateral: float | None,
                     rotational: float | None, normalized: bool = False, light: bool | None = None) -> None:
        """``DRIVE {AltitudeVelocity} {LinearVelocity} {LateralVelocity} {RotationalVelocity}``
        (protocol.md 5.3d): m/s up, forward, right and rad/s clockwise; unsent ones keep
        their value; limited to the robot's maxima (percentages of them when Normalized);
        all zero: hover."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return
        if light is not None:
            r.light = bool(light)
        if r.config.gait is not None:  # a walking robot: the same keys set its gait
            g = r.config.gait
            for key, value, top in (("linear", linear, g.max_linear_m_s), ("lateral", lateral, g.max_lateral_m_s),
                                    ("rotational", rotational, g.max_yaw_rate_rad_s)):
                if value is not None and math.isfinite(value):
                    v = value * top / 100.0 if normalized else value
                    r.walk[key] = max(-top, min(top, v))
            return
        if r.config.drive != "aerial":
            return
        lim = r.config.aerial
        for key, value, top in (("altitude", altitude, lim.max_vertical_m_s), ("linear", linear, lim.max_linear_m_s),
                                ("lateral", lateral, lim.max_lateral_m_s),
                                ("rotational", rotational, lim.max_yaw_rate_rad_s)):
            if value is not None and math.isfinite(value):
                v = value * top / 100.0 if normalized else value
                r.fly[key] = max(-top, min(top, v))
        self._apply_ctrl(r)

    def _level_aerial(self) -> None:
        """Keep hovering robots level: a restoring torque towards upright (their roll and
        pitch rates are damped by their servos)."""
        d = self.data
        for r in self.robots.values():
            if not r.handle.rotor:
                continue
            b = r.handle.body_id
            up = d.xmat[b].reshape(3, 3)[:, 2]
            torque = np.cross(up, np.array([0.0, 0.0, 1.0])) * (AERIAL_LEVEL_STIFFNESS * r.config.mass_kg)
            d.xfrc_applied[b, 3:] = torque

    def _walk(self, r: SimRobot) -> None:
        """Set the leg joints of a walking robot for this instant of its gait.  Each foot
        stands for ``duty`` of a period, staying where it was put while the body moves
        over it (the commanded speed, side speed and turn rate carry the body), then swings
        forward, lifted, to where it will stand evenly about its hip at the current speed:
        a trot for four legs at duty 0.5 (diagonal legs together), a walk for two legs
        above it, with both feet down at the start and end of every step while the body
        sways over the foot that will stand alone.  Hip yaw joints turn the feet with the
        ground, ankles keep the soles flat.  The gait sets off (swaying first) and comes to
        rest over half a period each; the walking speed follows the command within half a
        period.  At rest its feet are back under its hips and its joints are left to joint
        commands."""
        g = r.config.gait
        if r.battery_empty:
            return
        cmd = (r.walk["linear"], r.walk["lateral"], r.walk["rotational"])
        moving = any(abs(c) > 1e-6 for c in cmd)
        if not moving and r.gait_amp <= 0.0:
            return  # standing: its joints are the client's (DRIVE Name groups, MULTIDRIVE)
        n = len(g.legs)
        dt = max(0.0, self.time - r.gait_last)
        r.gait_last = self.time
        if r.gait_amp <= 0.0:  # setting off: both feet down, the body between them
            r.gait_clock = (g.duty - 0.5) / 2.0 * g.period_s
            r.gait_amp, dt = 1e-9, 0.0
            r.gait_vel = (0.0, 0.0, 0.0)
            r.feet = [[0.0, 0.0, 0.0] for _ in range(n)]
            r.swing_from = [None] * n
        else:
            r.gait_clock += dt
        half = 0.5 * g.period_s
        tops = (g.max_linear_m_s, g.max_lateral_m_s, g.max_yaw_rate_rad_s)
        if r.gait_amp >= 1.0:  # under way: the walking speed follows the command
            r.gait_vel = tuple(cur + max(-top * dt / half, min(top * dt / half, c - cur))
                               for cur, c, top in zip(r.gait_vel, cmd if moving else (0.0, 0.0, 0.0), tops))
        at_rest = not any(r.gait_vel) and all(abs(x) < 1e-4 for f in r.feet for x in f)
        if moving:
            r.gait_amp = min(1.0, r.gait_amp + dt / half)
        elif at_rest:
            r.gait_amp = max(0.0, r.gait_amp - dt / half)
        # the feet: standing ones stay on the ground as the body moves, swinging ones go
        # to where they will stand
        stance_t = g.duty * g.period_s
        v, lat, w = r.gait_vel
        reach = 0.4 * (g.legs[0].upper_m + g.legs[0].lower_m)
        for i, leg in enumerate(g.legs):
            hip = r.config.link_origin(leg.hip_pitch)
            ground = (v - w * hip[1], lat + w * hip[0], w)  # how the ground moves past the hip
            p = (r.gait_clock / g.period_s + leg.phase) % 1.0
            f = r.feet[i]
            if p < g.duty or r.gait_amp < 1.0:
                if r.swing_from[i] is not None and r.gait_amp >= 1.0:  # it landed p x period ago
                    for j in range(3):
                        f[j] = ground[j] * (stance_t / 2.0 - p * g.period_s)
                else:
                    for j in range(3):
                        f[j] -= ground[j] * dt
                r.swing_from[i] = None
            else:
                if r.swing_from[i] is None:  # it stood until (p - duty) x period ago
                    stood = max(0.0, dt - (p - g.duty) * g.period_s)
                    r.swing_from[i] = [x - gx * stood for x, gx in zip(f, ground)]
                s_ = _smooth((p - g.duty) / (1.0 - g.duty))
                for j in range(3):
                    f[j] = r.swing_from[i][j] + (ground[j] * stance_t / 2.0 - r.swing_from[i][j]) * s_
            f[0] = max(-reach, min(reach, f[0]))
            f[1] = max(-reach, min(reach, f[1]))
            f[2] = max(-0.8, min(0.8, f[2]))
        if r.gait_amp <= 0.0:
            r.feet = [[0.0, 0.0, 0.0] for _ in range(n)]
        for name, value in self._leg_targets(r, r.gait_clock, r.gait_amp):
            r.joints[name] = (0, value)
            self._apply_joint(r, r.config.link(name))

    def _leg_targets(self, r: SimRobot, t: float, amp: float) -> list[tuple[str, float]]:
        """The angle of every leg joint of a walking robot at time ``t`` of its gait, its
        feet where ``r.feet`` puts them, its sway and steps scaled by ``amp`` (0: standing,
        every foot under its hip)."""
        g = r.config.gait
        # a swaying robot sways first and steps once it sways fully
        step_amp = max(0.0, 2.0 * amp - 1.0) if g.sway_m > 0.0 else amp
        phases = [(t / g.period_s + leg.phase) % 1.0 for leg in g.legs]
        # a biped's body sways sideways (right positive) as a sine of the gait, furthest
        # over the standing foot in the middle of the other foot's swing: the smooth sway
        # keeps the point where the feet carry the weight inside the standing sole
        shift = 0.0
        if amp > 0.0 and g.sway_m > 0.0:
            side = r.config.link_origin(g.legs[0].hip_pitch)[1]
            shift = -math.copysign(g.sway_m * min(1.0, 2.0 * amp), side) * math.cos(
                2.0 * math.pi * (phases[0] - (g.duty + 1.0) / 2.0))
        targets = []
        for i, (leg, p) in enumerate(zip(g.legs, phases)):
            fx, fy, yaw = r.feet[i] if amp > 0.0 and r.feet else (0.0, 0.0, 0.0)
            fy -= shift
            fz = g.stand_height_m
            if amp > 0.0 and p >= g.duty:  # swinging: lifted
                fz -= g.step_height_m * step_amp * math.sin(math.pi * (p - g.duty) / (1.0 - g.duty))
            if leg.hip_yaw is not None:
                fx, fy = math.cos(yaw) * fx + math.sin(yaw) * fy, -math.sin(yaw) * fx + math.cos(yaw) * fy
            pitch, roll, knee = leg_ik(fx, fy, fz, leg.upper_m, leg.lower_m, leg.knee_forward)
            targets += [(leg.hip_pitch, pitch), (leg.hip_roll, roll), (leg.knee, knee)]
            if leg.hip_yaw is not None:
                targets.append((leg.hip_yaw, yaw))
            if leg.ankle_pitch is not None:
                targets.append((leg.ankle_pitch, -(pitch + knee)))
            if leg.ankle_roll is not None:
                targets.append((leg.ankle_roll, -roll))
        return targets

    def _stand_up(self, r: SimRobot) -> None:
        """A walking robot is built standing: its leg joints start at their standing angles."""
        m, d = self.model, self.data
        for name, value in self._leg_targets(r, 0.0, 0.0):
            r.joints[name] = (0, value)
            d.qpos[r.handle.joint_qpos[name]] = value
            d.act[int(m.actuator_actadr[r.handle.actuator[name]])] = value
            self._apply_joint(r, r.config.link(name))
        mujoco.mj_forward(m, d)

    def _apply_rollers(self) -> None:
        """Roller tables carry their loads: every body touching a table's top (other than
        the robot) is pushed along the robot's X towards the rollers' speed relative to
        the robot, with up to grip x its weight."""
        m, d = self.model, self.data
        pushed: set[int] = set()
        tables = {t.geom: t for t in self._rollers}  # stopped rollers hold their load
        if tables:
            g = self.world.gravity_m_s2
            for i in range(d.ncon):
                c = d.contact[i]
                t = tables.get(c.geom1) or tables.get(c.geom2)
                if t is None:
                    continue
                other = c.geom2 if t.geom == c.geom1 else c.geom1
                b = int(m.geom_bodyid[other])
                if b in pushed or m.body_rootid[b] == t.handle.body_id or m.body_weldid[b] == 0:
                    continue
                pushed.add(b)
                rot = d.xmat[t.handle.body_id].reshape(3, 3)
                axis = rot[:, 0]
                vel = np.empty(6)
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
                robot_vel = np.empty(6)
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, t.handle.body_id, robot_vel, 0)
                slip = t.speed - float(axis @ (vel[3:] - robot_vel[3:]))
                mass = float(m.body_subtreemass[b])
                push = max(-1.0, min(1.0, slip / 0.05)) * t.config.grip * mass * g
                d.xfrc_applied[b, :3] = axis * push
        for b in self._roller_pushed - pushed:
            d.xfrc_applied[b, :3] = 0.0
        self._roller_pushed = pushed

    def _external_forces(self) -> bool:
        return self._aerial or bool(self.world.water and self.robots) or bool(self._rollers) or \
            any(r.flip_until >= 0 for r in self.robots.values())

    def drive_nautical(self, uid: int, propeller: float | None, rudder: float | None, stern_plane: float | None,
                       normalized: bool = False, light: bool | None = None) -> None:
        """``DRIVE {Propeller} {Rudder} {SternPlane}`` (protocol.md 5.3e): the propeller as a
        fraction of full thrust, -1..1 (percent when Normalized); rudder and stern planes
        in radians (positive: turn right, rise), within the vessel's limits.  Unsent values
        are kept."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return
        if light is not None:
            r.light = bool(light)
        n = r.config.nautical
        if n is None:
            return
        for key, value, top, scale in (("propeller", propeller, 1.0, 0.01),
                                       ("rudder", rudder, n.max_rudder_rad, n.max_rudder_rad / 100.0),
                                       ("stern_plane", stern_plane, n.max_stern_plane_rad, n.max_stern_plane_rad / 100.0)):
            if value is not None and math.isfinite(value):
                v = value * scale if normalized else value
                r.sail[key] = max(-top, min(top, v))

    def _apply_water(self) -> None:
        """Buoyancy, drag and the vessel's own propulsion for every robot in water;
        robots not built for water lose their battery there (as in UT2004)."""
        d = self.data
        g = self.world.gravity_m_s2
        for r in self.robots.values():
            b = r.handle.body_id
            loc = frames.from_mj_vec(d.xipos[b])  # centre of mass, USARSim frame
            depth = max((wv.depth_of(loc), wv) for wv in self.world.water)
            height = r.config.geometry.dimensions[2]
            frac = min(max((depth[0] + height / 2.0) / height, 0.0), 1.0)
            was = r.in_water
            r.in_water = frac > 0.0
            if not r.in_water:
                if was:
                    d.xfrc_applied[b] = 0.0
                continue
            n = r.config.nautical
            if n is None:
                if depth[0] > 0.0 and not r.battery_empty:
                    r.battery_used_s = r.config.battery_s
                    log.info("robot '%s' (id %d) went under water: its battery is gone", r.name, r.uid)
                continue
            rot = d.xmat[b].reshape(3, 3)
            vel = np.empty(6)
            mujoco.mj_objectVelocity(self.model, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)  # world frame
            ang, lin = vel[:3], vel[3:]
            force = np.array([0.0, 0.0, depth[1].density_kg_m3 * g * n.volume_m3 * frac])
            # a hull slips through the water lengthwise and hardly at all sideways or
            # up and down (its fins): drag ten times larger across than along it
            v_body = rot.T @ lin
            force -= rot @ (v_body * np.array([1.0, HULL_CROSS_DRAG, HULL_CROSS_DRAG])) * (n.drag_n_per_m_s * frac)
            torque = -n.angular_drag * ang * frac
            if not r.battery_empty:
                forward = rot[:, 0]
                speed = float(forward @ lin)
                force += forward * (r.sail["propeller"] * n.max_thrust_n * frac)
                # rudder: turn right = clockwise seen from above = about -z (MuJoCo);
                # stern planes: rise = nose up = about the body's right axis (-y, +y is its left)
                torque += np.array([0.0, 0.0, -1.0]) * (n.rudder_gain * r.sail["rudder"] * speed)
                torque += rot[:, 1] * (-n.stern_plane_gain * r.sail["stern_plane"] * speed)
            # the hull rights itself (its weight hangs below its buoyancy): firmly in roll,
            # gently in pitch, which the stern planes overcome
            up = rot[:, 2]
            tilt = np.cross(up, np.array([0.0, 0.0, 1.0]))
            righting = AERIAL_LEVEL_STIFFNESS * r.config.mass_kg
            torque += rot[:, 0] * (float(tilt @ rot[:, 0]) * righting)
            torque += rot[:, 1] * (float(tilt @ rot[:, 1]) * righting * HULL_PITCH_RIGHTING)
            d.xfrc_applied[b, :3] = force
            d.xfrc_applied[b, 3:] = torque

    def drive_ackermann(self, uid: int, speed: float | None, front: float | None, rear: float | None,
                        normalized: bool = False, light: bool | None = None) -> None:
        """``DRIVE {Speed} {FrontSteer} {RearSteer}`` (protocol.md 5.3b): what is not sent keeps
        its value; speeds within MaxSpeed, angles within MaxFrontSteer/MaxRearSteer."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return
        if light is not None:
            r.light = bool(light)
        if r.config.drive != "ackermann":
            return
        c = r.config
        vmax, fmax, rmax = c.max_speed_rad_s, c.max_front_steer_rad, c.max_rear_steer_rad
        if speed is not None and math.isfinite(speed):
            r.speed = max(-vmax, min(vmax, speed * (vmax / 100.0 if normalized else 1.0)))
        if front is not None and math.isfinite(front):
            r.front_steer = max(-fmax, min(fmax, front * (fmax / 100.0 if normalized else 1.0)))
        if rear is not None and math.isfinite(rear):
            r.rear_steer = max(-rmax, min(rmax, rear * (rmax / 100.0 if normalized else 1.0)))
        r.wheel_speed.clear()
        self._apply_ctrl(r)

    def drive_wheels(self, uid: int, wheels: list[tuple[int, float | None, float | None]],
                     normalized: bool = False, light: bool | None = None) -> None:
        """Holonomic ``DRIVE {WheelNumber n} {WheelSpeed v} {WheelSteer a} ...`` (protocol.md 5.3c):
        each numbered steered wheel's spin speed (rad/s) and angle (rad, 0 straight ahead)."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty:
            return
        if light is not None:
            r.light = bool(light)
        if r.config.drive != "holonomic":
            return
        vmax = r.config.max_speed_rad_s
        by_number = {w.number: w for w in r.config.wheels if w.number >= 0}
        for number, speed, steer in wheels:
            w = by_number.get(number)
            if w is None:
                continue
            if speed is not None and math.isfinite(speed) and w.driven:
                r.wheel_speed[w.name] = max(-vmax, min(vmax, speed * (vmax / 100.0 if normalized else 1.0)))
            if steer is not None and math.isfinite(steer) and w.steer == "free":
                r.wheel_steer[w.name] = math.remainder(steer, 2 * math.pi)
        self._apply_ctrl(r)

    # Joints (links and wheels) --------------------------------------------------------
    ORDERS = (0, 1, 2, 3, 10, 11, 12)

    def drive_joint(self, uid: int, name: str, value: float, order: int = 0) -> bool:
        """A joint command (protocol.md 5.3f, 5.6): order 0 angle (m for prismatic), 1 speed,
        2 torque, 3 brake, 10/11/12 the same relative to the current value.  Targets are
        limited to the joint's range, speeds to MaxSpeed, torques to MaxTorque.  False when
        the robot has no such joint or the order is unknown."""
        r = self.robots.get(uid)
        if r is None or r.battery_empty or not math.isfinite(value) or order not in self.ORDERS:
            return False
        ln = r.config.link(name) or next((x for x in r.config.links if x.name.lower() == name.lower()), None)
        if ln is None:
            w = next((x for x in r.config.wheels if x.name.lower() == name.lower() and x.driven), None)
            if w is None:
                return False
            vmax = r.config.max_speed_rad_s
            if order in (1, 11):
                base = float(self.data.ctrl[r.handle.actuator[w.name]]) if order == 11 else 0.0
                r.wheel_speed[w.name] = max(-vmax, min(vmax, base + value))
            elif order == 3:
                r.wheel_speed[w.name] = 0.0
            else:
                return False  # wheel angle and torque orders are not modelled
            self._apply_ctrl(r)
            return True
        h = r.handle
        q = float(self.data.qpos[h.joint_qpos[ln.name]])
        qd = float(self.data.qvel[h.joint_qvel[ln.name]])
        cur_order, cur_value = r.joints.get(ln.name, (0, 0.0))
        if order == 10:
            order, value = 0, q + value
        elif order == 11:
            order, value = 1, qd + value
        elif order == 12:
            order, value = 2, (cur_value if cur_order == 2 else 0.0) + value
        elif order == 3:
            order, value = 1, 0.0
        if order == 0 and ln.limited:
            value = min(max(value, ln.min_range), ln.max_range)
        elif order == 1:
            value = min(max(value, -ln.max_speed), ln.max_speed)
        elif order == 2:
            value = min(max(value, -ln.max_torque), ln.max_torque)
        r.joints[ln.name] = (order, value)
        self._apply_joint(r, ln)
        return True

    def _apply_joint(self, r: SimRobot, ln) -> None:
        """Set a link's drive for its current order: for an angle, the set point runs at
        MaxSpeed towards the target and stops there; for a speed, it runs at that speed
        (within the joint's range); for a torque, the servo is replaced by that torque.
        The model's per-actuator values are set again after every rebuild."""
        a = r.handle.actuator[ln.name]
        m, d = self.model, self.data
        act = int(m.actuator_actadr[a])
        q = float(d.qpos[r.handle.joint_qpos[ln.name]])
        order, value = r.joints.get(ln.name, (0, None))
        if r.battery_empty:
            order, value = 2, 0.0
        kp, kv = builder.joint_servo_gains(ln)
        lo, hi = builder.joint_travel(ln)
        if order == 2:
            m.actuator_gainprm[a, 0] = 1.0
            m.actuator_biasprm[a, :3] = (0.0, 0.0, 0.0)
            m.actuator_actrange[a] = (-ln.max_torque, ln.max_torque)
            d.act[act] = value
            d.ctrl[a] = 0.0
            return
        if float(m.actuator_gainprm[a, 0]) != kp:  # back from a torque order: start from here
            d.act[act] = q
        m.actuator_gainprm[a, 0] = kp
        m.actuator_biasprm[a, :3] = (0.0, -kp, -kv)
        if order == 1:
            m.actuator_actrange[a] = (lo, hi)
            d.ctrl[a] = value
            return
        if value is None:  # never commanded: hold where it was built (0)
            value = 0.0
        cur = float(d.act[act])
        m.actuator_actrange[a] = (min(cur, value), max(cur, value))
        d.ctrl[a] = math.copysign(ln.max_speed, value - cur) if value != cur else 0.0

    def package_state(self, r: SimRobot, pkg) -> "PackageState":
        d, h = self.data, r.handle
        return PackageState(pkg.name, tuple(
            (i + 1, float(d.qpos[h.joint_qpos[n]]), float(d.actuator_force[h.actuator[n]]))
            for i, n in enumerate(pkg.links)))

    def _apply_ctrl(self, r: SimRobot) -> None:
        if r.handle.light >= 0:
            self.model.light_active[r.handle.light] = bool(r.light) and not r.battery_empty
        ctrl = self.data.ctrl
        if r.handle.rotor:
            f = r.fly if not r.battery_empty else dict.fromkeys(r.fly, 0.0)
            rot = r.handle.rotor
            # MuJoCo's site axes: x forward, y left, z up; USARSim's lateral is to the right and
            # its yaw clockwise seen from above
            ctrl[rot["linear"]] = f["linear"]
            ctrl[rot["lateral"]] = -f["lateral"]
            ctrl[rot["vertical"]] = f["altitude"]
            ctrl[rot["yaw"]] = -f["rotational"]
            ctrl[rot["roll"]] = ctrl[rot["pitch"]] = 0.0
        drive = r.config.drive
        for w in r.config.wheels:
            if w.steer != "none":
                ctrl[r.handle.steer_actuator[w.name]] = self._steer_angle(r, w)
            if not w.driven:
                continue
            a = r.handle.actuator[w.name]
            if r.battery_empty:
                ctrl[a] = 0.0
            elif w.name in r.wheel_speed:
                ctrl[a] = r.wheel_speed[w.name]
            elif drive == "ackermann":
                ctrl[a] = r.speed
            elif drive == "holonomic":
                ctrl[a] = 0.0
            else:
                ctrl[a] = r.left if w.side == "left" else r.right

    def _steer_angle(self, r: SimRobot, w) -> float:
        """A steered wheel's angle: holonomic wheels their own; Ackermann axles with the
        Ackermann correction (each wheel on a circle about the same centre) when only
        one axle steers, else both wheels of an axle alike."""
        if w.steer == "free":
            return r.wheel_steer.get(w.name, 0.0)
        delta = r.front_steer if w.steer == "front" else r.rear_steer
        other = r.rear_steer if w.steer == "front" else r.front_steer
        if delta == 0.0 or other != 0.0:
            return delta
        fixed = [x.position[0] for x in r.config.wheels if x.steer == "none"]
        base = w.position[0] - (sum(fixed) / len(fixed) if fixed else 0.0)
        if abs(base) < 1e-6:
            return delta
        t = math.tan(delta)
        y = w.position[1]
        if base > 0:  # a front axle: the turning centre is on the rear axle's line
            return math.atan2(base * t, base - y * t)
        return math.atan2(-base * t, -base + y * t)  # a rear axle: on the front axle's line

    def operate(self, uid: int, item_type: str | None, name: str | None, opcode: str | None,
                params: str | None) -> CommandResult | None:
        """``SET {Type} {Name} {Opcode} {Params}`` on a mounted item; None when the robot is gone."""
        r = self.robots.get(uid)
        if r is None:
            return None
        t = item_type or ""
        if r.battery_empty:
            return None
        for s in r.sensors:
            if s.TYPE.lower() == t.lower() and (not name or s.name.lower() == name.lower()):
                view = dataclasses.replace(self.view(), drive_joint=lambda n, v, o: self.drive_joint(uid, n, v, o))
                status = s.operate(view, opcode or "", params) if opcode else None
                state = getattr(s, "effecter_state", None)
                if status is not None and state is not None:
                    self.outbox.append(Output(uid, self.time, EffecterState(s.TYPE, s.name, state()),
                                              f"EFF:{s.name}", periodic=False))
                if s.LIVE_CONF:
                    self.live_conf[(uid, s.TYPE, s.name)] = s.conf_fields()
                if status is None:
                    return CommandResult(s.TYPE, s.name, "Failed")
                extra: tuple = ()
                if isinstance(status, tuple):
                    status, extra = status
                elif not isinstance(status, str):
                    return status  # an item-specific result (e.g. a camera zoom)
                if status == "OK" and (opcode or "").upper() == "SCAN" and s.PERIODIC:
                    self._emit(r, s.TYPE, [s], f"SEN:{s.TYPE}:{s.name}")
                return CommandResult(s.TYPE, s.name, status, tuple(extra))
        return CommandResult(t, name or "", "Failed")

    # Stepping -----------------------------------------------------------------
    def advance(self, seconds: float) -> None:
        """Run whole physics steps covering ``seconds`` of simulated time, measuring
        every sensor that falls due (including at the final instant)."""
        target = self.step_count + max(0, int(round(seconds / self.dt)))
        while True:
            self._fire_due()
            if self.step_count >= target:
                break
            n = target - self.step_count
            if self._heap:
                due = self._heap[0][0]
                n = max(1, min(n, int(math.ceil(due / self.dt - EPS)) - self.step_count))
            if self._external_forces():  # forces we set by hand are renewed often enough
                n = min(n, EXTERNAL_FORCE_STEPS)
            if self._legged:  # gaits are updated every GAIT_STEPS
                n = min(n, GAIT_STEPS)
            self._step(n)
        for fn in self.after_advance:
            fn(self)

    def _step(self, n: int) -> None:
        """``n`` physics steps in one call.  If a robot blows up on the way, the
        stretch is run again one step at a time from its start, and each robot is
        caught at the step where it goes wrong, before it can disturb the others."""
        m, d = self.model, self.data
        if self.entities.has_motion:
            self.entities.update(d, self.time)
        if any(r.flip_until >= 0 for r in self.robots.values()):
            self._apply_flips()
        if self._aerial:
            self._level_aerial()
        if self.world.water:
            self._apply_water()
        if self._rollers:
            self._apply_rollers()
        if self._legged:
            for r in self.robots.values():
                if r.config.gait is not None:
                    self._walk(r)
        if self._snapshot is None or self._snapshot.size != mujoco.mj_stateSize(m, STATE):
            self._snapshot = np.empty(mujoco.mj_stateSize(m, STATE))
        mujoco.mj_getState(m, d, self._snapshot, STATE)
        mujoco.mj_step(m, d, n)
        if self._healthy():
            self._good_qpos = d.qpos.copy()
        else:
            mujoco.mj_setState(m, d, self._snapshot, STATE)
            self._repair()
            for _ in range(n):
                mujoco.mj_step(m, d)
                if self._healthy():
                    self._good_qpos = d.qpos.copy()
                else:
                    self._repair()
        self.step_count += n
        self.physics_steps += n
        self._check_batteries(n * self.dt)

    def _healthy(self) -> bool:
        """No velocity beyond :data:`MAX_SANE_VELOCITY` and nothing non-finite (a NaN
        or an infinity makes the max and the sum non-finite)."""
        d = self.data
        if d.qvel.size == 0:
            return True
        return float(np.abs(d.qvel).max()) < self._sane and math.isfinite(float(d.qpos.sum()))

    def _repair(self) -> None:
        """Put every robot whose state is not finite, or whose joints move faster than
        anything real (:data:`MAX_SANE_VELOCITY`), back where it last was healthy, at
        rest; the other robots are not touched."""
        d = self.data
        good = self._good_qpos if self._good_qpos is not None and len(self._good_qpos) == len(d.qpos) else None
        for r in self.robots.values():
            h = r.handle
            nq, nv = 7 + len(h.joint_qpos), 6 + len(h.joint_qvel)
            qs, vs = slice(h.root_qpos, h.root_qpos + nq), slice(h.root_qvel, h.root_qvel + nv)
            v = d.qvel[vs]
            if np.isfinite(v).all() and np.isfinite(d.qpos[qs]).all() and float(np.abs(v).max()) < sane_velocity(r.config):
                continue
            self.resets += 1
            r.resets += 1
            log.error("robot '%s' (id %d) became physically unstable at t=%.3f; it is put back where it last "
                      "was stable, at rest", r.name, r.uid, d.time)
            if good is not None and np.isfinite(good[qs]).all():
                d.qpos[qs] = good[qs]
            else:  # no healthy pose known: its spawn pose
                q = d.qpos[qs]
                q[:7] = r.spawn_qpos
                q[7:] = 0.0
            d.qvel[vs] = 0.0
            d.qacc_warmstart[vs] = 0.0
        # whatever else is not finite (not part of a robot) is cleared too
        for arr in (d.qpos, d.qvel, d.qacc_warmstart, d.act):
            bad = ~np.isfinite(arr)
            if bad.any():
                arr[bad] = 0.0
        mujoco.mj_forward(self.model, d)

    def _check_batteries(self, seconds: float = 0.0) -> None:
        """Drain every battery by ``seconds`` of use: one second per second at rest, up to
        twice as fast at the rated mechanical power of all the robot's motors (the
        battery ran down "faster under load" in UT2004, protocol.md 6.2)."""
        now = self.time
        if seconds > 0 and self.robots:
            d = self.data
            owners = self._actuator_owner
            if owners is not None and len(owners) == self.model.nu and self.model.nu:
                power = np.bincount(owners, weights=np.abs(d.actuator_force * d.actuator_velocity),
                                    minlength=self._owner_count)
            else:
                power = None
            for r in self.robots.values():
                load = float(power[r.owner_index]) / r.rated_power_w if power is not None else 0.0
                r.battery_used_s += seconds * (1.0 + min(load, 1.0) * BATTERY_LOAD_FACTOR)
        for r in self.robots.values():
            if not r.battery_empty and r.battery_left(now) <= 0.0:
                r.battery_empty = True
                r.left = r.right = 0.0
                r.wheel_speed.clear()
                self._apply_ctrl(r)
                for ln in r.config.links:
                    self._apply_joint(r, ln)
                log.info("robot '%s' (id %d): battery empty at t=%.3f", r.name, r.uid, now)

    def _fire_due(self) -> None:
        now = self.time
        heap = self._heap
        view = None
        while heap and heap[0][0] <= now + EPS:
            _, _, u = heapq.heappop(heap)
            r = u.robot
            if r.removed:
                continue
            # next due: the first multiple of the interval after now
            u.k += 1
            while u.due <= now + EPS:
                u.k += 1
            heapq.heappush(heap, (u.due, next(self._seq), u))
            if u.status:
                self.outbox.append(Output(r.uid, now, self.status_of(r), "STA"))
            elif u.package is not None:
                if not r.battery_empty:
                    self.outbox.append(Output(r.uid, now, self.package_state(r, u.package), u.key))
            elif not r.battery_empty:
                if view is None:
                    view = self.view()
                self._emit(r, u.sensors[0].TYPE, u.sensors, u.key, view)

    def _emit(self, r: SimRobot, stype: str, sensors: list[Sensor], key: str, view: WorldView | None = None) -> None:
        view = view or self.view()
        first = sensors[0]
        if first.PACKED:
            cls = type(first)
            value = cls.combine(cls.measure_group(sensors, view))
        else:
            value = first.measure(view)
        if value is None:  # nothing to report this tick (e.g. a sensor that accumulates scans)
            return
        t = view.time if first.config.with_time_stamp else None
        self.outbox.append(Output(r.uid, t, value, key))

    def status_of(self, r: SimRobot) -> RobotStatus:
        left = r.battery_left(self.time)
        front = rear = 0.0
        if r.config.drive == "ackermann":  # the current angles of the axles (mean of their wheels)
            q = self.data.qpos
            fa = [float(q[r.handle.steer_qpos[w.name]]) for w in r.config.wheels if w.steer == "front"]
            ra = [float(q[r.handle.steer_qpos[w.name]]) for w in r.config.wheels if w.steer == "rear"]
            front = sum(fa) / len(fa) if fa else 0.0
            rear = sum(ra) / len(ra) if ra else 0.0
        joints = tuple((n, float(self.data.qpos[r.handle.joint_qpos[n]])) for n in r.config.status_joints)
        return RobotStatus(vehicle_type=r.config.vehicle_type, battery_s=int(math.ceil(left - 1e-6)),
                           front_steer=front, rear_steer=rear, joints=joints, light_toggle=r.light,
                           light_intensity=100 if r.light else 0, view=self.view_index(r.uid))

    # Cameras and the MultiView (protocol.md 10, 11) -----------------------------------
    def cameras_of(self, r: SimRobot) -> list[Sensor]:
        return [s for s in r.sensors if s.item.item_type in builder.CAMERA_TYPES]

    @property
    def multiview_cameras(self) -> int:
        return self._multiview_cameras

    @multiview_cameras.setter
    def multiview_cameras(self, n: int) -> None:
        self._multiview_cameras = max(1, int(n))
        self._multiview = None

    def multiview(self) -> list[tuple[int, str]]:
        """The robot cameras the MultiView shows, tile by tile: the first camera chosen by
        each robot's viewports (else its first camera), robots in the order they were
        spawned, at most ``multiview_cameras`` of them."""
        if self._multiview is not None and self._multiview_robots == self.robots.keys():
            return self._multiview
        out = []
        for uid in sorted(self.robots):
            r = self.robots[uid]
            cams = [s.name for s in self.cameras_of(r)]
            shown = [v for v in r.viewports if v.lower() in (c.lower() for c in cams)]
            if shown or cams:
                out.append((uid, (shown or cams)[0]))
            if len(out) >= self.multiview_cameras:
                break
        self._multiview, self._multiview_robots = out, set(self.robots)
        return out

    def view_index(self, uid: int) -> int:
        """A robot's tile in the MultiView (STA ``View``), -1 when it is not shown."""
        for i, (u, _) in enumerate(self.multiview()):
            if u == uid:
                return i
        return -1

    def set_viewports(self, uid: int, names: list[str | None]) -> list[tuple[str, str]]:
        """SET {Type Viewports}: viewport n shows the robot's camera ``names[n]`` (None or
        ``Disable``: off).  Returns (what viewport n shows: the camera, ``Disabled`` or
        ``None`` for an unknown camera; ``OK``/``Failed``) for each."""
        r = self.robots.get(uid)
        cams = {s.name.lower(): s.name for s in self.cameras_of(r)} if r is not None else {}
        shown, result = [], []
        for name in names:
            if name is None or name.lower() in ("disable", "disabled"):
                result.append(("Disabled", "OK"))
            elif name.lower() in cams:
                shown.append(cams[name.lower()])
                result.append((cams[name.lower()], "OK"))
            else:
                result.append(("None", "Failed"))
        if r is not None:
            r.viewports = tuple(shown)
            self._multiview = None
        return result

    def render_snapshot(self, reuse=None):
        """A copy of the state for the render thread (taken between steps): ``reuse``, the
        previous snapshot, is refilled when the model is still the same."""
        from usarsim.sim.render import CameraState, Snapshot

        m = self.model
        if reuse is not None and reuse.model is m:
            snap = reuse
            snap.cameras = {}
        else:
            snap = Snapshot(model=m, data=mujoco.MjData(m), time=0.0)
        mujoco.mj_copyData(snap.data, m, self.data)
        snap.time = self.time
        snap.robots = {r.name.lower(): r.uid for r in self.robots.values()}
        snap.multiview = list(self.multiview())
        for r in self.robots.values():
            for cam in self.cameras_of(r):
                cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, builder.camera_name(r.prefix, cam.name))
                if cid >= 0:
                    snap.cameras[(r.uid, cam.name.lower())] = CameraState(
                        cam_id=cid, fov_rad=float(getattr(cam, "fov_rad", cam.config.def_fov_rad)),
                        omni=cam.item.item_type != "Camera")
            # the chase view behind and above the robot (builder.CHASE_CAMERA)
            cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, builder.chase_camera_name(r.prefix))
            if cid >= 0:
                snap.cameras.setdefault((r.uid, builder.CHASE_CAMERA.lower()),
                                        CameraState(cam_id=cid, fov_rad=builder.CHASE_FOV_RAD, omni=False))
        return snap

    def truth(self, class_name: str | None = None, name: str | None = None) -> list[tuple]:
        """Everything the ground-truth service knows, now: (name, class, time, location,
        rotation) of every robot (its class and INIT name), victim (``Victim``), RFID tag
        (``RFIDTag``, named by its id), false alarm (``FalseAlarm``) and movable object
        (``MovableObject``); world frame, rotations in [0, 2 pi).  Filtered by class and
        name (any case) when given."""
        now = self.time
        m, d = self.model, self.data
        rows = []
        for r in self.robots.values():
            loc, rot = r.handle.location(d), r.handle.orientation(d)
            rows.append((r.name, r.config.class_name, loc, rot))
        for v in self.world.victims:
            b = m.body(f"victim/{v.name}").id
            rows.append((v.name, "Victim", frames.from_mj_vec(d.xpos[b]), frames.mj_mat_to_usar_euler(d.xmat[b])))
        for tag in self.entities.tags.values():
            rows.append((str(tag.tag_id), "RFIDTag", tuple(tag.location), (0.0, 0.0, 0.0)))
        for a in self.world.false_alarms:
            rows.append((a.name, "FalseAlarm", tuple(a.center), tuple(a.rotation)))
        for o in self.world.objects:
            if o.mass_kg > 0:
                b = m.body(f"movable/{o.name}").id
                rows.append((o.name, "MovableObject", frames.from_mj_vec(d.xpos[b]),
                             frames.mj_mat_to_usar_euler(d.xmat[b])))
        out = []
        for n, c, loc, rot in rows:
            if (class_name is None or c.lower() == class_name.lower()) and (name is None or n.lower() == name.lower()):
                out.append((n, c, now, tuple(float(x) for x in loc), tuple(frames.wrap_2pi(float(a)) for a in rot)))
        return out

    def take_outputs(self) -> list[Output]:
        out, self.outbox = self.outbox, []
        return out

    def pose_of(self, uid: int) -> tuple[tuple[float, float, float], tuple[float, float, float]] | None:
        r = self.robots.get(uid)
        if r is None:
            return None
        return r.handle.location(self.data), r.handle.orientation(self.data)
