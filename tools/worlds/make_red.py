"""Writes src/usarsim/data/worlds/DM-USAR_red.yaml: the NIST red arena (rubble, pancaked slabs).

python tools/worlds/make_red.py
"""

from __future__ import annotations

import math
import random

from common import CMU_MASS, CMU_SIZE, World

OUTER_H = 1.8
WALL_H = 1.2
CONCRETE_KG_M3 = 2400.0

HEADER = """\
# DM-USAR_red -- the NIST "red" USAR test arena, rebuilt for usarsim.
#
# What it models
#   The red arena is the hardest of the three colour-coded arenas (yellow,
#   orange, red) of the NIST Reference Test Facility for Autonomous Mobile
#   Robots: few perceptual difficulties but maximal demand on locomotion.
#   Its floor is covered with rubble piles, cement blocks, slabs and debris;
#   concrete slabs lie "pancaked" on rubble and on broken columns, leaving
#   voids in which victims lie. Wheeled research robots get stuck here;
#   tracked robots are needed to cross most of it.
#
# Sources (facts only; no text or geometry was copied from any map file)
#   [1] USARSim manual v3.1.3, sec. 3.2.1 "Environment simulation",
#       Fig. 6 and 7 (the real and the simulated red arena): rubble piles,
#       cement blocks, slabs and debris on the floor; fewer perceptual
#       difficulties, maximal demand on locomotion; rubble, bricks and pipes
#       are movable obstacles.
#       (J. Wang, ed. S. Balakirsky, "USARSim V3.1.3: A Game-based Simulation
#       of Mobile Robots", NIST; in the USARSim release files at
#       http://sourceforge.net/projects/usarsim)
#   [2] R. Murphy, J. Casper, M. Micire, J. Hyams, "Assessment of the NIST
#       Standard Test Bed for Urban Search and Rescue", AAAI Tech. Report
#       WS-00-09, 2000 (https://studylib.net/doc/13662779/): the red section,
#       the most difficult, held piles of rubble and dropped floorboards
#       representing a pancake-like structure.
#   [3] NIST, "Performance Metrics and Test Arenas for Autonomous Mobile
#       Robots" (ISD project page, mirrored at http://honda-p3.com/
#       robot_worldwide/robotic_puzzle/performance-metrics-and-test-arenas-
#       for-autonomous-mobile-robots.html): the arenas are modelled on
#       buildings in various stages of collapse. No size is given for the red
#       arena.
#   [4] A. Jacoff, E. Messina, J. Evans, "A Reference Test Course for Urban
#       Search and Rescue Robots", FLAIRS-01, AAAI 2001: the arenas are highly
#       reconfigurable, so no single layout is canonical.
#   [5] Concrete masonry unit ("cement block"): actual 7 5/8 x 7 5/8 x
#       15 5/8 in = 0.194 x 0.194 x 0.397 m
#       (https://engineeringtoolbox.com/concrete-masonry-blocks-d_1731.html),
#       about 28-35 lb (12.7-15.9 kg) (https://www.handlebar-online.com/
#       guidelines/what-are-standard-concrete-block-sizes/).
#
# Estimates (no exact numbers found in the sources available)
#   * Footprint 16.0 m (X) x 20.0 m (Y) inside the outer walls, 320 m^2: an
#     estimate; none of [1]-[4] gives the red arena's size.
#   * Outer walls 1.8 m, partition stubs 1.2 m, 0.1 m thick.
#   * Rubble piles 3.2-3.6 m across and 0.65-0.85 m high, of concrete chunks
#     0.3-0.8 m long tilted up to 0.5 rad (static); loose chunks around them
#     (movable, their mass from concrete at 2400 kg/m^3).
#   * Slabs 0.2 m thick; the central "pancake" slab 3.2 x 2.6 m lies on four
#     0.4 m column stubs, its top 0.6 m above the floor, reached by two
#     leaning slabs (16.7 and 19.4 degrees). Other slabs lean on rubble at
#     14-19 degrees; a toppled wall panel leans on the east wall at 60 degrees.
#   * Cement blocks: 0.397 x 0.194 x 0.194 m, 13 kg [5], movable.
#
# Layout (X = north, Y = east; origin at the arena centre)
#   staging  x -15.5..-8 and 8..15.5 : aprons outside the south and north
#            entrances (each 2.4 m wide, y -1.2..1.2), three start areas each,
#            facing the arena
#   arena    rubble piles in the four quarters (SW, SE, NW, NE), the
#            pancaked slab in the centre, partition stubs beside the entrances
#            and at mid-length of the long walls, loose blocks and debris
#            everywhere except just inside the entrances
#   Every start pose has a level, obstacle-free disc of radius >= 3.2 m
#   around it (room for the largest cars), 0.25 m above the floor.
#
# Conventions
#   USARSim frame: X forward/north, Y right/east, Z down; metres, radians.
#   Floor top is z = 0, so standing objects have negative z centres. Box size
#   and cylinder length are full extents; a cylinder's axis is its own Z
#   before rotation. rotation = [roll, pitch, yaw] applied as R = Rz(yaw)
#   Ry(pitch) Rx(roll) in this Z-down frame: positive yaw turns clockwise
#   seen from above, positive pitch raises the +X end, positive roll lowers
#   the +Y end. Objects with mass_kg are movable; all others are static."""


def chunk_mass(size) -> float:
    return round(size[0] * size[1] * size[2] * CONCRETE_KG_M3, 1)


def build() -> World:
    rng = random.Random(20240612)
    w = World("DM-USAR_red", "NIST red arena - rubble piles, pancaked slabs, cement blocks and debris")
    w.set_floor((0.0, 0.0), (31.0, 21.0))
    w.geo_reference(39.0 + 8.0273 / 60.0, -(77.0 + 12.998 / 60.0))  # NIST Gaithersburg (USARSim's origin)
    w.material("floor", (0.50, 0.49, 0.47, 1.0), 1.0, "dusty concrete")
    w.material("wall", (0.78, 0.22, 0.16, 1.0), 0.8, "red, after the arena name")
    w.material("concrete", (0.60, 0.58, 0.55, 1.0), 0.9, "rubble chunks, slabs, column stubs")
    w.material("cinder", (0.64, 0.64, 0.62, 1.0), 0.9, "cement blocks")
    w.material("metal", (0.42, 0.30, 0.24, 1.0), 0.6, "rusty rebar and pipe")
    w.material("wood", (0.70, 0.56, 0.38, 1.0), 0.8, "broken plywood and floorboards")

    w.comment("outer walls (1.8 m), entrances in the south and north walls")
    w.wall("outer_s", (-8.0, -10.05), (-8.0, 10.05), OUTER_H, "wall", gaps=[(-1.2, 1.2)])
    w.wall("outer_n", (8.0, -10.05), (8.0, 10.05), OUTER_H, "wall", gaps=[(-1.2, 1.2)])
    w.wall("outer_w", (-8.0, -10.0), (8.0, -10.0), OUTER_H, "wall")
    w.wall("outer_e", (-8.0, 10.0), (8.0, 10.0), OUTER_H, "wall")
    w.comment("partition stubs (1.2 m)")
    w.wall("stub_s_w", (-7.95, -3.0), (-5.8, -3.0), WALL_H, "wall")
    w.wall("stub_s_e", (-7.95, 3.0), (-5.8, 3.0), WALL_H, "wall")
    w.wall("stub_n_w", (5.8, -3.0), (7.95, -3.0), WALL_H, "wall")
    w.wall("stub_n_e", (5.8, 3.0), (7.95, 3.0), WALL_H, "wall")
    w.wall("stub_w", (0.0, -9.95), (0.0, -7.2), WALL_H, "wall")
    w.wall("stub_e", (0.0, 7.4), (0.0, 8.7), WALL_H, "wall")

    w.comment("central pancake: a slab on four column stubs, two slabs leaning up to it")
    for i, (px, py) in enumerate([(-1.25, -0.95), (1.25, -0.95), (-1.25, 0.95), (1.25, 0.95)]):
        w.box(f"column_stub_{i + 1}", (px, py, -0.2), (0.35, 0.35, 0.4), "concrete")
    w.box("slab_centre", (0.0, 0.0, -0.5), (3.2, 2.6, 0.2), "concrete")
    w.plate("slab_lean_s", (-3.6, 0.0), (-1.6, 0.0), 2.2, 0.0, 0.6, 0.2, "concrete")
    w.plate("slab_lean_n", (3.3, 0.3), (1.6, 0.3), 1.8, 0.0, 0.6, 0.2, "concrete")

    w.comment("rubble piles (static concrete chunks on a low core)")
    w.pile("pile_sw", -4.2, -6.0, 1.8, 0.8, 32, "concrete", rng)
    w.pile("pile_se", -4.0, 6.0, 1.7, 0.65, 28, "concrete", rng)
    w.pile("pile_nw", 3.8, -6.2, 1.8, 0.85, 32, "concrete", rng)
    w.pile("pile_ne", 4.2, 6.0, 1.6, 0.7, 26, "concrete", rng)

    w.comment("slabs leaning on the piles, a toppled wall panel leaning on the east wall")
    w.plate("slab_lean_nw", (0.8, -6.2), (3.0, -6.2), 1.8, 0.0, 0.75, 0.2, "concrete")
    w.plate("slab_lean_se", (-4.0, 3.4), (-4.0, 5.2), 2.0, 0.0, 0.45, 0.2, "concrete")
    w.plate("panel_lean_e", (0.0, 9.15), (0.0, 9.95), 3.0, 0.0, 1.39, 0.15, "wall")
    w.box("panel_toppled", (-2.0, 8.4, -0.06), (2.4, 1.2, 0.12), "wall", rotation=(0.0, 0.0, 0.3))
    w.plate("floorboard_1", (-6.2, -1.6), (-5.0, -2.6), 0.3, 0.0, 0.25, 0.03, "wood")
    w.plate("floorboard_2", (5.4, 1.9), (6.6, 1.2), 0.3, 0.0, 0.2, 0.03, "wood")

    w.comment("rebar and pipe (static)")
    for i, (x, y, yaw, L) in enumerate(
        [(-1.8, -4.0, 0.4, 2.0), (2.2, 3.2, 1.2, 1.6), (-6.0, 7.8, 2.0, 1.8), (6.4, -8.2, 0.9, 2.2)]
    ):
        w.cylinder(f"rebar_{i + 1}", (x, y, -0.016), 0.016, L, "metal", rotation=(0.0, math.pi / 2, yaw))
    w.cylinder("pipe_1", (-2.6, 2.2, -0.1), 0.1, 1.6, "metal", rotation=(math.pi / 2, 0.0, 0.0))

    # victims first, so that the loose debris keeps clear of them
    w.victim("Kim", 0.2, 0.3, yaw=1.5708, sound=(50.0, 6.0, 2.0))  # in the void under the central slab
    w.victim("Lea", 0.0, 9.65, yaw=0.0, sound=(45.0, 8.0, 2.5))  # under the panel leaning on the east wall
    w.victim("Max", -7.0, -9.6, yaw=-1.5708, posture="sitting", waving=True)  # SW corner, back to the wall
    w.victim("Nia", 2.2, -6.2, yaw=1.5708, sound=(55.0, 7.0, 2.0))  # under the high end of slab_lean_nw
    w.victim("Oto", 1.6, 4.4, yaw=0.5, waving=True, sound=(60.0, 5.0, 1.5))  # in the open, east of centre
    w.victim("Pia", 7.3, 8.8, yaw=0.0, posture="sitting", waving=True)  # NE corner
    w.false_alarm("doll_head", (-4.3, -6.1, -0.95), (0.2, 0.2, 0.2), "Head")  # on top of the SW pile
    w.false_alarm("glove", (5.6, -1.4, -0.03), (0.18, 0.1, 0.06), "Hand")
    w.false_alarm("mannequin_arm", (-2.9, 7.1, -0.05), (0.6, 0.1, 0.1), "Arm", rotation=(0.0, 0.0, 0.7))

    entrances = [(-8.0, -5.0, -1.8, 1.8), (5.0, 8.0, -1.8, 1.8)]  # kept clear just inside the doors
    w.comment("cement blocks (movable, 13 kg): two stacks, the rest strewn")
    bz = CMU_SIZE[2]
    for i, (x, y, lvl, yaw) in enumerate(
        [
            (-6.9, 4.4, 0, 0.0),
            (-6.9, 4.4, 1, 0.0),
            (-6.45, 4.4, 0, 0.0),
            (6.9, -4.6, 0, 1.5708),
            (6.9, -4.6, 1, 1.5708),
            (6.9, -4.6, 2, 1.5708),
        ]
    ):
        w.box(
            f"block_stack_{i + 1}",
            (x, y, -(bz / 2 + lvl * bz)),
            CMU_SIZE,
            "cinder",
            rotation=(0.0, 0.0, yaw),
            mass=CMU_MASS,
        )
    w.scatter(
        "block", 16, (-7.6, 7.6, -9.6, 9.6), [CMU_SIZE], "cinder", rng, mass_of=lambda s: CMU_MASS, keep_out=entrances
    )
    w.comment("loose concrete debris (movable)")
    w.scatter(
        "debris",
        22,
        (-7.6, 7.6, -9.6, 9.6),
        [(0.3, 0.2, 0.15), (0.25, 0.25, 0.12), (0.4, 0.25, 0.1), (0.2, 0.15, 0.1)],
        "concrete",
        rng,
        mass_of=chunk_mass,
        keep_out=entrances,
    )
    w.comment("static debris: big chunks too heavy to push")
    w.scatter(
        "boulder",
        10,
        (-7.4, 7.4, -9.4, 9.4),
        [(0.8, 0.6, 0.35), (0.7, 0.7, 0.3), (1.0, 0.5, 0.25)],
        "concrete",
        rng,
        keep_out=entrances,
    )

    # start poses: staging aprons outside both entrances
    for i, y in enumerate((-6.5, 0.0, 6.5)):
        w.start_pose(
            f"PlayerStart{i + 1}", -11.8, y, 0.0, comment="south apron, facing north into the arena" if i == 0 else ""
        )
    for i, y in enumerate((-6.5, 0.0, 6.5)):
        w.start_pose(
            f"PlayerStart{i + 4}", 11.8, y, 3.1416, comment="north apron, facing south into the arena" if i == 0 else ""
        )

    for tid, x, y in [
        (3001, 0.6, 1.6),
        (3002, 0.9, 9.0),
        (3003, -6.3, -9.3),
        (3004, 1.3, -6.9),
        (3005, 2.4, 4.9),
        (3006, 6.6, 8.6),
        (3007, -6.6, 0.0),
        (3008, 6.6, 0.0),
    ]:
        w.rfid(tid, x, y)
    return w


if __name__ == "__main__":
    build().write(HEADER)
