"""The settings of the aerial, nautical and legged drives as robot files give them (sections
``aerial``, ``nautical`` and ``gait``): an aerial robot's speed limits, a vessel's buoyancy,
thrust and control surfaces, and a walking robot's legs and gait, with their readers.
"""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.config.reader import FieldDefaults, Section


@dataclass(frozen=True, kw_only=True)
class AerialLimits:
    """Speed limits of an aerial robot (protocol.md 5.3d; UDK AirRobot: 2 m/s linear, lateral
    and vertical, 100 degrees/s of yaw) and how hard its rotors can push."""

    max_linear_m_s: float = 2.0
    max_lateral_m_s: float = 2.0
    max_vertical_m_s: float = 2.0
    max_yaw_rate_rad_s: float = 1.7453
    max_accel_m_s2: float = 4.0


@dataclass(frozen=True, kw_only=True)
class NauticalSpec:
    """A vessel (protocol.md 5.3e): its displaced volume (buoyancy), its propeller's thrust,
    and how its rudder and stern planes turn it."""

    volume_m3: float = 0.0
    max_thrust_n: float = 50.0
    max_rudder_rad: float = 0.5
    max_stern_plane_rad: float = 0.5
    rudder_gain: float = 20.0  # N m of yaw torque per rad of rudder per m/s of speed
    stern_plane_gain: float = 20.0  # N m of pitch torque per rad of plane per m/s
    drag_n_per_m_s: float = 40.0  # linear drag in water
    angular_drag: float = 20.0  # N m per rad/s


@dataclass(frozen=True, kw_only=True)
class Leg:
    """One leg of a walking robot: its hip pitch, hip roll and knee links, the lengths of
    its upper and lower segments, and its phase in the gait (0..1).  A biped's leg also
    has a hip yaw (it turns the foot) and ankle pitch and roll links (they keep the sole
    flat); its chain then runs yaw, roll, pitch, knee, ankle pitch, ankle roll, and
    ``knee_forward`` bends its knee forward, as a person's does."""

    hip_pitch: str
    hip_roll: str
    knee: str
    upper_m: float
    lower_m: float
    phase: float = 0.0
    hip_yaw: str | None = None
    ankle_pitch: str | None = None
    ankle_roll: str | None = None
    knee_forward: bool = False

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(
            j
            for j in (self.hip_yaw, self.hip_roll, self.hip_pitch, self.knee, self.ankle_pitch, self.ankle_roll)
            if j is not None
        )


@dataclass(frozen=True, kw_only=True)
class Gait:
    """A walking robot's gait (DRIVE {LinearVelocity} {LateralVelocity} {RotationalVelocity})."""

    legs: tuple[Leg, ...]
    stand_height_m: float  # hip to foot, standing
    step_height_m: float = 0.02
    period_s: float = 0.5
    max_linear_m_s: float = 0.2
    max_lateral_m_s: float = 0.1
    max_yaw_rate_rad_s: float = 0.8
    # fraction of a period each foot stands: 0.5 trots; above it every step begins and
    # ends with both feet down (a biped's double support)
    duty: float = 0.5
    sway_m: float = 0.0  # how far the body shifts sideways over the standing foot


def read_aerial(a: Section) -> AerialLimits:
    d = FieldDefaults(AerialLimits)
    out = AerialLimits(
        max_linear_m_s=a.float("max_linear_m_s", d.max_linear_m_s, min=0.0, min_exclusive=True),
        max_lateral_m_s=a.float("max_lateral_m_s", d.max_lateral_m_s, min=0.0, min_exclusive=True),
        max_vertical_m_s=a.float("max_vertical_m_s", d.max_vertical_m_s, min=0.0, min_exclusive=True),
        max_yaw_rate_rad_s=a.float("max_yaw_rate_rad_s", d.max_yaw_rate_rad_s, min=0.0, min_exclusive=True),
        max_accel_m_s2=a.float("max_accel_m_s2", d.max_accel_m_s2, min=0.0, min_exclusive=True),
    )
    a.finish()
    return out


def read_nautical(n: Section) -> NauticalSpec:
    d = FieldDefaults(NauticalSpec)
    out = NauticalSpec(
        volume_m3=n.float("volume_m3", min=0.0, min_exclusive=True),  # required in a file
        max_thrust_n=n.float("max_thrust_n", d.max_thrust_n, min=0.0, min_exclusive=True),
        max_rudder_rad=n.float("max_rudder_rad", d.max_rudder_rad, min=0.0, max=1.6),
        max_stern_plane_rad=n.float("max_stern_plane_rad", d.max_stern_plane_rad, min=0.0, max=1.6),
        rudder_gain=n.float("rudder_gain", d.rudder_gain, min=0.0),
        stern_plane_gain=n.float("stern_plane_gain", d.stern_plane_gain, min=0.0),
        drag_n_per_m_s=n.float("drag_n_per_m_s", d.drag_n_per_m_s, min=0.0),
        angular_drag=n.float("angular_drag", d.angular_drag, min=0.0),
    )
    n.finish()
    return out


def read_gait(gs: Section) -> Gait:
    ld = FieldDefaults(Leg)
    legs = []
    for ls in gs.entries("legs", required=True):
        legs.append(
            Leg(
                hip_pitch=ls.str("hip_pitch"),
                hip_roll=ls.str("hip_roll"),
                knee=ls.str("knee"),
                upper_m=ls.float("upper_m", min=0.001),
                lower_m=ls.float("lower_m", min=0.001),
                phase=ls.float("phase", ld.phase, min=0.0, max=1.0),
                hip_yaw=ls.str("hip_yaw", ld.hip_yaw),
                ankle_pitch=ls.str("ankle_pitch", ld.ankle_pitch),
                ankle_roll=ls.str("ankle_roll", ld.ankle_roll),
                knee_forward=ls.bool("knee_forward", ld.knee_forward),
            )
        )
    d = FieldDefaults(Gait)
    out = Gait(
        legs=tuple(legs),
        stand_height_m=gs.float("stand_height_m", min=0.001),
        step_height_m=gs.float("step_height_m", d.step_height_m, min=0.0),
        period_s=gs.float("period_s", d.period_s, min=0.05),
        max_linear_m_s=gs.float("max_linear_m_s", d.max_linear_m_s, min=0.0, min_exclusive=True),
        max_lateral_m_s=gs.float("max_lateral_m_s", d.max_lateral_m_s, min=0.0, min_exclusive=True),
        max_yaw_rate_rad_s=gs.float("max_yaw_rate_rad_s", d.max_yaw_rate_rad_s, min=0.0, min_exclusive=True),
        duty=gs.float("duty", d.duty, min=0.5, max=0.95),
        sway_m=gs.float("sway_m", d.sway_m, min=0.0),
    )
    gs.finish()
    return out
