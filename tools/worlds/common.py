"""Shared helpers for the world generators in this folder.

Each ``make_*.py`` script builds one world with a :class:`World` and writes its YAML file
(src/usarsim/data/worlds/<name>.yaml).  The scripts are deterministic (fixed random seeds),
so running one again rewrites the same file byte for byte.

Frames and conventions are the world file's (src/usarsim/config/world.py): metres, radians,
X north, Y east, Z down, the floor top at z = 0; a box ``size`` is its full extents; a
``rotation`` is [roll, pitch, yaw] applied as R = Rz(yaw) Ry(pitch) Rx(roll): positive yaw
turns clockwise seen from above, positive pitch raises the body's +X end, positive roll lowers
its +Y end.  A height ``h`` above the floor is z = -h.
"""

from __future__ import annotations

import math
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
WORLDS_DIR = REPO / "src" / "usarsim" / "data" / "worlds"

# Robot footprint rule: every start pose has a flat, level, obstacle-free disc of this radius
# around it (the largest cars of the catalogue are 4.8 m x 2.3 m: half-diagonal ~2.6 m).
START_CLEAR_RADIUS = 3.2
START_LIFT = 0.25  # start poses are 0.25 m above the surface under them

# Standard concrete masonry unit ("cinder block"), nominal 8 x 8 x 16 in, actual
# 7 5/8 x 7 5/8 x 15 5/8 in; about 28 lb (12.7 kg) to 35 lb (15.9 kg).
CMU_SIZE = (0.397, 0.194, 0.194)
CMU_MASS = 13.0
# Modular clay brick, 7 5/8 x 3 5/8 x 2 1/4 in, about 2 kg.
BRICK_SIZE = (0.194, 0.092, 0.057)
BRICK_MASS = 2.0


def rot_matrix(roll: float, pitch: float, yaw: float):
    """R = Rz(yaw) Ry(pitch) Rx(roll), all in the world file's frame."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def apply(m, v):
    return tuple(sum(m[i][j] * v[j] for j in range(3)) for i in range(3))


def box_corners(center, size, rotation):
    m = rot_matrix(*rotation)
    out = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                d = apply(m, (sx * size[0] / 2, sy * size[1] / 2, sz * size[2] / 2))
                out.append(tuple(center[i] + d[i] for i in range(3)))
    return out


def fmt(v: float) -> str:
    v = round(float(v), 4)
    if v == 0:
        v = 0.0
    s = f"{v:.4f}".rstrip("0")
    return s + "0" if s.endswith(".") else s


def vec(v) -> str:
    return "[" + ", ".join(fmt(x) for x in v) + "]"


class World:
    """Collects a world's contents and writes them as YAML, one object per line."""

    def __init__(self, name: str, description: str):
        self.name = name
        self.description = description
        self.floor = None
        self.materials: list[tuple[str, tuple, float, str, tuple]] = []
        self.items: list[tuple[str, object]] = []  # ("comment", text) or ("obj", dict)
        self.poses: list[tuple[str, tuple, tuple, str]] = []
        self.victims: list[dict] = []
        self.alarms: list[dict] = []
        self.tags: list[dict] = []
        self.geo: dict | None = None
        self.names: set[str] = set()
        self.keep_clear: list[tuple[float, float, float, float]] = []  # (x, y, r, floor height)

    # -- declarations ---------------------------------------------------------------------
    def set_floor(self, center, size, material="floor"):
        self.floor = (center, size, material)

    def material(self, name, rgba, friction, comment="", see_through=()):
        self.materials.append((name, rgba, friction, comment, tuple(see_through)))

    def comment(self, text: str):
        self.items.append(("comment", text))

    def _name(self, name: str) -> str:
        if name in self.names:
            raise ValueError(f"duplicate name {name}")
        self.names.add(name)
        return name

    def box(self, name, center, size, material, rotation=(0.0, 0.0, 0.0), mass=0.0):
        if min(size) <= 0:
            raise ValueError(f"{name}: size {size}")
        o = {
            "name": self._name(name),
            "shape": "box",
            "center": tuple(center),
            "size": tuple(size),
            "rotation": tuple(rotation),
            "material": material,
            "mass_kg": mass,
        }
        self.items.append(("obj", o))
        return o

    def cylinder(self, name, center, radius, length, material, rotation=(0.0, 0.0, 0.0), mass=0.0):
        o = {
            "name": self._name(name),
            "shape": "cylinder",
            "center": tuple(center),
            "radius": radius,
            "length": length,
            "rotation": tuple(rotation),
            "material": material,
            "mass_kg": mass,
        }
        self.items.append(("obj", o))
        return o

    def start_pose(self, name, x, y, yaw, floor_height=0.0, comment=""):
        self.poses.append((name, (x, y, -(floor_height + START_LIFT)), (0.0, 0.0, yaw), comment))
        self.keep_clear.append((x, y, START_CLEAR_RADIUS, floor_height))

    def victim(self, name, x, y, floor_height=0.0, yaw=0.0, posture="lying", waving=False, sound=None):
        v = {
            "name": self._name(name),
            "location": (x, y, -(floor_height + 0.1)),
            "rotation": (0.0, 0.0, yaw),
            "posture": posture,
            "waving": waving,
            "sound": sound,
            "level": floor_height,
        }
        self.victims.append(v)

    def false_alarm(self, name, center, size, part, material="default", rotation=(0.0, 0.0, 0.0)):
        self.alarms.append(
            {
                "name": self._name(name),
                "center": center,
                "size": size,
                "part": part,
                "material": material,
                "rotation": rotation,
            }
        )

    def rfid(self, tag_id, x, y, floor_height=0.0, memory=""):
        self.tags.append(
            {"id": tag_id, "location": (x, y, -(floor_height + 0.01)), "memory": memory, "level": floor_height}
        )

    def geo_reference(self, lat, lon, scale_lat=111200.0, scale_lon=71670.0):
        self.geo = {
            "latitude_deg": lat,
            "longitude_deg": lon,
            "scale_latitude_m": scale_lat,
            "scale_longitude_m": scale_lon,
        }

    # -- geometry helpers -----------------------------------------------------------------
    def wall(self, name, p0, p1, height, material, thick=0.1, base=0.0, gaps=()):
        """An upright wall from p0 to p1 (x, y), parallel to X or Y, standing on the surface at
        height ``base``; ``gaps`` are (from, to) stretches along it left open (doorways)."""
        (x0, y0), (x1, y1) = p0, p1
        along_x = abs(y1 - y0) < 1e-9
        if not along_x and abs(x1 - x0) > 1e-9:
            raise ValueError(f"{name}: walls run along X or Y")
        a0, a1 = (min(x0, x1), max(x0, x1)) if along_x else (min(y0, y1), max(y0, y1))
        pieces, cur = [], a0
        for g0, g1 in sorted(gaps):
            if g0 > cur:
                pieces.append((cur, g0))
            cur = max(cur, g1)
        if cur < a1:
            pieces.append((cur, a1))
        zc = -(base + height / 2)
        out = []
        for i, (s0, s1) in enumerate(pieces):
            if s1 - s0 < 0.05:
                continue
            n = name if len(pieces) == 1 else f"{name}_{i + 1}"
            mid = (s0 + s1) / 2
            if along_x:
                out.append(self.box(n, (mid, y0, zc), (s1 - s0, thick, height), material))
            else:
                out.append(self.box(n, (x0, mid, zc), (thick, s1 - s0, height), material))
        return out

    def facade(self, name, p0, p1, height, material, thick=0.25, base=0.0, doors=(), windows=(), sill=0.9, head=2.1):
        """A wall like :meth:`wall` with openings: ``doors`` (from, to) or (from, to, top) are
        open from the surface up to ``top`` (None or absent: the full height), ``windows``
        (from, to) are open between ``sill`` and ``head`` above the surface."""
        (x0, y0), (x1, y1) = p0, p1
        along_x = abs(y1 - y0) < 1e-9
        a0, a1 = (min(x0, x1), max(x0, x1)) if along_x else (min(y0, y1), max(y0, y1))
        cuts = [(d[0], d[1], 0.0, d[2] if len(d) > 2 and d[2] is not None else height) for d in doors]
        cuts += [(wd[0], wd[1], sill, head) for wd in windows]
        cuts.sort()
        spans, cur = [], a0
        for c0, c1, lo, hi in cuts:
            if c0 > cur:
                spans.append((cur, c0, 0.0, 0.0))
            spans.append((c0, c1, lo, hi))
            cur = c1
        if cur < a1:
            spans.append((cur, a1, 0.0, 0.0))
        n = 0
        for s0, s1, lo, hi in spans:
            for zb, zt in ((0.0, lo), (hi, height)) if hi > lo else ((0.0, height),):
                if zt - zb < 0.01 or s1 - s0 < 0.01:
                    continue
                n += 1
                mid, zc = (s0 + s1) / 2, -(base + (zb + zt) / 2)
                if along_x:
                    self.box(f"{name}_{n}", (mid, y0, zc), (s1 - s0, thick, zt - zb), material)
                else:
                    self.box(f"{name}_{n}", (x0, mid, zc), (thick, s1 - s0, zt - zb), material)

    def plate(self, name, start, end, width, h0, h1, thick, material):
        """A flat plate (ramp) whose top surface runs from height h0 above ``start`` (x, y) to
        height h1 above ``end``: pitch = the slope, yaw = the direction."""
        dx, dy = end[0] - start[0], end[1] - start[1]
        run = math.hypot(dx, dy)
        yaw = math.atan2(dy, dx)
        pitch = math.atan2(h1 - h0, run)
        length = math.hypot(run, h1 - h0)
        m = rot_matrix(0.0, pitch, yaw)
        up = apply(m, (0.0, 0.0, -1.0))
        top = ((start[0] + end[0]) / 2, (start[1] + end[1]) / 2, -(h0 + h1) / 2)
        center = tuple(top[i] - thick / 2 * up[i] for i in range(3))
        return self.box(name, center, (length, width, thick), material, rotation=(0.0, pitch, yaw))

    def resting_box(self, name, x, y, size, rotation, material, ground=0.0, sink=0.0, mass=0.0):
        """A (tilted) box whose lowest corner touches the surface at height ``ground`` (sunk
        into it by ``sink``)."""
        corners = box_corners((0.0, 0.0, 0.0), size, rotation)
        low = max(c[2] for c in corners)  # Z down: the lowest corner has the largest z
        return self.box(name, (x, y, -ground - low + sink), size, material, rotation=rotation, mass=mass)

    def top_of(self, obj) -> float:
        """Height above the floor of an object's highest point."""
        if obj["shape"] == "box":
            return -min(c[2] for c in box_corners(obj["center"], obj["size"], obj["rotation"]))
        return -obj["center"][2] + max(obj["radius"], obj["length"] / 2)

    # -- checks ---------------------------------------------------------------------------
    def footprint(self, obj):
        """Axis-aligned (xmin, xmax, ymin, ymax, zlow_height, ztop_height) of an object."""
        if obj["shape"] == "box":
            cs = box_corners(obj["center"], obj["size"], obj["rotation"])
        else:
            r, L = obj["radius"], obj["length"]
            cs = box_corners(obj["center"], (2 * r, 2 * r, L), obj["rotation"])
        xs, ys, zs = [c[0] for c in cs], [c[1] for c in cs], [c[2] for c in cs]
        return min(xs), max(xs), min(ys), max(ys), -max(zs), -min(zs)

    def check_start_areas(self):
        """Every start pose's disc is free of objects that rise above its surface (except the
        surface it stands on), and free of victims, alarms and tags."""
        problems = []
        for (name, _loc, _, _), (x, y, r, h) in zip(self.poses, self.keep_clear):
            for kind, o in self.items:
                if kind != "obj":
                    continue
                x0, x1, y0, y1, zlo, zhi = self.footprint(o)
                cx, cy = min(max(x, x0), x1), min(max(y, y0), y1)
                if math.hypot(cx - x, cy - y) >= r:
                    continue
                if zhi <= h + 1e-6:  # below or flush with the surface: the surface itself
                    continue
                if zlo >= h + 2.0:  # well overhead (none in these worlds)
                    continue
                problems.append(f"{name}: {o['name']} within {r} m")
            for v in self.victims:  # a lying body reaches 0.9 m from its pelvis
                if abs(v["level"] - h) < 0.5 and math.hypot(v["location"][0] - x, v["location"][1] - y) < r + 1.0:
                    problems.append(f"{name}: victim {v['name']} too close")
            for a in self.alarms:
                if abs(-a["center"][2] - h) < 0.5 and math.hypot(a["center"][0] - x, a["center"][1] - y) < r + 0.2:
                    problems.append(f"{name}: false alarm {a['name']} too close")
            for t in self.tags:
                if abs(t["level"] - h) < 0.5 and math.hypot(t["location"][0] - x, t["location"][1] - y) < r:
                    problems.append(f"{name}: RFID tag {t['id']} too close")
        for i, (_, _, _, _) in enumerate(self.poses):
            for j in range(i):
                (xi, yi, ri, hi), (xj, yj, rj, hj) = self.keep_clear[i], self.keep_clear[j]
                if abs(hi - hj) < 0.01 and math.hypot(xi - xj, yi - yj) < ri + rj - 1e-6:
                    problems.append(f"{self.poses[i][0]} and {self.poses[j][0]} discs overlap")
        fc, fs, _ = self.floor
        for (name, _loc, _, _), (x, y, r, _h) in zip(self.poses, self.keep_clear):
            if abs(x - fc[0]) + r > fs[0] / 2 or abs(y - fc[1]) + r > fs[1] / 2:
                problems.append(f"{name}: its disc leaves the floor")
        return problems

    def is_free(self, x0, x1, y0, y1, below=100.0, margin=0.05) -> bool:
        """No object (nor victim or false alarm) overlaps the rectangle [x0, x1] x [y0, y1]
        (grown by ``margin``) at heights below ``below``."""
        for kind, o in self.items:
            if kind != "obj":
                continue
            a0, a1, b0, b1, zlo, _ = self.footprint(o)
            if zlo < below and a0 < x1 + margin and a1 > x0 - margin and b0 < y1 + margin and b1 > y0 - margin:
                return False
        for v in self.victims:
            vx, vy, _ = v["location"]
            if abs(vx - (x0 + x1) / 2) < 1.2 + (x1 - x0) / 2 and abs(vy - (y0 + y1) / 2) < 1.2 + (y1 - y0) / 2:
                return False
        for a in self.alarms:
            if abs(a["center"][0] - (x0 + x1) / 2) < 0.4 and abs(a["center"][1] - (y0 + y1) / 2) < 0.4:
                return False
        return True

    def scatter(self, prefix, count, zone, sizes, material, rng, mass_of=None, keep_out=(), start=1, tries=400):
        """``count`` level boxes lying on the floor at random spots of ``zone`` (x0, x1, y0, y1),
        each with a random yaw and a size drawn from ``sizes``, none touching anything already
        placed nor inside a ``keep_out`` rectangle; ``mass_of(size)`` makes them movable."""
        placed = 0
        for _ in range(tries):
            if placed == count:
                break
            size = rng.choice(sizes)
            x, y = rng.uniform(zone[0], zone[1]), rng.uniform(zone[2], zone[3])
            yaw = round(rng.uniform(0.0, math.pi), 2)
            half = (
                (abs(size[0] * math.cos(yaw)) + abs(size[1] * math.sin(yaw))) / 2,
                (abs(size[0] * math.sin(yaw)) + abs(size[1] * math.cos(yaw))) / 2,
            )
            rect = (x - half[0], x + half[0], y - half[1], y + half[1])
            if any(rect[0] < k[1] and rect[1] > k[0] and rect[2] < k[3] and rect[3] > k[2] for k in keep_out):
                continue
            if not self.is_free(*rect, margin=0.1):
                continue
            mass = mass_of(size) if mass_of else 0.0
            self.box(
                f"{prefix}_{start + placed}",
                (round(x, 3), round(y, 3), -size[2] / 2),
                size,
                material,
                rotation=(0.0, 0.0, yaw),
                mass=mass,
            )
            placed += 1
        if placed < count:
            raise SystemExit(f"{prefix}: placed only {placed} of {count}")

    def pile(
        self, prefix, cx, cy, radius, peak, n, material, rng, sizes=((0.3, 0.8), (0.2, 0.55), (0.15, 0.4)), tilt=0.5
    ):
        """A static rubble pile: a low core and ``n`` tilted concrete chunks whose tops follow a
        dome of height ``peak`` over a disc of ``radius``."""
        self.box(
            f"{prefix}_core_1",
            (cx, cy, -peak * 0.2),
            (radius * 1.0, radius * 1.0, peak * 0.4),
            material,
            rotation=(0.0, 0.0, round(rng.uniform(0, 1.5), 2)),
        )
        self.box(
            f"{prefix}_core_2",
            (cx, cy, -peak * 0.35),
            (radius * 0.55, radius * 0.55, peak * 0.7),
            material,
            rotation=(0.0, 0.0, round(rng.uniform(0, 1.5), 2)),
        )
        for i in range(n):
            d = radius * math.sqrt(rng.random())
            th = rng.uniform(0, 2 * math.pi)
            x, y = cx + d * math.cos(th), cy + d * math.sin(th)
            size = tuple(round(rng.uniform(*r), 2) for r in sizes)
            rot = (
                round(rng.uniform(-tilt, tilt), 2),
                round(rng.uniform(-tilt, tilt), 2),
                round(rng.uniform(0, math.pi), 2),
            )
            e = max(c[2] for c in box_corners((0.0, 0.0, 0.0), size, rot))  # vertical half extent
            top = peak * (1.0 - (d / radius) ** 1.6) + rng.uniform(-0.05, 0.08)
            top = max(top, 1.2 * e)
            self.box(
                f"{prefix}_{i + 1}", (round(x, 3), round(y, 3), round(-(top - e), 3)), size, material, rotation=rot
            )

    def count(self) -> int:
        return sum(1 for k, _ in self.items if k == "obj")

    # -- output ---------------------------------------------------------------------------
    def yaml(self, header: str) -> str:
        out = [header.rstrip() + "\n", f"name: {self.name}", f"description: {self.description}", "time_limit_min: 0"]
        fc, fs, fm = self.floor
        out += ["floor:", f"  center: {vec(fc)}", f"  size: {vec(fs)}", f"  material: {fm}"]
        if self.geo:
            out.append("geo_reference:")
            out += [f"  {k}: {fmt(v) if 'scale' in k else f'{v:.6f}'}" for k, v in self.geo.items()]
        out.append("materials:")
        for name, rgba, fr, com, see in self.materials:
            extra = f", see_through: [{', '.join(see)}]" if see else ""
            line = f"  {name}: {{rgba: {vec(rgba)}, friction: {fmt(fr)}{extra}}}"
            out.append(line + (f"  # {com}" if com else ""))
        out.append("objects:")
        for kind, item in self.items:
            if kind == "comment":
                out.append(f"  # --- {item} ---")
                continue
            o = item
            parts = [f"name: {o['name']}", f"shape: {o['shape']}", f"center: {vec(o['center'])}"]
            if o["shape"] == "box":
                parts.append(f"size: {vec(o['size'])}")
            else:
                parts += [f"radius: {fmt(o['radius'])}", f"length: {fmt(o['length'])}"]
            if any(abs(a) > 1e-9 for a in o["rotation"]):
                parts.append(f"rotation: {vec(o['rotation'])}")
            parts.append(f"material: {o['material']}")
            if o["mass_kg"] > 0:
                parts.append(f"mass_kg: {fmt(o['mass_kg'])}")
            out.append("  - {" + ", ".join(parts) + "}")
        out.append("start_poses:")
        for name, loc, rot, com in self.poses:
            if com:
                out.append(f"  # {com}")
            out.append(f"  - {{name: {name}, location: {vec(loc)}, rotation: {vec(rot)}}}")
        if self.victims:
            out.append("victims:")
            for v in self.victims:
                parts = [f"name: {v['name']}", f"location: {vec(v['location'])}", f"rotation: {vec(v['rotation'])}"]
                if v["posture"] != "lying":
                    parts.append(f"posture: {v['posture']}")
                if v["waving"]:
                    parts.append("waving: true")
                if v["sound"]:
                    db, period, dur = v["sound"]
                    parts.append(f"sound: {{loudness_db: {fmt(db)}, period_s: {fmt(period)}, duration_s: {fmt(dur)}}}")
                out.append("  - {" + ", ".join(parts) + "}")
        if self.alarms:
            out.append("false_alarms:")
            for a in self.alarms:
                parts = [f"name: {a['name']}", f"center: {vec(a['center'])}", f"size: {vec(a['size'])}"]
                if any(abs(r) > 1e-9 for r in a["rotation"]):
                    parts.append(f"rotation: {vec(a['rotation'])}")
                parts.append(f"part: {a['part']}")
                if a["material"] != "default":
                    parts.append(f"material: {a['material']}")
                out.append("  - {" + ", ".join(parts) + "}")
        if self.tags:
            out.append("rfid_tags:")
            for t in self.tags:
                out.append(f'  - {{id: {t["id"]}, location: {vec(t["location"])}, memory: "{t["memory"]}"}}')
        return "\n".join(out) + "\n"

    def write(self, header: str) -> Path:
        problems = self.check_start_areas()
        if problems:
            raise SystemExit("start areas not clear:\n  " + "\n  ".join(problems))
        path = WORLDS_DIR / f"{self.name}.yaml"
        path.write_text(self.yaml(header), encoding="utf-8")
        print(
            f"wrote {path.relative_to(REPO)}: {self.count()} objects, {len(self.poses)} start poses, "
            f"{len(self.victims)} victims, {len(self.tags)} RFID tags, {len(self.alarms)} false alarms"
        )
        return path
