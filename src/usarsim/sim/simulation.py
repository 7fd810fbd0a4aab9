"""The authoritative simulation: one MuJoCo world, a fixed physics step on a
simulated clock, robots spawned and removed while others run, reports (STA, SEN,
MISSTA) at their own periods of simulated time.

The simulation itself only spawns, removes, rebuilds, advances and schedules; what a
robot does is its drive model's (:mod:`usarsim.robots`), its joint servos'
(:mod:`usarsim.sim.joints`) and its battery's (:mod:`usarsim.sim.battery`); forces set by
hand are world systems (:mod:`usarsim.sim.systems`); the blow-up guard, the cameras and
the ground truth have modules of their own.

This object is used from one thread only (the simulation thread, see
:mod:`usarsim.sim.runner`); readings leave it as :class:`Output` records.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import mujoco
import numpy as np

from usarsim.config.robot import RobotConfig
from usarsim.config.world import WorldConfig
from usarsim.controls import DriveCommand, JointOrder
from usarsim.errors import ConfigError, SimulationError
from usarsim.readings import CommandResult, ItemParams, Refusal, ZoomResult
from usarsim.sim import builder, frames, joints, robotspec, systems, truth
from usarsim.sim.battery import Batteries
from usarsim.sim.cameras import Cameras
from usarsim.sim.constants import GROUND_GROUPS
from usarsim.sim.entities import Entities
from usarsim.sim.health import BlowUpGuard
from usarsim.sim.measuring import Due, Measurer, OrderedOutbox, measure_all, measure_report
from usarsim.sim.outputs import Output
from usarsim.sim.plugins import PluginSet, builtin_plugins
from usarsim.sim.raycaster import RayCaster
from usarsim.sim.reports import EPS, ReportSchedule
from usarsim.sim.robot import SimRobot, describe_items
from usarsim.sim.settings import PHYSICS_THREADS_LIMIT, SimSettings
from usarsim.sim.status import Standing
from usarsim.sim.systems.righting import start_righting
from usarsim.sim.view import RobotHandle, WorldView

if TYPE_CHECKING:
    from usarsim.sensors.base import Sensor

log = logging.getLogger("usarsim.sim")

# MuJoCo's thread pool (mju_threadpool) solves the constraint islands of robots that do not
# touch, and parts of collision detection, on several cores; the results are the same bit for
# bit.  Alone, on the 2-core machine, it takes bare mj_step from 3.6 to 4.9 times real time
# with 64 P2ATs and from 0.74 to 1.09 with 256 (and costs more than it saves with 16: 20.8 ->
# 19.5).  Beside the measuring thread (usarsim.sim.measuring) and the event loop, which want
# a core too, the bench (2 runs each, alternately) lost 5-15 % with it with 64 robots and 30 %
# with 16, gained nothing with 128 and 7-15 % with 256 while the robots started packed in one
# corner.  Spread over the floor, with 256 robots the pool on both cores lost 4-13 % (four pairs
# alternately, 2026-11-25: 0.92-1.03 times real time with it, 1.04-1.09 without): the
# measuring thread and the server's Python need the second core as much.  So it gets every
# core but one from PHYSICS_POOL_MIN_ROBOTS robots on (none on two cores).
# SimSettings.physics_threads (serve --physics-threads) sets its threads: 0 or 1 for none, None
# ("auto", the default) for that rule, at most PHYSICS_THREADS_MAX.
PHYSICS_POOL_MIN_ROBOTS = 32
PHYSICS_THREADS_MAX = 8


def physics_threads(robots: int, asked: int | None = None) -> int:
    """Threads of MuJoCo's pool for a world of ``robots`` robots (0: no pool); ``asked``: the
    number :class:`SimSettings` gives (None: the rule above)."""
    if asked is not None:
        return min(asked, PHYSICS_THREADS_LIMIT) if asked > 1 else 0
    if robots < PHYSICS_POOL_MIN_ROBOTS:
        return 0
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    threads = min(cores - 1, PHYSICS_THREADS_MAX)  # a core for the measuring thread and the server
    return threads if threads > 1 else 0


__all__ = ["Output", "SimRobot", "Simulation", "describe_items"]


class Simulation:
    """One world in MuJoCo on a simulated clock of fixed physics steps (the world's timestep, 4 ms by default): the
    robots spawned in it, their reports scheduled at their own periods, and the entities, ray caster, batteries and
    cameras they use; used from the simulation thread only."""

    def __init__(
        self,
        world: WorldConfig,
        *,
        seed: int = 0,
        settings: SimSettings | None = None,
        plugins: PluginSet | None = None,
    ):
        self.world = world
        self.seed = seed
        # the drives and items robots are built from (the built-in ones unless the composition root says)
        self.plugins = plugins or builtin_plugins()
        self.settings = settings or SimSettings()
        self.dt = world.timestep_s
        self.spec = builder.world_spec(world, textures=self.settings.textures, antialias=self.settings.antialias)
        self.model = self.spec.compile()
        self.data = mujoco.MjData(self.model)
        self.threads = 0  # MuJoCo's thread pool: none until the robots are many (physics_threads)
        mujoco.mj_forward(self.model, self.data)
        self.step_count = 0
        self.physics_steps = 0
        self.robots: dict[int, SimRobot] = {}
        # what the simulation outputs, in order; readings being taken on the measuring thread
        # hold back what comes after them (usarsim.sim.measuring)
        self.outbox = OrderedOutbox()
        self.measurer: Measurer | None = None
        self.entities = Entities(world)
        self.entities.resolve(self.model)
        self.caster = RayCaster(self.model, self.data, see_through=self.entities.see_through)
        self.reports = ReportSchedule(self.settings.report_phases, self.dt)
        self.guard = BlowUpGuard()
        self.batteries = Batteries()
        self.cameras = Cameras(self)
        # CONF fields that changed at run time (a camera's zoom), by (robot id, type, name);
        # read by the server thread (plain dict reads and replacements are atomic)
        self.live_conf: dict[tuple[int, str, str], tuple] = {}
        self.systems = systems.collect(self)
        # called with the simulation at the end of every ``advance`` (on the simulation
        # thread, at the simulated instant the clock reached): the radio links
        self._after_advance: list[Callable[[Simulation], None]] = []
        # [next simulated time, period, fn]: called whenever the clock reaches the next multiple
        # of their period, within an advance too (frames for a recording, :meth:`every`)
        self._samplers: list[list] = []

    # Clock -------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.step_count * self.dt

    @property
    def resets(self) -> int:
        """Robots put back by the blow-up guard so far."""
        return self.guard.resets

    def view(self) -> WorldView:
        return WorldView(self.model, self.data, self.time, self.caster, self.world, self.entities)

    def on_advance(self, fn: Callable[[Simulation], None]) -> None:
        """Call ``fn(sim)`` at the end of every :meth:`advance` (before the simulation starts)."""
        self._after_advance.append(fn)

    def every(self, period_s: float, fn: Callable[[Simulation], None]) -> None:
        """Call ``fn(sim)`` each time the simulated clock reaches a multiple of ``period_s``
        (the physics steps are split there, as for a sensor's report), from the next one on."""
        period = max(self.dt, float(period_s))
        k = math.floor(self.time / period + EPS) + 1
        self._samplers.append([k * period, period, fn])

    def _sample_due(self) -> None:
        now = self.time
        for s in self._samplers:
            if s[0] <= now + EPS * self.dt:
                s[2](self)
                s[0] = (math.floor(now / s[1] + EPS) + 1) * s[1]

    # Model changes ------------------------------------------------------------
    def _rebuild(self) -> None:
        self.settle()  # the sensors are configured anew for the new model
        self.model, self.data = self.spec.recompile(self.model, self.data)
        threads = physics_threads(len(self.robots), self.settings.physics_threads)
        if threads != self.threads:
            log.info("physics on %s", f"{threads} threads (MuJoCo's thread pool)" if threads else "one thread")
        self.threads = threads
        if threads:
            mujoco.mju_threadpool(self.data, threads)
        self.entities.resolve(self.model)
        self.entities.update(self.data, self.time)
        mujoco.mj_forward(self.model, self.data)
        self.caster = RayCaster(self.model, self.data, see_through=self.entities.see_through)
        self.guard.mark_good(self.data)
        view = self.view()
        for r in self.robots.values():
            self._configure(r, view)
        robots = list(self.robots.values())
        self.batteries.index(self.model, robots)
        self.guard.index(robots)
        self.systems = systems.collect(self, self.systems)

    def _configure(self, r: SimRobot, view: WorldView) -> None:
        r.handle.resolve(self.model, r.config.wheels, r.config.links)
        r.drive.resolve(self.model, r.handle)
        for s in r.sensors:
            s.configure(view)
        self.apply_controls(r)
        joints.apply_all(self.model, self.data, r)

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
                f"y within {fl.center[1] - fl.size[1] / 2:.2f}..{fl.center[1] + fl.size[1] / 2:.2f})"
            )
        if not (-100.0 <= loc[2] <= 100.0):
            raise SimulationError(f"location z {loc[2]:.2f} is too far from the floor (allowed -100..100 m)")
        try:
            drive = self.plugins.make_drive(robot)
            sensors = [self.plugins.make_item(item, robot, self.seed, f"{uid}:{name}") for item in robot.items]
        except ConfigError as exc:
            raise SimulationError(str(exc)) from exc
        level = abs(rot[0]) < 1e-6 and abs(rot[1]) < 1e-6
        lowest = drive.lowest_point_m(robot)
        # a level robot put lower than it stands (its wheels in the floor) is lifted onto it
        if level and loc[2] > -lowest:
            loc = (loc[0], loc[1], -lowest - 0.005)
        # a robot at a start pose is set down on what lies below it (a vessel starts where
        # the pose is: in water), and a walking robot wherever it is put (a standing biped
        # would not survive a drop)
        if level and ((set_down and drive.SET_DOWN_AT_START) or drive.SET_DOWN_ALWAYS):
            ground = self._ground_below(loc)
            if ground is not None:
                loc = (loc[0], loc[1], ground - lowest - robot.spawn_clearance_m)
        prefix = f"robot{uid}"
        robotspec.add_robot(self.spec, robot, prefix, loc, rot, drive, sensors)
        r = SimRobot(
            uid=uid,
            name=name,
            config=robot,
            prefix=prefix,
            spawn_time=self.time,
            handle=RobotHandle(prefix),
            sensors=sensors,
            drive=drive,
        )
        for s in sensors:
            s.handle = r.handle
        self.robots[uid] = r
        try:
            self._rebuild()
        except Exception:
            del self.robots[uid]
            robotspec.remove_robot(self.spec, prefix)
            self._rebuild()
            raise
        drive.on_spawn(self, r)
        view = self.view()
        for s in sensors:
            s.reset(view)
        h = r.handle
        r.spawn_qpos = self.data.qpos[h.root_qpos : h.root_qpos + 7].copy()
        self.guard.mark_good(self.data)
        self.reports.add_robot(r, self.time)
        log.info("spawned %s '%s' (id %d) at %.2f,%.2f,%.2f at t=%.3f", robot.class_name, name, uid, *loc, self.time)
        return r

    def _ground_below(self, loc) -> float | None:
        """The USARSim z of the first surface straight below ``loc`` (None: nothing)."""
        start = frames.to_mj_vec(loc)
        geom = np.array([-1], dtype=np.int32)
        dist = mujoco.mj_ray(self.model, self.data, start, np.array([0.0, 0.0, -1.0]), GROUND_GROUPS, 1, -1, geom)
        return None if dist < 0 else loc[2] + dist

    def remove(self, uid: int) -> None:
        r = self.robots.pop(uid, None)
        if r is None:
            return
        r.removed = True
        self.reports.remove_robot(r)
        for key in [k for k in self.live_conf if k[0] == uid]:
            del self.live_conf[key]
        robotspec.remove_robot(self.spec, r.prefix)
        self._rebuild()
        log.info("removed robot '%s' (id %d) at t=%.3f", r.name, uid, self.time)

    # Commands -----------------------------------------------------------------
    def drive(self, uid: int, command: DriveCommand) -> None:
        """One DRIVE (protocol.md 5.3): Flip starts self-righting; with power, Light switches
        the headlight, the robot's drive model applies the parts its kind understands (the
        others are ignored), then the joint orders apply in turn."""
        r = self.robots.get(uid)
        if r is None:
            return
        if command.flip:
            start_righting(self, r)
        if r.battery_empty:
            return
        if command.light is not None:
            r.light = bool(command.light)
        accepts = r.drive.ACCEPTS
        for part in command.parts:
            if type(part) in accepts:
                r.drive.command(part, command.normalized)
        self.apply_controls(r)
        if command.joints:
            self.drive_joints(uid, command.joints)

    def drive_joints(self, uid: int, orders: tuple[JointOrder, ...] | list[JointOrder]) -> None:
        """Joint orders (protocol.md 5.3f, 5.6), applied in turn."""
        r = self.robots.get(uid)
        for o in orders:
            if r is None or not joints.order(self, r, o.name, o.value, o.order):
                log.info("robot id %d: no joint '%s' for order %d (or no power); ignored", uid, o.name, o.order)

    def apply_controls(self, r: SimRobot) -> None:
        """Write the robot's headlight and its drive's controls into the model."""
        if r.handle.light >= 0:
            self.model.light_active[r.handle.light] = bool(r.light) and not r.battery_empty
        r.drive.apply(r, self.data.ctrl)

    def operate(
        self, uid: int, item_type: str | None, name: str | None, opcode: str | None, params: ItemParams | None
    ) -> CommandResult | ZoomResult | Refusal | None:
        """``SET {Type} {Name} {Opcode} {Params}`` on a mounted item (protocol.md 5.4), with
        the Params typed by the protocol layer: its RES goes out first, then whatever the
        operation reported (EFF, a SEN for SCAN); a Refusal (an ERROR line) when the robot has no
        power; None when it is gone."""
        before = len(self.outbox)
        res = self._operate(uid, item_type, name, opcode, params or ItemParams())
        if res is not None:
            self.outbox.insert(before, Output(uid, self.time, res, "RES", periodic=False))
        return res

    def _operate(
        self, uid: int, item_type: str | None, name: str | None, opcode: str | None, params: ItemParams
    ) -> CommandResult | ZoomResult | Refusal | None:
        r = self.robots.get(uid)
        if r is None:
            return None
        if r.battery_empty:
            return Refusal("SET", f"robot '{r.name}' has no power: its battery is empty")
        t = item_type or ""
        for s in r.sensors:
            if s.TYPE.lower() == t.lower() and (not name or s.name.lower() == name.lower()):
                view = dataclasses.replace(
                    self.view(), drive_joint=lambda n, v, o: joints.order(self, r, n, v, o), robot_name=r.name
                )
                result = s.operate(view, opcode, params) if opcode else None
                state = s.state() if result is not None else None
                if state is not None:
                    self.outbox.append(Output(uid, self.time, state, f"EFF:{s.name}", periodic=False))
                if s.LIVE_CONF:
                    self.live_conf[(uid, s.TYPE, s.name)] = s.conf_fields()
                if result is None:
                    return CommandResult(s.TYPE, s.name, ok=False)
                if isinstance(result, ZoomResult):
                    return result  # a camera's RES of its own
                if result.ok and opcode is not None and opcode.upper() == "SCAN" and s.PERIODIC:
                    # the items that send SEN lines at their period are sensors
                    self._emit(r, [cast("Sensor[Any]", s)], f"SEN:{s.TYPE}:{s.name}")
                return CommandResult(s.TYPE, s.name, result.ok, result.extra)
        return CommandResult(t, name or "", ok=False)

    # Stepping -----------------------------------------------------------------
    def advance(self, seconds: float, *, waited: bool = False) -> None:
        """Run whole physics steps covering ``seconds`` of simulated time, sending every
        report that falls due (including at the final instant).

        ``waited``: the caller waits for every reading right after (a lock-step STEP), so
        the final instant's readings are taken on this thread: nothing would run meanwhile,
        and handing them to the measuring thread and back costs two thread wake-ups."""
        target = self.step_count + max(0, int(round(seconds / self.dt)))
        while True:
            self._fire_due(inline=waited and self.step_count >= target)
            if self._samplers:
                self._sample_due()
            if self.step_count >= target:
                break
            n = target - self.step_count
            due = self.reports.next_due()
            if self._samplers:
                first = min(s[0] for s in self._samplers)
                due = first if due is None else min(due, first)
            if due is not None:
                n = max(1, min(n, int(math.ceil(due / self.dt - EPS)) - self.step_count))
            for system in self.systems:  # forces set by hand are renewed often enough
                most = system.max_steps()
                if most is not None:
                    n = min(n, most)
            self._step(n)
        for fn in self._after_advance:
            fn(self)

    def _step(self, n: int) -> None:
        """``n`` physics steps in one call, after every world system's pre-step, under the
        blow-up guard; then the batteries drain."""
        for system in self.systems:
            system.pre_step()
        robots = list(self.robots.values())
        self.guard.step(self.model, self.data, n, robots)
        self.step_count += n
        self.physics_steps += n
        for r in self.batteries.drain(self.model, self.data, robots, n * self.dt):
            r.drive.on_battery_empty()
            self.apply_controls(r)
            joints.apply_all(self.model, self.data, r)
            log.info("robot '%s' (id %d): battery empty at t=%.3f", r.name, r.uid, self.time)

    def _fire_due(self, inline: bool = False) -> None:
        now = self.time
        plans = self.reports.take_due_plans(now)
        if not plans:
            return
        items: list[Due] = []
        if not any(r.battery_empty for r in self.robots.values()):
            for plan in plans:  # sensors' reports (tuples), statuses and packages' states (Reports)
                items += plan
        else:  # a robot whose battery is empty reports its status only
            for plan in plans:
                for x in plan:
                    if x.__class__ is not tuple:
                        if x.status or not x.robot.battery_empty:
                            items.append(x)
                    elif not self.robots[x[0]].battery_empty:
                        items.append(x)
        standing = self.standing()
        if self.measurer is not None and any(x.__class__ is tuple for x in items):
            if not inline:
                self.outbox.push(
                    self.measurer.submit(
                        self.model, self.data, self.caster, now, self.world, self.entities, items, standing
                    )
                )
                return
            self.settle()  # the earlier instants first: a sensor is read by one thread at a time, in order
        for o in measure_all(items, self.view(), standing):
            self.outbox.append(o)

    def standing(self) -> Standing:
        """What a robot's status reads now besides the physics (usarsim.sim.status)."""
        return Standing(
            self.batteries.used_now(),
            frozenset(uid for uid, r in self.robots.items() if r.light),
            tuple(self.cameras.multiview()),
        )

    def _emit(self, r: SimRobot, sensors: list[Sensor], key: str, view: WorldView | None = None) -> None:
        o = measure_report(r.uid, sensors, key, view or self.view())
        if o is not None:
            self.outbox.append(o)

    # The measuring thread ---------------------------------------------------------
    def measure_on_thread(self, on: bool) -> None:
        """Take sensor readings on a thread of their own (usarsim.sim.measuring), or again
        on the calling thread; the simulation thread turns it on while it runs.  Readings
        are then handed out by :meth:`take_outputs` as they are ready."""
        if on and self.measurer is None:
            self.measurer = Measurer()
        elif not on and self.measurer is not None:
            self.settle()
            self.measurer.close()
            self.measurer = None

    def settle(self) -> None:
        """Wait until every reading handed to the measuring thread has been taken (before
        anything that changes what sensors read: the model, an item's settings)."""
        if self.outbox.waiting:
            self.outbox.settle()

    # Reports and queries --------------------------------------------------------
    def truth(self, class_name: str | None = None, name: str | None = None) -> list[tuple]:
        """The ground truth now (:func:`usarsim.sim.truth.truth_rows`)."""
        return truth.truth_rows(self, class_name, name)

    def report(self, uid: int, value) -> None:
        """An answer for robot ``uid``'s client now (a reply: never dropped); nothing when the
        robot is gone."""
        if uid in self.robots:
            self.outbox.append(Output(uid, self.time, value, "RES", periodic=False))

    def take_outputs(self, wait: bool = True) -> list[Output]:
        """Everything output so far, in order; ``wait=False``: only as far as the readings
        being taken on the measuring thread are ready (the rest on a later call)."""
        return self.outbox.take(wait)

    def pose_of(self, uid: int) -> tuple[tuple[float, float, float], tuple[float, float, float]] | None:
        r = self.robots.get(uid)
        if r is None:
            return None
        return r.handle.location(self.data), r.handle.orientation(self.data)
