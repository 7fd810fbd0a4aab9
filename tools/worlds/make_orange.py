"""Writes src/usarsim/data/worlds/DM-USAR_orange.yaml: the NIST orange arena (two levels).

python tools/worlds/make_orange.py
"""

from __future__ import annotations

import math
import random

from common import BRICK_MASS, BRICK_SIZE, CMU_MASS, CMU_SIZE, World

H = 1.1  # deck top above the floor
SLAB = 0.1  # deck slab thickness
WALL_H = 1.2  # ground-level maze walls
OUTER_H = 2.4  # outer walls (they also close the deck's north and west sides)
RAIL_H = 1.0  # railing walls on the deck
RAMP_RUN = 4.4  # horizontal length of the ramp: slope atan(1.1 / 4.4) = 14.0 degrees
RAMP_Y, RAMP_W = -10.0, 1.6
STEPS = 6  # risers from the floor to the deck
TREAD = 0.28

HEADER = """\
# DM-USAR_orange -- the NIST "orange" USAR test arena, rebuilt for usarsim.
#
# What it models
#   The orange arena is the intermediate one of the three colour-coded arenas
#   (yellow, orange, red) of the NIST Reference Test Facility for Autonomous
#   Mobile Robots: a bi-level arena, a maze of wall panels like the yellow one
#   on the ground floor plus a second level (a deck) that robots reach by a
#   ramp or by stairs. The floor is strewn with debris: paper, pipes, cinder
#   blocks and bricks; a hole in the deck and an open edge are drop-offs.
#
# Sources (facts only; no text or geometry was copied from any map file)
#   [1] USARSim manual v3.1.3, sec. 3.2.1 "Environment simulation",
#       Fig. 4 and 5 (the real and the simulated orange arena): a bi-level
#       arena with more challenging physical obstacles such as stairs and a
#       ramp; the floor is covered with debris including paper, pipes and
#       cinder blocks; bricks, pipes and rubble are movable obstacles.
#       (J. Wang, ed. S. Balakirsky, "USARSim V3.1.3: A Game-based Simulation
#       of Mobile Robots", NIST; in the USARSim release files at
#       http://sourceforge.net/projects/usarsim)
#   [2] R. Murphy, J. Casper, M. Micire, J. Hyams, "Assessment of the NIST
#       Standard Test Bed for Urban Search and Rescue", AAAI Tech. Report
#       WS-00-09, 2000 (https://studylib.net/doc/13662779/): the orange
#       section added a second level reachable by stairs or a ramp, and doors,
#       to the yellow section's hallways, blinds and openings.
#   [3] NIST, "Performance Metrics and Test Arenas for Autonomous Mobile
#       Robots" (ISD project page, mirrored at http://honda-p3.com/
#       robot_worldwide/robotic_puzzle/performance-metrics-and-test-arenas-
#       for-autonomous-mobile-robots.html): the arenas are modelled on
#       buildings in various stages of collapse; the "reality arena" covers
#       about 300 square metres. No size is given for the orange arena.
#   [4] A. Jacoff, E. Messina, J. Evans, "A Reference Test Course for Urban
#       Search and Rescue Robots", FLAIRS-01, AAAI 2001, and "Experiences in
#       Deploying Test Arenas for Autonomous Mobile Robots", PerMIS 2001: the
#       arenas are highly reconfigurable, so no single layout is canonical.
#   [5] Concrete masonry unit sizes: nominal 8 x 8 x 16 in, actual
#       7 5/8 x 7 5/8 x 15 5/8 in = 0.194 x 0.194 x 0.397 m
#       (https://engineeringtoolbox.com/concrete-masonry-blocks-d_1731.html;
#       NAVEDTRA 14043 Builder manual, http://constructionmanuals.tpub.com/
#       14043/css/14043_210.htm); about 28 lb (12.7 kg), 35 lb for
#       heavyweight units (https://www.handlebar-online.com/guidelines/
#       what-are-standard-concrete-block-sizes/).
#   [6] Stair geometry: US residential code (IRC R311.7.5) allows risers of
#       at most 7 3/4 in (0.197 m) and treads of at least 10 in (0.254 m).
#
# Estimates (no exact numbers found in the sources available)
#   * Footprint 20.0 m (X) x 24.0 m (Y) inside the outer walls, about 480 m^2:
#     an estimate. None of [1]-[4] gives the orange arena's size. It is
#     larger than the physical arena probably was, because its deck must hold
#     two level 6.4 m wide areas where any robot of the catalogue, cars
#     included, can be started.
#   * Deck 1.1 m above the floor, 7.4 m x 14.0 m, 0.1 m plywood slab on
#     posts, with a 1.0 m clear crawl space under it; 1.0 m railing walls.
#   * Ramp: 1.6 m wide, 4.4 m run, 14.0 degrees (a P2AT-class wheeled robot
#     climbs it), with 0.15 m curbs. Stairs: 1.4 m wide, 6 risers of
#     0.183 m, treads 0.28 m (within [6]).
#   * Walls 0.1 m thick; maze walls 1.2 m tall, outer walls 2.4 m.
#   * Paper: 5 mm static sheets of a low-friction material (0.3).
#     Cinder blocks 0.397 x 0.194 x 0.194 m, 13 kg [5]; bricks
#     0.194 x 0.092 x 0.057 m, 2 kg; both movable. Pipes 0.12-0.2 m across.
#
# Layout (X = north, Y = east; origin at the arena centre)
#   staging     x -18.5..-10 : paved apron south of the arena, four start
#                              areas facing the 2.0 m entrance (y -1..1)
#   ground      x -10..-6    : SW room | foyer (entrance) | SE room
#               x -6..2.6    : ramp hall (west; the ramp rises north to the
#                              deck), central hall (paper, blocks, crawl-space
#                              opening), east rooms E1 and E2
#               x 2.6..10, y 2.4..12 : north-east hall below the deck's east
#                              edge: an open hall with a start area; the
#                              stairs come down into it; the deck's open edge
#                              (a 1.1 m drop-off) is above its west end
#   upper level x 2.6..10, y -12..2.4 : the deck, two start areas, a hole
#                              (0.8 m square) in its north-west corner over
#                              the crawl space
#   Every start pose has a level, obstacle-free disc of radius >= 3.2 m
#   around it (room for the largest cars), 0.25 m above the surface under it.
#
# Conventions
#   USARSim frame: X forward/north, Y right/east, Z down; metres, radians.
#   Floor top is z = 0, so standing objects have negative z centres; the deck
#   top is z = -1.1. Box size and cylinder length are full extents; a
#   cylinder's axis is its own Z before rotation. rotation = [roll, pitch,
#   yaw] applied as R = Rz(yaw) Ry(pitch) Rx(roll) in this Z-down frame:
#   positive yaw turns clockwise seen from above, positive pitch raises the
#   +X end, positive roll lowers the +Y end. Objects with mass_kg are
#   movable; all others are static."""


def build() -> World:
    rng = random.Random(20240611)
    w = World(
        "DM-USAR_orange", "NIST orange arena - two levels joined by a ramp and stairs, paper, pipes, cinder blocks"
    )
    w.set_floor((-3.75, 0.0), (29.5, 27.0))
    w.geo_reference(39.0 + 8.0273 / 60.0, -(77.0 + 12.998 / 60.0))  # NIST Gaithersburg (USARSim's origin)
    w.material("floor", (0.55, 0.55, 0.52, 1.0), 1.0, "bare concrete")
    w.material("wall", (0.95, 0.56, 0.20, 1.0), 0.8, "orange, after the arena name")
    w.material("wood", (0.78, 0.64, 0.44, 1.0), 0.9, "plywood deck, ramp, stairs")
    w.material("paper", (0.92, 0.92, 0.88, 1.0), 0.3, "loose paper sheets: slippery")
    w.material("cinder", (0.62, 0.62, 0.60, 1.0), 0.9, "concrete masonry units")
    w.material("brick", (0.62, 0.28, 0.20, 1.0), 0.8, "clay bricks")
    w.material("metal", (0.45, 0.47, 0.50, 1.0), 0.6, "steel pipe")
    w.material("pvc", (0.85, 0.85, 0.80, 1.0), 0.5, "plastic pipe")

    # ---------------------------------------------------------------- outer walls
    w.comment("outer walls (2.4 m: they also close the deck's north and west sides)")
    w.wall("outer_s", (-10.0, -12.05), (-10.0, 12.05), OUTER_H, "wall", gaps=[(-1.0, 1.0)])
    w.wall("outer_n", (10.0, -12.05), (10.0, 12.05), OUTER_H, "wall")
    w.wall("outer_w", (-10.0, -12.0), (10.0, -12.0), OUTER_H, "wall")
    w.wall("outer_e", (-10.0, 12.0), (10.0, 12.0), OUTER_H, "wall")

    # ---------------------------------------------------------------- deck
    w.comment("upper level: deck slab (top 1.1 m) with a 0.8 m hole in its north-west corner, posts, skirts")
    zc = -(H - SLAB / 2)
    w.box("deck_main", (6.3, -4.375, zc), (7.4, 13.55, SLAB), "wood")
    w.box("deck_strip_w", (5.8, -11.575, zc), (6.4, 0.85, SLAB), "wood")
    w.box("deck_strip_e", (9.9, -11.575, zc), (0.2, 0.85, SLAB), "wood")
    under = H - SLAB  # crawl space height
    for i, (px, py) in enumerate([(4.6, -9.0), (8.0, -9.0), (4.6, -4.6), (8.0, -4.6), (4.6, -0.2), (8.0, -0.2)]):
        w.box(f"deck_post_{i + 1}", (px, py, -under / 2), (0.2, 0.2, under), "wood")
    # skirts close the crawl space except for an opening from the central hall
    w.wall("deck_skirt_s", (2.6, -11.95), (2.6, 2.4), under, "wood", gaps=[(-4.0, -2.8)])
    w.wall("deck_skirt_e", (2.6, 2.4), (9.95, 2.4), under, "wood")
    w.comment("deck railings (1.0 m walls): gaps for the ramp, the stairs and an open edge (drop-off)")
    w.wall("rail_s", (2.6, -11.95), (2.6, 2.45), RAIL_H, "wall", base=H, gaps=[(-11.0, -9.0)])
    w.wall("rail_e", (2.55, 2.4), (9.95, 2.4), RAIL_H, "wall", base=H, gaps=[(3.2, 4.6), (7.2, 8.8)])

    # ---------------------------------------------------------------- ramp
    w.comment("ramp: ground (x -1.8) to deck (x 2.6) along y -10, 1.6 m wide, 14.0 degrees, with curbs")
    x0 = 2.6 - RAMP_RUN
    w.plate("ramp", (x0, RAMP_Y), (2.6, RAMP_Y), RAMP_W, 0.0, H, 0.1, "wood")
    for side, dy in (("w", -RAMP_W / 2 - 0.03), ("e", RAMP_W / 2 + 0.03)):
        w.plate(f"ramp_curb_{side}", (x0, RAMP_Y + dy), (2.6, RAMP_Y + dy), 0.06, 0.15, H + 0.15, 0.2, "wood")

    # ---------------------------------------------------------------- stairs
    w.comment("stairs: from the north-east hall (y 3.8) up to the deck's east edge (y 2.4), x 7.3..8.7")
    rise = H / STEPS
    for k in range(1, STEPS):
        depth = (STEPS - k) * TREAD
        hk = k * rise
        w.box(f"stair_{k}", (8.0, 2.4 + depth / 2, -hk / 2), (1.4, depth, hk), "wood")

    # ---------------------------------------------------------------- ground maze
    w.comment("ground-level maze walls (1.2 m)")
    w.wall("maze_x-6", (-6.0, -11.95), (-6.0, 11.95), WALL_H, "wall", gaps=[(-8.5, -7.0), (-1.0, 1.0), (8.0, 9.5)])
    w.wall("maze_sw_foyer", (-9.95, -4.0), (-6.05, -4.0), WALL_H, "wall", gaps=[(-8.2, -6.7)])
    w.wall("maze_foyer_se", (-9.95, 4.0), (-6.05, 4.0), WALL_H, "wall", gaps=[(-8.2, -6.7)])
    w.wall("maze_ramp_central", (-5.95, -6.0), (2.55, -6.0), WALL_H, "wall", gaps=[(-3.5, -2.0)])
    w.wall("maze_central_east", (-5.95, 2.4), (2.55, 2.4), WALL_H, "wall", gaps=[(-4.6, -3.1), (0.3, 1.8)])
    w.wall("maze_e1_e2", (-2.0, 2.45), (-2.0, 11.95), WALL_H, "wall", gaps=[(6.0, 7.5)])
    w.wall("maze_e2_ne", (2.6, 2.45), (2.6, 11.95), WALL_H, "wall", gaps=[(9.5, 11.0)])
    w.wall("blind_central_1", (0.2, -1.6), (2.55, -1.6), WALL_H, "wall")
    w.wall("blind_central_2", (-3.8, -0.8), (-3.8, 1.4), WALL_H, "wall")
    w.wall("blind_sw", (-8.6, -10.6), (-6.05, -10.6), WALL_H, "wall")
    w.wall("blind_e1", (-4.4, 10.2), (-2.05, 10.2), WALL_H, "wall")

    # ---------------------------------------------------------------- debris
    w.comment("paper on the floor (5 mm sheets)")
    sheets = [
        (-8.9, -2.6, 0.3),
        (-7.6, -1.4, 1.1),
        (-8.4, 1.9, 2.0),
        (-6.9, 2.8, 0.6),  # foyer
        (-4.9, -4.6, 0.9),
        (-2.9, -3.6, 2.4),
        (-1.2, -4.8, 0.2),
        (0.9, -3.4, 1.4),  # central hall
        (-2.2, -0.6, 0.7),
        (-0.6, 0.9, 2.9),
        (1.4, 1.4, 1.8),
        (-4.6, 1.9, 0.4),
        (-5.1, 5.6, 1.3),
        (-3.2, 7.9, 0.1),
        (-0.9, 4.4, 2.2),
        (1.2, 7.6, 0.8),
    ]  # east rooms
    for i, (x, y, yaw) in enumerate(sheets):
        sx, sy = (0.9, 0.6) if i % 3 else (1.2, 0.8)  # newspaper spreads and cardboard
        w.box(f"paper_{i + 1}", (x, y, -0.0025), (sx, sy, 0.005), "paper", rotation=(0.0, 0.0, yaw))

    w.comment("pipes (static; two movable plastic ones)")
    w.cylinder("pipe_ramp_hall", (-3.9, -10.9, -0.1), 0.1, 1.8, "metal", rotation=(0.0, math.pi / 2, 0.0))
    w.cylinder("pipe_central_1", (-1.6, -2.2, -0.06), 0.06, 1.6, "metal", rotation=(math.pi / 2, 0.0, 0.0))
    w.cylinder("pipe_central_2", (0.6, -0.4, -0.08), 0.08, 1.2, "metal", rotation=(0.0, math.pi / 2, 0.3))
    w.cylinder("pipe_se_1", (-9.2, 7.0, -0.1), 0.1, 2.0, "metal", rotation=(math.pi / 2, 0.0, 0.0))
    w.cylinder("pipe_e2", (0.4, 5.5, -0.06), 0.06, 1.5, "metal", rotation=(0.0, math.pi / 2, 0.0))
    w.cylinder("pipe_crawl", (6.3, -6.8, -0.08), 0.08, 1.8, "metal", rotation=(0.0, math.pi / 2, 0.0))
    w.cylinder("pipe_ne_hall", (9.5, 11.0, -0.1), 0.1, 1.4, "metal", rotation=(math.pi / 2, 0.0, 0.0))
    w.cylinder("pvc_pipe_1", (-5.0, -8.8, -0.055), 0.055, 1.2, "pvc", rotation=(math.pi / 2, 0.0, 0.0), mass=2.0)
    w.cylinder("pvc_pipe_2", (-1.0, 9.0, -0.055), 0.055, 1.2, "pvc", rotation=(0.0, math.pi / 2, 0.0), mass=2.0)

    w.comment("cinder blocks (movable, 13 kg): single, in rows and in two-high stacks")
    bx, by, bz = CMU_SIZE
    blocks = [
        # (x, y, level, yaw)
        (-8.9, -11.3, 0, 0.0),
        (-8.9, -11.3, 1, 0.0),
        (-8.4, -11.3, 0, 0.0),  # SW room, by the blind wall
        (-7.3, -6.0, 0, 0.4),
        (-9.0, -8.1, 0, 1.2),
        (-4.4, -7.1, 0, 0.0),
        (-4.0, -7.1, 0, 0.0),
        (-4.2, -7.1, 1, 0.0),  # ramp hall
        (-3.3, -11.4, 0, 1.5708),
        (-4.8, -2.1, 0, 0.8),
        (-0.2, -2.8, 0, 0.0),
        (1.8, -5.2, 0, 1.5708),
        (1.8, -4.7, 0, 1.5708),  # central
        (-8.6, 10.9, 0, 0.0),
        (-8.6, 10.9, 1, 0.0),
        (-3.2, 3.3, 0, 1.9),  # SE room, E1
        (1.6, 3.3, 0, 0.0),
        (2.0, 11.3, 0, 0.6),  # E2
        (4.0, 11.3, 0, 0.0),
        (4.45, 11.3, 0, 0.0),
        (4.2, 11.3, 1, 0.0),
        (8.9, 3.2, 0, 1.5708),  # NE hall
    ]
    for i, (x, y, lvl, yaw) in enumerate(blocks):
        w.box(
            f"cinder_{i + 1}", (x, y, -(bz / 2 + lvl * bz)), CMU_SIZE, "cinder", rotation=(0.0, 0.0, yaw), mass=CMU_MASS
        )

    w.comment("bricks (movable, 2 kg)")
    brick_spots = [
        (-7.0, -9.6),
        (-6.7, -9.3),
        (-2.6, -8.2),
        (-0.8, -7.0),
        (-5.1, -0.3),
        (-1.3, -0.9),
        (-8.0, 6.3),
        (-7.2, 9.8),
        (-4.9, 8.6),
        (-0.4, 10.9),
        (5.2, 10.9),
        (3.3, 3.0),
    ]
    for i, (x, y) in enumerate(brick_spots):
        yaw = round(rng.uniform(0.0, math.pi), 2)
        w.box(
            f"brick_{i + 1}", (x, y, -BRICK_SIZE[2] / 2), BRICK_SIZE, "brick", rotation=(0.0, 0.0, yaw), mass=BRICK_MASS
        )

    w.comment("SE room: a low table (the victim beside it)")
    w.box("crate_se", (-7.2, 11.2, -0.2), (0.8, 0.8, 0.4), "wood")

    # ---------------------------------------------------------------- start poses
    for i, y in enumerate((-9.75, -3.25, 3.25, 9.75)):
        w.start_pose(
            f"PlayerStart{i + 1}",
            -14.0,
            y,
            0.0,
            comment="staging apron south of the entrance, facing north" if i == 0 else "",
        )
    w.start_pose(
        "PlayerStart5", 6.3, -8.5, 1.5708, floor_height=H, comment="upper deck, west part, facing east along the deck"
    )
    w.start_pose(
        "PlayerStart6",
        6.3,
        -1.6,
        1.5708,
        floor_height=H,
        comment="upper deck, east part, facing east toward the head of the stairs",
    )
    w.start_pose("PlayerStart7", 6.3, 7.3, -1.5708, comment="north-east hall, facing the stairs (west)")

    # ---------------------------------------------------------------- victims, alarms, tags
    w.victim("Dora", 9.3, 1.4, floor_height=H, yaw=1.5708, waving=True, sound=(60.0, 7.0, 2.0))  # deck NE corner
    w.victim("Eric", 3.3, -5.0, floor_height=H, yaw=-1.5708)  # deck south edge, between the two start areas
    w.victim("Fay", 6.2, -2.6, yaw=1.5708, sound=(55.0, 6.0, 2.5))  # crawl space under the deck
    w.victim("Gus", -8.6, 8.2, posture="sitting", waving=True, yaw=1.5708)  # SE room
    w.victim("Hana", -4.2, 6.2, yaw=3.1416, sound=(50.0, 9.0, 2.0))  # E1 room
    w.victim("Ivan", -8.0, -8.9, yaw=0.0, waving=True)  # SW room
    w.false_alarm("doll_head", (1.6, 9.2, -0.1), (0.2, 0.2, 0.2), "Head")
    w.false_alarm("glove", (-1.1, -9.3, -0.03), (0.18, 0.1, 0.06), "Hand")
    w.false_alarm("boot", (9.4, -5.4, -1.16), (0.28, 0.1, 0.12), "Foot")  # on the deck, north edge
    tags = [
        (2001, 9.0, 0.6, H),
        (2002, 3.3, -6.0, H),
        (2003, 6.2, -1.5, 0.0),
        (2004, -8.0, 7.4, 0.0),
        (2005, -4.2, 5.3, 0.0),
        (2006, -7.6, -8.9, 0.0),
        (2007, -1.2, -10.0, 0.0),
        (2008, 2.0, 6.8, 0.0),
        (2009, 3.4, -11.6, H),
    ]
    for tid, x, y, h in tags:
        w.rfid(tid, x, y, floor_height=h)
    return w


if __name__ == "__main__":
    build().write(HEADER)
