"""Joint servos: the links of every robot (arms, flippers, pan-tilts, legs) and joint
orders on its wheels (protocol.md 5.3f, 5.6; manual 3.2.3).

A link is driven by a position servo whose set point runs at the link's MaxSpeed towards
the ordered angle (order 0), at an ordered speed (1), or is replaced by an ordered torque
(2); 3 brakes; 10/11/12 are the same relative to the current value.  A driven wheel takes
speed orders (1, 11) and brakes (3), which its drive model honours until the kind's own
wheel command takes the wheel back.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco

from usarsim.config.robot import Link
from usarsim.readings import PackageLink, PackageState
from usarsim.sim import robotspec

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext
    from usarsim.sim.robot import SimRobot

ORDERS = (0, 1, 2, 3, 10, 11, 12)


def order(sim: WorldContext, r: SimRobot, name: str, value: float, kind: int = 0) -> bool:
    """A joint order: targets are limited to the joint's range, speeds to MaxSpeed, torques
    to MaxTorque.  False when the robot has no such joint, no power, or the order is
    unknown."""
    if r.battery_empty or not math.isfinite(value) or kind not in ORDERS:
        return False
    ln = r.config.link(name) or next((x for x in r.config.links if x.name.lower() == name.lower()), None)
    if ln is None:
        w = next((x for x in r.config.wheels if x.name.lower() == name.lower() and x.driven), None)
        if w is None:
            return False
        vmax = r.config.max_speed_rad_s
        if kind in (1, 11):
            base = float(sim.data.ctrl[r.handle.actuator[w.name]]) if kind == 11 else 0.0
            r.drive.wheel_speed[w.name] = max(-vmax, min(vmax, base + value))
        elif kind == 3:
            r.drive.wheel_speed[w.name] = 0.0
        else:
            return False  # wheel angle and torque orders are not modelled
        sim.apply_controls(r)
        return True
    h = r.handle
    q = float(sim.data.qpos[h.joint_qpos[ln.name]])
    qd = float(sim.data.qvel[h.joint_qvel[ln.name]])
    cur_order, cur_value = r.joints.get(ln.name, (0, 0.0))
    if kind == 10:
        kind, value = 0, q + value
    elif kind == 11:
        kind, value = 1, qd + value
    elif kind == 12:
        kind, value = 2, (cur_value if cur_order == 2 else 0.0) + value
    elif kind == 3:
        kind, value = 1, 0.0
    if kind == 0 and ln.limited:
        value = min(max(value, ln.min_range), ln.max_range)
    elif kind == 1:
        value = min(max(value, -ln.max_speed), ln.max_speed)
    elif kind == 2:
        value = min(max(value, -ln.max_torque), ln.max_torque)
    r.joints[ln.name] = (kind, value)
    apply(sim.model, sim.data, r, ln)
    return True


def apply(m: mujoco.MjModel, d: mujoco.MjData, r: SimRobot, ln: Link) -> None:
    """Set a link's servo for its current order: for an angle, the set point runs at
    MaxSpeed towards the target and stops there; for a speed, it runs at that speed
    (within the joint's range); for a torque, the servo is replaced by that torque.  The
    model's per-actuator values are set again after every rebuild."""
    a = r.handle.actuator[ln.name]
    act = int(m.actuator_actadr[a])
    q = float(d.qpos[r.handle.joint_qpos[ln.name]])
    kind, value = r.joints.get(ln.name, (0, None))
    if r.battery_empty:
        kind, value = 2, 0.0
    kp, kv = robotspec.joint_servo_gains(ln)
    lo, hi = robotspec.joint_travel(ln)
    if kind == 2:
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
    if kind == 1:
        m.actuator_actrange[a] = (lo, hi)
        d.ctrl[a] = value
        return
    if value is None:  # never commanded: hold where it was built (0)
        value = 0.0
    cur = float(d.act[act])
    m.actuator_actrange[a] = (min(cur, value), max(cur, value))
    d.ctrl[a] = math.copysign(ln.max_speed, value - cur) if value != cur else 0.0


def apply_all(m: mujoco.MjModel, d: mujoco.MjData, r: SimRobot) -> None:
    """Every link's servo (after a rebuild, or when the battery ran out)."""
    for ln in r.config.links:
        apply(m, d, r, ln)


def position(d: mujoco.MjData, r: SimRobot, name: str) -> float:
    """A link's position as reported (STA, MISSTA): a free-turning joint's angle wrapped into
    [-pi, pi], however many turns it has made."""
    q = float(d.qpos[r.handle.joint_qpos[name]])
    ln = r.config.link(name)
    return math.remainder(q, 2.0 * math.pi) if ln is not None and not ln.limited else q


def package_state(d: mujoco.MjData, r: SimRobot, pkg) -> PackageState:
    """MISSTA: each link of a mission package, its position and torque."""
    h = r.handle
    return PackageState(
        pkg.name,
        tuple(
            PackageLink(i + 1, position(d, r, n), float(d.actuator_force[h.actuator[n]]))
            for i, n in enumerate(pkg.links)
        ),
    )
