"""Constants shared by the model builder, the ray caster and the world's entities (a leaf
module: it imports nothing of the simulation, so that they need not import each other)."""

from __future__ import annotations

import numpy as np

# Geom groups: which geoms ray-cast sensors can see.
GROUP_STATIC = 0  # world geometry
GROUP_ROBOT = 1  # robot bodies (chassis)
GROUP_MOVABLE = 2  # movable obstacles
GROUP_WHEEL = 3  # wheels and other small moving parts: not seen by range sensors
RAY_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)
GROUP_WATER = 4  # water volumes: seen by cameras only
GROUP_LOOK = GROUP_WATER  # what only cameras see: water, victims' faces, sensors' housings
# What a robot set down at a start pose lands on: everything but water
GROUND_GROUPS = np.array([1, 1, 1, 1, 0, 1], dtype=np.uint8)

# Collision classes (MuJoCo contype/conaffinity bits): world geometry and chassis
# collide with everything; wheels collide with world geometry and chassis but not
# with other wheels (cylinder-cylinder contacts between robots rubbing side by side
# give unstable contact normals that launch robots).
SOLID_CONTYPE, SOLID_CONAFFINITY = 1, 3
WHEEL_CONTYPE, WHEEL_CONAFFINITY = 2, 0

# Wheel rolling friction and torsional friction: MuJoCo's defaults for the
# second and third friction coefficients.
SPIN_FRICTION = 0.005
ROLL_FRICTION = 0.0001

# Treads (usarsim.robots.skid): a skid-steered robot's wheels meet the floor through a
# tread contact of their own, whose friction is direction-dependent (MuJoCo gives that
# to explicit contact pairs only, in the contact frame of the collider: a capsule lying
# along the axle has its first tangent along the axle).  The floor carries a collision bit
# of its own so that the wheel's cylinder, which still meets everything else (ramps,
# steps, walls, other robots), skips it.
FLOOR_CONTYPE = 8
TREAD_WHEEL_CONTYPE, TREAD_WHEEL_CONAFFINITY = 0, SOLID_CONTYPE

# Waving victims: the right arm rises about the shoulder's own left-right axis from where it
# lies (along the body) to 2 x 0.6 rad, and back, once every 2 s (the manual's victims wave an
# arm to draw attention, section 3.2.1).  A roll about the body's long axis, along which the
# arm lies, would turn the arm about itself and show nothing.
WAVE_AMPLITUDE_RAD = 0.6
WAVE_PERIOD_S = 2.0

# The world's up direction in MuJoCo's frame (Z up), for the systems that right robots.
UP = np.array([0.0, 0.0, 1.0])

# N m per rad of tilt per kg: hovering robots right themselves (usarsim.robots.aerial's
# levelling), and a vessel's hull, by its weight hanging below its buoyancy, in roll
# (usarsim.sim.systems.water).
LEVEL_STIFFNESS = 20.0
