"""Arenas varied by seed: variant N of a world places its victims, false alarms, RFID tags and
movable debris anew, and may close or open doorways, by the world's ``variation`` rules
(usarsim.config.variation; docs/world-files.md, "Variants").

The rules every variant keeps:

* the same things, as many and of the same kinds: only positions and headings change (a
  victim keeps its posture, build, waving and sounds; a tag its id and memory);
* nothing inside a solid: a victim's or false alarm's footprint keeps ``wall_clearance_m``
  from every static solid at the heights it occupies, a tag lies on free floor, debris stands
  clear of solids and of the victims;
* start poses kept clear: nothing placed within ``start_clearance_m`` of one;
* every victim reachable: a robot of ``robot_radius_m`` can drive from a start pose to within
  ``reach_m`` of it (debris, which robots push aside, does not count as a wall);
* a doorway is closed only when every room stays reachable: closing it may not cut off any
  floor that a robot could reach before.

The same world and variant give the same arena, byte for byte: the random choices come from
one generator seeded with the world's name and the variant, and positions are kept to the
millimetre.  :func:`check_arena` is the world check ``usarsim validate`` runs on every world.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import random
from collections.abc import Sequence

import numpy as np

from usarsim.config.variation import VariationRules
from usarsim.config.world import StaticObject, WorldConfig
from usarsim.errors import ConfigError
from usarsim.maps.grid import Solid, floor_grid, solid_cells, to_map_frame
from usarsim.maps.truth import connected_to

RESOLUTION_M = 0.05  # the grid the placement works on
# Heights (metres above the floor) where a robot meets solids: from a wheel's bottom to a
# P2AT's top (its body is 0.277 m tall on 0.11 m wheels, Pioneer 3-AT operations manual)
ROBOT_HEIGHTS = (0.03, 0.1, 0.2, 0.35)
# A lying victim's footprint about its pelvis, its own frame (metres): feet to head, and its
# width with the arms (usarsim.sim.victims.VICTIM_LYING), plus the debris across a trapped one
VICTIM_FOOTPRINT = (-0.95, 0.9, -0.32, 0.32)
TRAPPED_FOOTPRINT = (-0.95, 0.9, -0.62, 0.62)
VICTIM_HEIGHTS = (0.03, 0.15, 0.3, 0.6)
TRIES = 4000  # candidate positions drawn per thing before a variant gives up


def load_arena(name_or_path: str, variant: int | None = None) -> WorldConfig:
    """A shipped world by name or a world file by path, as variant ``variant`` (None: as written)."""
    from usarsim.config.catalog import resolve_world

    return apply_variant(resolve_world(name_or_path), variant)


def variant_seed(world_name: str, variant: int) -> int:
    """The seed of variant ``variant`` of ``world_name``'s random choices."""
    return int.from_bytes(hashlib.sha256(f"usarsim-variant:{world_name}:{variant}".encode()).digest()[:8], "big")


def apply_variant(world: WorldConfig, variant: int | None) -> WorldConfig:
    """Variant ``variant`` of ``world`` (``world`` itself for None)."""
    if variant is None:
        return world
    if isinstance(variant, bool) or not isinstance(variant, int) or variant < 0:
        raise ConfigError(f"a variant is a whole number >= 0, got {variant!r}", key="--variant")
    return _Placer(world, variant).place()


class _Placer:
    def __init__(self, world: WorldConfig, variant: int):
        self.world = world
        self.variant = variant
        self.rules: VariationRules = world.variation or VariationRules()
        self.rng = random.Random(variant_seed(world.name, variant))
        self.grid = floor_grid(world, RESOLUTION_M)
        self.starts = np.array([to_map_frame(*p.location[:2]) for p in world.start_poses] or [(0.0, 0.0)])

    # --- the grids ---
    def _static(self, objects: Sequence[StaticObject], heights) -> np.ndarray:
        return solid_cells(self.grid, [Solid.of(o) for o in objects if o.mass_kg <= 0], heights)

    def _clear(self, objects: Sequence[StaticObject]) -> np.ndarray:
        """Cells where a robot of the rules' radius stands clear of everything it cannot
        drive on (usarsim.maps.terrain: the floor, ramps and what they lead up to)."""
        from usarsim.maps.terrain import clear_cells

        return clear_cells(self.grid, [Solid.of(o) for o in objects if o.mass_kg <= 0], self.rules.robot_radius_m)

    def _drivable(self, objects: Sequence[StaticObject]) -> np.ndarray:
        """Cells a robot of the rules' radius can drive to from a start pose."""
        return connected_to(self._clear(objects), self.starts, self.grid)

    def _region_mask(self, objects: Sequence[StaticObject]) -> np.ndarray:
        box = self.rules.region
        if box is None:
            static = [o for o in objects if o.mass_kg <= 0]
            if not static:
                (cx, cy), (sx, sy) = self.world.floor.center, self.world.floor.size
                box = (cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2)
            else:
                box = _solids_box(static)
        xmin, ymin, xmax, ymax = box
        c = self.grid.centres()
        inside = (c[:, 0] > xmin) & (c[:, 0] < xmax) & (-c[:, 1] > ymin) & (-c[:, 1] < ymax)
        return inside.reshape(self.grid.shape)

    # --- the variant ---
    def place(self) -> WorldConfig:
        import cv2

        w = self.world
        rules = self.rules
        if not (
            rules.doorways
            or (rules.victims and w.victims)
            or (rules.false_alarms and w.false_alarms)
            or (rules.rfid_tags and w.rfid_tags)
            or (rules.debris and any(o.mass_kg > 0 for o in w.objects))
        ):
            return dataclasses.replace(w, variant=self.variant)  # nothing to vary
        objects = self._doorways(list(w.objects))
        drivable = self._drivable(objects)
        self.tall_solid = self._static(objects, VICTIM_HEIGHTS)
        # nothing is placed on a platform: only where no solid stands at a victim's heights
        self.region = self._region_mask(objects) & ~self.tall_solid
        # where a robot within reach_m of a point can be: drivable cells grown by reach_m
        k = int(math.ceil(self.rules.reach_m / RESOLUTION_M))
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * k + 1, 2 * k + 1))
        self.near_drivable = cv2.dilate(drivable.astype(np.uint8), kernel).astype(bool)
        self.tall_clear = cv2.distanceTransform((~self.tall_solid).astype(np.uint8), cv2.DIST_L2, 5) * RESOLUTION_M
        self.placed: list[tuple[str, float, float]] = []  # (kind, x, y) in the USARSim frame

        victims, tags = list(w.victims), list(w.rfid_tags)
        followers = self._tag_followers(victims, tags) if self.rules.victims else {}
        if self.rules.victims:
            for i, v in enumerate(victims):
                fp = TRAPPED_FOOTPRINT if v.posture == "trapped" else VICTIM_FOOTPRINT
                x, y, yaw = self._spot(fp, "victim", f"victim '{v.name}'", spacing=self.rules.spacing_m)
                dyaw = yaw - v.rotation[2]
                victims[i] = dataclasses.replace(v, location=(x, y, v.location[2]), rotation=_yawed(v.rotation, yaw))
                for k in followers.get(i, []):
                    tags[k] = self._follow(tags[k], v.location, (x, y), dyaw)
        alarms = list(w.false_alarms)
        if self.rules.false_alarms:
            for i, a in enumerate(alarms):
                hx, hy = a.size[0] / 2, a.size[1] / 2
                x, y, yaw = self._spot((-hx, hx, -hy, hy), "alarm", f"false alarm '{a.name}'", spacing=1.0)
                alarms[i] = dataclasses.replace(a, center=(x, y, a.center[2]), rotation=_yawed(a.rotation, yaw))
        if self.rules.rfid_tags:
            moved = {t for ts in followers.values() for t in ts}
            for i, t in enumerate(tags):
                if i not in moved:
                    x, y, _ = self._spot((-0.05, 0.05, -0.05, 0.05), "tag", f"RFID tag {t.tag_id}", spacing=0.5)
                    tags[i] = dataclasses.replace(t, location=(x, y, t.location[2]))
        if self.rules.debris:
            for i, o in enumerate(objects):
                if o.mass_kg > 0:
                    r = float(np.hypot(*Solid.of(o).half_extents()[:2]))
                    x, y, yaw = self._spot((-r, r, -r, r), "debris", f"movable object '{o.name}'", spacing=0.6)
                    objects[i] = dataclasses.replace(o, center=(x, y, o.center[2]), rotation=_yawed(o.rotation, yaw))
        return dataclasses.replace(
            w,
            objects=tuple(objects),
            victims=tuple(victims),
            false_alarms=tuple(alarms),
            rfid_tags=tuple(tags),
            variant=self.variant,
        )

    def _spot(self, footprint, kind: str, what: str, *, spacing: float) -> tuple[float, float, float]:
        """A free (x, y, yaw) for a thing of ``footprint`` (x min, x max, y min, y max in its own
        frame) by the rules; ConfigError when none is found."""
        cells = np.argwhere(self.region)
        if not len(cells):
            raise ConfigError(f"variant {self.variant}: the variation region holds no free floor", key="variation")
        x0, x1, y0, y1 = footprint
        res = RESOLUTION_M
        us = np.arange(x0, x1 + res / 2, res / 2)
        vs = np.arange(y0, y1 + res / 2, res / 2)
        uu, vv = (a.ravel() for a in np.meshgrid(us, vs))
        clearance = self.rules.wall_clearance_m if kind in ("victim", "alarm") else 0.05
        for _ in range(TRIES):
            r, c = cells[self.rng.randrange(len(cells))]
            x = round(float(self.grid.origin[0] + (c + self.rng.random()) * res), 3)
            y = round(float(-(self.grid.origin[1] + (r + self.rng.random()) * res)), 3)
            yaw = round(self.rng.uniform(-math.pi, math.pi), 4)
            mx, my = to_map_frame(x, y)
            if np.min(np.hypot(self.starts[:, 0] - mx, self.starts[:, 1] - my)) < self.rules.start_clearance_m:
                continue
            if any(math.hypot(px - x, py - y) < self._gap(kind, pk, spacing) for pk, px, py in self.placed):
                continue
            if kind == "victim" and not self.near_drivable[r, c]:
                continue
            # the footprint, turned by yaw (USARSim: clockwise from X seen from above), on the map
            wx = x + uu * math.cos(yaw) - vv * math.sin(yaw)
            wy = y + uu * math.sin(yaw) + vv * math.cos(yaw)
            rows, cols, inside = self.grid.cell_of(np.column_stack((wx, -wy)))
            if not inside.all() or np.min(self.tall_clear[rows, cols]) < clearance:
                continue
            self.placed.append((kind, x, y))
            return x, y, yaw
        raise ConfigError(
            f"variant {self.variant}: found no place for {what} by the variation rules in {TRIES} tries: "
            f"loosen wall_clearance_m, start_clearance_m or spacing_m, or widen the region",
            key="variation",
        )

    @staticmethod
    def _gap(kind: str, other: str, spacing: float) -> float:
        if kind == "victim" and other == "victim":
            return spacing
        if {kind, other} <= {"victim", "alarm"}:
            return max(1.0, min(spacing, 1.5))
        return min(spacing, 0.6) if "debris" in (kind, other) else 0.3

    def _tag_followers(self, victims, tags) -> dict[int, list[int]]:
        """The tags lying within tag_follow_m of a victim, by the victim's index (each tag
        follows its nearest victim)."""
        out: dict[int, list[int]] = {}
        for t, tag in enumerate(tags):
            best = None
            for i, v in enumerate(victims):
                d = math.hypot(tag.location[0] - v.location[0], tag.location[1] - v.location[1])
                if d <= self.rules.tag_follow_m and (best is None or d < best[0]):
                    best = (d, i)
            if best is not None:
                out.setdefault(best[1], []).append(t)
        return out

    def _follow(self, tag, old, new, dyaw: float):
        """``tag`` moved with its victim from ``old`` to ``new``, turned by ``dyaw``; if that
        spot is in a solid the tag lies on the victim's other side, then on it."""
        dx, dy = tag.location[0] - old[0], tag.location[1] - old[1]
        c, s = math.cos(dyaw), math.sin(dyaw)
        for ox, oy in ((c * dx - s * dy, s * dx + c * dy), (-(c * dx - s * dy), -(s * dx + c * dy)), (0.0, 0.0)):
            x, y = round(float(new[0] + ox), 3), round(float(new[1] + oy), 3)
            rows, cols, inside = self.grid.cell_of(np.array([to_map_frame(x, y)]))
            if inside[0] and not self.tall_solid[rows[0], cols[0]]:
                break
        self.placed.append(("tag", x, y))
        return dataclasses.replace(tag, location=(x, y, tag.location[2]))

    def _doorways(self, objects: list[StaticObject]) -> list[StaticObject]:
        """Close or open the rules' doorways, each by its chance, in the file's order; a closing
        that would cut off floor a robot could reach is skipped."""
        for door in self.rules.doorways:
            if self.rng.random() >= door.chance:
                continue
            if door.object:
                objects = [o for o in objects if o.name != door.object]
                continue
            assert door.center is not None and door.size is not None
            panel = StaticObject(
                name=f"door_{door.name}", shape="box", center=door.center, size=door.size, material=door.material
            )
            before = self._drivable(objects)
            clear = self._clear([*objects, panel])
            cut_off = before & clear & ~connected_to(clear, self.starts, self.grid)
            if not cut_off.any():  # every room a robot could reach is still reachable
                objects.append(panel)
        return objects


def _yawed(rotation, yaw: float) -> tuple[float, float, float]:
    return (rotation[0], rotation[1], yaw)


def _solids_box(objects: Sequence[StaticObject]) -> tuple[float, float, float, float]:
    boxes = np.array([Solid.of(o).world_box()[1:] for o in objects])  # (n, 2 corners, 3)
    lo, hi = boxes[:, 0, :2].min(axis=0), boxes[:, 1, :2].max(axis=0)
    return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))


def check_arena(world: WorldConfig) -> list[str]:
    """The world checks: what is wrong with ``world``'s victims, false alarms, RFID tags and
    movable objects (empty when nothing is): each inside no solid, and every victim reachable
    by a robot of the variation rules' radius from a start pose."""
    import cv2

    problems: list[str] = []
    for v in world.victims:
        solid = world.solid_at(v.location, movable=False)
        if solid is not None:
            problems.append(f"victim '{v.name}' lies inside {solid}")
    for a in world.false_alarms:
        others = dataclasses.replace(world, false_alarms=tuple(x for x in world.false_alarms if x is not a))
        solid = others.solid_at(a.center, movable=False)
        if solid is not None:
            problems.append(f"false alarm '{a.name}' lies inside {solid}")
    for t in world.rfid_tags:
        solid = world.solid_at(t.location, movable=False)
        if solid is not None:
            problems.append(f"RFID tag {t.tag_id} lies inside {solid}")
    statics = dataclasses.replace(world, objects=tuple(x for x in world.objects if x.mass_kg <= 0))
    for o in world.objects:
        if o.mass_kg > 0:
            solid = statics.solid_at(o.center, movable=False)
            if solid is not None:
                problems.append(f"movable object '{o.name}' lies inside {solid}")
    if world.victims and world.start_poses:
        placer = _Placer(world, 0)
        drivable = placer._drivable(world.objects)
        k = int(math.ceil(placer.rules.reach_m / RESOLUTION_M))
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * k + 1, 2 * k + 1))
        near = cv2.dilate(drivable.astype(np.uint8), kernel).astype(bool)
        for v in world.victims:
            rows, cols, inside = placer.grid.cell_of(np.array([to_map_frame(*v.location[:2])]))
            if not (inside[0] and near[rows[0], cols[0]]):
                problems.append(
                    f"victim '{v.name}' cannot be reached: no robot {2 * placer.rules.robot_radius_m:g} m wide "
                    f"gets within {placer.rules.reach_m:g} m of it from a start pose"
                )
    return problems
