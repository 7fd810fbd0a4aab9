"""Writes src/usarsim/data/worlds/DM-CollapsedBuilding.yaml: a partly collapsed three-storey
building in open ground.

    python tools/worlds/make_collapsed.py
"""

from __future__ import annotations

import math
import random

from common import CMU_MASS, CMU_SIZE, World

STOREY = 3.0  # floor-to-floor height
SLAB = 0.25  # floor slab thickness
WALL = STOREY - SLAB  # clear height of a storey
EXT = 0.25  # exterior wall thickness
INT = 0.15  # interior wall thickness
CONCRETE_KG_M3 = 2400.0

HEADER = """\
# DM-CollapsedBuilding -- a partly collapsed three-storey building in open ground.
#
# What it models
#   An outdoor collapsed-structure site of the kind US&R robots are tested
#   in: a three-storey concrete-frame office building, 12 m x 24 m, whose
#   west half still stands (a usable ground floor of four rooms, two upper
#   storeys open on their broken east side) while its east half came down.
#   The east half shows the classic collapse patterns and their voids: the
#   first-floor slab hangs from the standing part onto the ground (a
#   "lean-to" with a triangular void beneath), the second-floor slab leans
#   from the standing part onto a pancaked stack of the remaining floors and
#   roof (low voids between the layers), exterior wall panels lie toppled
#   around it, and a rubble field with debris piles surrounds the ruin.
#   Open, level ground all around gives room to start any robot, cars and
#   aircraft included.
#
# Sources (facts only; no text or geometry was copied from any map file)
#   [1] USARSim manual v3.1.3, sec. 3.2.1 "Environment simulation": besides
#       the USAR arenas, outdoor areas and simulated collapsed buildings were
#       modelled; victims wave, groan and lie in the rubble.
#       (J. Wang, ed. S. Balakirsky, "USARSim V3.1.3: A Game-based Simulation
#       of Mobile Robots", NIST; in the USARSim release files at
#       http://sourceforge.net/projects/usarsim)
#   [2] UK Fire and Rescue national guidance, "Structural defect or further
#       collapse" (https://www.ukfrs.com/guidance/subsurface-height-
#       structures-and-confined-spaces?bundle=hazard&id=13542&parent=13555):
#       pancake collapse (floors fall horizontally onto those below), lean-to
#       collapse (a support fails at one end; triangular voids beneath offer
#       refuge), V-shape collapse.
#   [3] "Disaster City helps master any disaster", Officer.com
#       (http://www.officer.com/article/10249196/preparing-for-disaster) and
#       "When Disaster Strikes", Government Technology
#       (https://www.govtech.com/em/safety/When-Disaster-Strikes.html): the
#       TEEX training site is a 52-acre mock community with full-scale
#       buildings, rubble piles, a multi-storey prop with crushed columns and
#       hanging concrete slabs, and a two-storey concrete building whose top
#       floor "pancaked" onto the one below.
#   [4] NIST/DHS Response Robot Evaluation Exercise #6
#       (https://www.nist.gov/news-events/events/2010/03/response-robot-
#       evaluation-exercise-6): robots search building interiors and
#       exteriors, partially collapsed structures and confined spaces in
#       rubble piles.
#
# Estimates (this is a representative site, not a survey of a real one)
#   * Building 12.0 m (X) x 24.0 m (Y), storeys 3.0 m floor to floor, slabs
#     0.25 m, exterior walls 0.25 m (windows 0.9-2.1 m above each floor),
#     interior walls 0.15 m, doorways 1.2-1.6 m wide and 2.1-2.2 m high, a
#     3.0 m loading door in the west face.
#   * Lean-to slab 29.9 degrees, upper leaning slab 27.8 degrees; pancaked
#     layers 0.75, 1.6 and 2.4 m high with 0.25-0.5 m voids.
#   * Rubble piles 4-6 m across and 0.8-1.4 m high (static chunks); loose
#     chunks (movable, concrete at 2400 kg/m^3) and cement blocks
#     (0.397 x 0.194 x 0.194 m, 13 kg) scattered around.
#   * Ground 80 m x 80 m of packed earth and gravel.
#
# Layout (X = north, Y = east; origin at the centre of the building)
#   building   x -6..6, y -12..12; the standing west half y -12..0, the
#              collapsed east half y 0..12
#   ground floor of the standing half: SW room (x -6..0.5, y -12..-6; door
#              in the south face), NW room (x 0.5..6, y -12..-6; loading door
#              in the west face), SE room (x -6..-1, y -6..0), NE room
#              (x -1..6, y -6..0; a door in the north face and a breach in
#              the east wall into the lean-to void)
#   rubble     piles south (x -9.5), north (x 9.8), east (y 18) and
#              south-east (x -9, y 15) of the ruin, debris in between
#   start      eight start areas in the open: three south (x -20), two
#              west (y -22), two north (x 20), one east (y 32), each facing
#              the building, each a level obstacle-free disc of radius
#              >= 3.2 m, 0.25 m above the ground.
#
# Conventions
#   USARSim frame: X forward/north, Y right/east, Z down; metres, radians.
#   Ground top is z = 0, so standing objects have negative z centres. Box
#   size and cylinder length are full extents; a cylinder's axis is its own
#   Z before rotation. rotation = [roll, pitch, yaw] applied as R = Rz(yaw)
#   Ry(pitch) Rx(roll) in this Z-down frame: positive yaw turns clockwise
#   seen from above, positive pitch raises the +X end, positive roll lowers
#   the +Y end. Objects with mass_kg are movable; all others are static."""


def chunk_mass(size) -> float:
    return round(size[0] * size[1] * size[2] * CONCRETE_KG_M3, 1)


def build() -> World:
    rng = random.Random(20240613)
    w = World(
        "DM-CollapsedBuilding",
        "outdoor collapsed building - standing half with a usable ground floor, "
        "pancaked and lean-to slabs, rubble field, open ground",
    )
    w.set_floor((0.0, 0.0), (80.0, 80.0), material="ground")
    w.geo_reference(39.0 + 8.0273 / 60.0, -(77.0 + 12.998 / 60.0))  # NIST Gaithersburg (USARSim's origin)
    w.material("ground", (0.45, 0.41, 0.34, 1.0), 0.9, "packed earth and gravel")
    w.material("concrete", (0.66, 0.65, 0.61, 1.0), 0.9, "slabs, columns, rubble")
    w.material("facade", (0.74, 0.64, 0.52, 1.0), 0.8, "exterior walls (rendered masonry)")
    w.material("plaster", (0.86, 0.84, 0.79, 1.0), 0.7, "interior walls")
    w.material("cinder", (0.64, 0.64, 0.62, 1.0), 0.9, "cement blocks")
    w.material("metal", (0.42, 0.30, 0.24, 1.0), 0.6, "rusty rebar")
    w.material("wood", (0.62, 0.48, 0.32, 1.0), 0.7, "furniture, crates")

    # ------------------------------------------------------------------ standing half
    w.comment("standing half (y -12..0): ground-floor exterior walls")
    south_win = [(-11.0, -9.6), (-4.6, -3.2), (-2.0, -0.8)]
    w.facade("gf_south", (-6.0, -12.125), (-6.0, 0.0), WALL, "facade", doors=[(-8.2, -6.6, 2.2)], windows=south_win)
    w.facade("gf_west", (-5.875, -12.0), (5.875, -12.0), WALL, "facade", doors=[(1.5, 4.5)], windows=[(-4.8, -3.4)])
    w.facade(
        "gf_north",
        (6.0, -12.125),
        (6.0, 0.0),
        WALL,
        "facade",
        doors=[(-5.0, -3.6, 2.2)],
        windows=[(-10.5, -9.1), (-1.8, -0.6)],
    )
    w.facade("gf_east", (-5.875, 0.0), (5.875, 0.0), WALL, "facade", doors=[(0.8, 2.6, 1.7)])  # breach
    w.comment("ground-floor interior walls and furniture")
    w.facade(
        "gf_int_mid",
        (-5.875, -6.0),
        (5.875, -6.0),
        WALL,
        "plaster",
        thick=INT,
        doors=[(-4.4, -3.2, 2.1), (2.0, 3.4, 2.1)],
    )
    w.facade("gf_int_nw", (0.5, -11.875), (0.5, -6.075), WALL, "plaster", thick=INT, doors=[(-9.6, -8.4, 2.1)])
    w.facade("gf_int_se", (-1.0, -5.925), (-1.0, -0.125), WALL, "plaster", thick=INT, doors=[(-3.6, -2.4, 2.1)])
    w.box("gf_column", (2.5, -3.0, -WALL / 2), (0.4, 0.4, WALL), "concrete")
    w.box("desk_sw", (-1.4, -10.9, -0.375), (1.4, 0.7, 0.75), "wood")
    w.box("cabinet_sw", (-5.5, -6.6, -0.65), (0.5, 0.9, 1.3), "wood")
    w.box("desk_se", (-3.2, -0.7, -0.375), (1.4, 0.7, 0.75), "wood")
    w.plate("ceiling_fall_se", (-5.6, -4.0), (-3.8, -4.0), 1.8, 0.0, 1.1, 0.12, "concrete")
    w.box("desk_ne", (4.6, -1.0, -0.375), (0.7, 1.4, 0.75), "wood")
    for i, (x, y) in enumerate([(4.9, -10.9), (4.9, -10.2), (5.3, -7.0)]):
        w.box(f"crate_nw_{i + 1}", (x, y, -0.25), (0.5, 0.5, 0.5), "wood", mass=15.0)

    w.comment("slabs of the standing half (tops 3.0, 6.0 and 9.0 m)")
    for k, top in enumerate((STOREY, 2 * STOREY, 3 * STOREY)):
        w.box(f"slab_{k + 1}", (0.0, -6.0625, -(top - SLAB / 2)), (12.25, 12.125, SLAB), "concrete")
    w.comment("upper storeys: exterior walls with windows, the east side broken open")
    up_win = [(-11.0, -9.6), (-7.6, -6.2), (-4.6, -3.2), (-2.0, -0.8)]
    for k, base in enumerate((STOREY, 2 * STOREY)):
        f = k + 1
        w.facade(f"f{f}_south", (-6.0, -12.125), (-6.0, 0.0), WALL, "facade", base=base, windows=up_win)
        w.facade(
            f"f{f}_west",
            (-5.875, -12.0),
            (5.875, -12.0),
            WALL,
            "facade",
            base=base,
            windows=[(-4.8, -3.4), (-1.2, 0.2), (2.4, 3.8)],
        )
        w.facade(f"f{f}_north", (6.0, -12.125), (6.0, 0.0), WALL, "facade", base=base, windows=up_win)
        w.box(f"f{f}_east_stub_s", (-5.3, 0.0, -(base + WALL / 2)), (1.4, EXT, WALL), "facade")
        w.box(f"f{f}_east_stub_n", (5.4, 0.0, -(base + WALL / 2)), (1.2, EXT, WALL), "facade")

    # ------------------------------------------------------------------ collapsed half
    w.comment("collapsed half (y 0..12): lean-to first-floor slab, leaning second-floor slab")
    w.plate("slab_leanto", (0.0, 5.2), (0.0, 0.0), 11.5, 0.0, 2.95, SLAB, "concrete")
    w.plate("slab_leaning", (0.0, 6.9), (0.0, 0.0), 11.5, 2.45, 5.95, SLAB, "concrete")
    w.comment("pancaked floors and roof (tops 0.75, 1.6, 2.4 m) on wall and column remnants")
    for i, (c, s) in enumerate(
        [
            ((-3.25, 6.3), (4.5, 0.25)),
            ((3.25, 11.85), (4.5, 0.25)),
            ((-5.85, 9.5), (0.25, 3.0)),
            ((5.85, 7.8), (0.25, 2.6)),
        ]
    ):
        w.box(f"remnant_0_{i + 1}", (c[0], c[1], -0.25), (s[0], s[1], 0.5), "facade")
    w.box("pancake_1", (0.0, 9.0625, -0.625), (12.25, 6.125, SLAB), "concrete", rotation=(0.02, 0.0, 0.0))
    for i, (x, y) in enumerate([(-4.5, 7.0), (4.0, 7.5), (-3.5, 11.2), (4.5, 11.0)]):
        w.box(f"remnant_1_{i + 1}", (x, y, -1.05), (0.8, 0.8, 0.6), "concrete", rotation=(0.0, 0.0, 0.3 * i))
    w.box("pancake_2", (0.3, 9.1, -1.475), (12.0, 6.0, SLAB), "concrete", rotation=(0.0, 0.0, 0.03))
    for i, (x, y) in enumerate([(-4.0, 8.0), (3.5, 8.5), (0.5, 11.3)]):
        w.box(f"remnant_2_{i + 1}", (x, y, -1.875), (0.7, 0.7, 0.55), "concrete", rotation=(0.0, 0.0, 0.5 * i))
    w.box("pancake_3", (-0.3, 9.1, -2.275), (11.8, 6.1, SLAB), "concrete", rotation=(-0.03, 0.02, 0.0))
    w.comment("toppled exterior wall panels")
    w.box("fallen_wall_e", (0.0, 13.8, -0.125), (11.0, 2.9, 0.25), "facade", rotation=(0.0, 0.0, 0.05))
    w.plate("fallen_wall_s", (-8.0, 9.0), (-6.2, 9.0), 5.0, 0.0, 2.3, 0.25, "facade")
    w.plate("fallen_wall_n", (9.0, 3.0), (6.3, 3.0), 4.0, 0.0, 0.8, 0.25, "facade")
    w.comment("broken columns and rebar")
    for i, (x, y, yaw) in enumerate([(-7.4, 1.2, 0.3), (8.0, 11.6, 1.2), (3.5, 15.8, 2.6)]):
        w.cylinder(f"column_broken_{i + 1}", (x, y, -0.2), 0.2, 2.5, "concrete", rotation=(0.0, math.pi / 2, yaw))
    for i, (x, y, yaw, L) in enumerate(
        [
            (-7.0, 5.6, 0.4, 2.0),
            (7.5, 5.8, 1.9, 2.4),
            (-4.8, 16.0, 0.9, 1.8),
            (6.2, 14.8, 2.2, 2.2),
            (-10.5, 8.0, 1.4, 1.6),
            (11.2, 14.0, 0.2, 2.0),
        ]
    ):
        w.cylinder(f"rebar_{i + 1}", (x, y, -0.016), 0.016, L, "metal", rotation=(0.0, math.pi / 2, yaw))

    w.comment("rubble piles")
    w.pile("pile_s", -9.5, 3.0, 2.0, 1.0, 24, "concrete", rng)
    w.pile("pile_n", 9.8, 9.0, 2.4, 1.2, 28, "concrete", rng)
    w.pile("pile_e", 0.5, 18.0, 3.0, 1.4, 34, "concrete", rng)
    w.pile("pile_se", -9.0, 15.0, 2.0, 0.8, 20, "concrete", rng)

    # victims before the loose debris, so that the debris keeps clear of them
    w.victim("Quinn", 2.0, 1.8, yaw=1.5708, sound=(55.0, 6.0, 2.0))  # lean-to void, by the breach
    w.victim("Rosa", -2.0, 9.2, yaw=0.0, sound=(45.0, 9.0, 2.5))  # under the lowest pancaked slab
    w.victim("Sam", -4.6, -10.8, yaw=1.5708, posture="sitting", waving=True)  # SW room
    w.victim("Tia", 11.6, 4.2, yaw=2.4, waving=True, sound=(65.0, 5.0, 1.5))  # rubble field, north
    w.victim("Uma", 3.0, 10.6, floor_height=2.4, yaw=0.0, waving=True)  # on top of the pancaked stack
    w.victim("Vic", -3.0, -2.6, yaw=3.1416, sound=(50.0, 7.0, 2.0))  # SE room, beside the fallen ceiling
    w.false_alarm("doll_head", (-9.3, 3.2, -1.1), (0.2, 0.2, 0.2), "Head")  # on the south pile
    w.false_alarm("glove", (7.2, 1.4, -0.03), (0.18, 0.1, 0.06), "Hand")
    w.false_alarm("mannequin_leg", (-2.6, 21.8, -0.06), (0.9, 0.14, 0.12), "Leg", rotation=(0.0, 0.0, 0.6))

    building = (-6.5, 6.5, -12.5, 12.5)
    w.comment("loose concrete debris and cement blocks (movable)")
    w.scatter(
        "debris",
        24,
        (-14.0, 14.0, -4.0, 24.0),
        [(0.3, 0.2, 0.15), (0.25, 0.25, 0.12), (0.4, 0.25, 0.1), (0.2, 0.15, 0.1)],
        "concrete",
        rng,
        mass_of=chunk_mass,
        keep_out=[building],
    )
    w.scatter(
        "block",
        10,
        (-14.0, 14.0, -4.0, 24.0),
        [CMU_SIZE],
        "cinder",
        rng,
        mass_of=lambda s: CMU_MASS,
        keep_out=[building],
    )
    w.comment("static debris: big chunks")
    w.scatter(
        "boulder",
        18,
        (-14.0, 14.0, -4.0, 24.0),
        [(0.9, 0.7, 0.4), (0.8, 0.8, 0.35), (1.2, 0.6, 0.3), (0.6, 0.5, 0.5)],
        "concrete",
        rng,
        keep_out=[building],
    )

    # ------------------------------------------------------------------ start poses
    for i, y in enumerate((-8.0, 0.0, 8.0)):
        w.start_pose(
            f"PlayerStart{i + 1}", -20.0, y, 0.0, comment="south of the building, facing north" if i == 0 else ""
        )
    w.start_pose("PlayerStart4", -4.0, -22.0, 1.5708, comment="west, facing east toward the loading door")
    w.start_pose("PlayerStart5", 4.0, -22.0, 1.5708)
    w.start_pose("PlayerStart6", 20.0, -4.0, 3.1416, comment="north, facing south")
    w.start_pose("PlayerStart7", 20.0, 6.0, 3.1416)
    w.start_pose("PlayerStart8", 0.0, 32.0, -1.5708, comment="east, beyond the rubble field, facing west")

    for tid, x, y, h in [
        (4001, 2.8, 1.2, 0.0),
        (4002, -1.0, 9.9, 0.0),
        (4003, -3.8, -10.0, 0.0),
        (4004, 11.0, 3.6, 0.0),
        (4005, 2.2, 10.0, 2.4),
        (4006, -3.6, -3.2, 0.0),
        (4007, -7.0, -7.4, 0.0),
        (4008, 2.9, -12.6, 0.0),
        (4009, 7.0, -4.3, 0.0),
    ]:
        w.rfid(tid, x, y, floor_height=h)
    return w


if __name__ == "__main__":
    build().write(HEADER)
