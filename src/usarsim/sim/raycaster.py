"""Batched ray casts for the sensors, the radio and the ground: the compiled kernel of
:mod:`usarsim.sim.raycast` or MuJoCo's ``mj_multiRay``, with see-through materials,
mirrors and grid fenders (manual 3.2.1) and wall counting (protocol.md 12.3)."""

from __future__ import annotations

import copy
import os
import zlib

import mujoco
import numpy as np

from usarsim.sim.constants import GROUP_STATIC, RAY_GROUPS

# Special effects of materials on rays (manual 3.2.1: glass, mirrors, grid fenders).
# Mirrors reflect the range rays of lasers and IR: the ray goes on in the specular
# direction and the reading is the whole path, as a real LIDAR in front of a mirror reads
# the distance to what the mirror shows.  Sonar, cameras and the rays of wall-counting
# sensors see the mirror's face itself.
MIRROR_KINDS = ("laser", "ir")
# Grid fenders let this fraction (their porosity) of laser, IR and camera rays through;
# sonar is echoed by the grid.
POROUS_KINDS = ("laser", "ir", "camera")
# Reflections followed on one ray; a mirror met after them is read as a plain surface.
MAX_BOUNCES = 3
# A ray that passes or leaves a surface goes on from this far beyond it (metres).
RAY_RESTART_M = 1e-6
# Whether a ray passes a grid is decided per direction, told apart at this resolution
# (about 15 microradians; the beams of a scanner are a thousand times farther apart).
POROSITY_DIR_QUANTUM = 2.0**-16
# Surfaces met on one ray at most (grids are met twice each: entering and leaving).
MAX_LEGS = 64
# Counting the walls between two points (protocol.md 12.3, the UDK ComServerInterface's
# obstacle count): each trace starts this far beyond the last hit (50 UU, 0.2 m), to get
# out of the solid it met.
WALL_STEP_M = 0.2
# Hits followed along one segment at most (each wall costs one or two traces).
MAX_WALL_HITS = 64


class RayCaster:
    """Batched ray casts with the caller's robot excluded and a cutoff at the
    sensor's maximum range.

    Rays are cast by the compiled kernel of :mod:`usarsim.sim.raycast` (one call
    for a whole batch, one origin per ray, geoms out of reach culled); models
    with shapes it does not handle, or ``USARSIM_RAYCAST=mujoco`` in the
    environment, use ``mj_multiRay`` (one call per distinct origin).  Both give
    the same distances.

    ``see_through`` maps a sensor kind (``ir``, ``camera``, ``laser``, ``sonar``) to
    the geoms its rays pass through (a bool per geom), and may hold two more
    entries, taken as ``mirror`` and ``porosity`` when those are not given: mirrors
    (a bool per geom; flat faces: the world file allows boxes only) reflect the rays
    of MIRROR_KINDS about the surface normal where they hit, and a geom's
    porosity (0..1) is the fraction of the rays of POROUS_KINDS it lets through.
    Which rays pass is decided by a hash of the ray's direction and the geom's
    name: the same ray passes the same grid every time.  A world without mirrors
    and grids casts exactly as before, one kernel call per batch.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        backend: str | None = None,
        see_through: dict[str, np.ndarray] | None = None,
        mirror: np.ndarray | None = None,
        porosity: np.ndarray | None = None,
    ):
        self.m = model
        self.d = data
        self.rays_cast = 0
        m = model
        alpha = np.where(
            m.geom_matid >= 0, m.mat_rgba[np.maximum(m.geom_matid, 0), 3] if m.nmat else 0.0, m.geom_rgba[:, 3]
        )
        group = np.clip(m.geom_group, 0, 5)
        self._visible = (RAY_GROUPS[group] != 0) & (alpha != 0)
        see_through = dict(see_through or {})
        given_mirror, given_porosity = see_through.pop("mirror", None), see_through.pop("porosity", None)
        mirror = given_mirror if mirror is None else mirror
        porosity = given_porosity if porosity is None else porosity
        # per sensor kind (ir, camera, laser, sonar): the geoms its rays pass through (glass)
        self._see_through = {k: v for k, v in see_through.items() if len(v) == m.ngeom and v.any()}
        self._masks = {k: self._visible & ~v for k, v in self._see_through.items()}
        # mirrors and grids: None when the model has none (then every cast takes the plain path)
        self._mirror = None
        self._porosity = None
        if mirror is not None and len(mirror) == m.ngeom and np.any(mirror):
            self._mirror = np.asarray(mirror, dtype=bool) & self._visible
        if porosity is not None and len(porosity) == m.ngeom and np.any(np.asarray(porosity) > 0):
            self._porosity = np.clip(np.asarray(porosity, dtype=float), 0.0, 1.0)
        self._effects = self._mirror is not None or self._porosity is not None
        if self._porosity is not None:
            # a stable value per geom (its name survives rebuilds, its id may not)
            self._salt = np.array(
                [zlib.crc32((m.geom(g).name or f"#{g}").encode()) for g in range(m.ngeom)], dtype=np.uint64
            )
        # what wall counting sees: the static solids of the world, not robots, movable
        # objects or victims (protocol.md 12.3)
        victims = np.array([m.names.startswith(b"victim/", a) for a in m.name_geomadr], dtype=bool)
        self._solid = self._visible & (group == GROUP_STATIC) & ~victims
        self._gtype = np.ascontiguousarray(m.geom_type, dtype=np.int64)
        self._gbody = np.ascontiguousarray(m.geom_bodyid, dtype=np.int64)
        backend = backend or os.environ.get("USARSIM_RAYCAST", "") or "compiled"
        if backend not in ("compiled", "mujoco"):
            raise ValueError(f"USARSIM_RAYCAST must be 'compiled' or 'mujoco', got {backend!r}")
        if backend == "compiled":
            from usarsim.sim import raycast

            if not np.isin(self._gtype[self._visible], raycast.SUPPORTED).all():
                backend = "mujoco"
            else:
                raycast.warm_up()
        self.backend = backend
        self._new_grid()

    def _new_grid(self) -> None:
        """No grid of geoms yet (the compiled kernel's; filed at its first cast), and the
        time, joint positions and mocap orientations it will have been filed at."""
        self._grid: tuple | None = None
        self._grid_time: float | None = None
        self._grid_qpos = np.empty(0)
        self._grid_mocap = np.empty(0)
        self.grid_builds = 0

    def bound_to(self, data: mujoco.MjData) -> RayCaster:
        """This caster for another MjData of the same model (a copy of the world's state):
        the same masks and materials, a grid of its own."""
        other = copy.copy(self)
        other.d = data
        other.rays_cast = 0
        other._new_grid()
        return other

    def _filed(self) -> tuple:
        """The grid of the visible geoms where they are now: filed again when the clock,
        any joint position or the orientation of a mocap body (a waving victim's arm)
        changed since it was last filed (mocap bodies are turned, not moved)."""
        from usarsim.sim import raycast

        d = self.d
        if (
            self._grid is None
            or d.time != self._grid_time
            or not raycast.same_values(d.qpos, self._grid_qpos)
            or not raycast.same_values(d.mocap_quat.ravel(), self._grid_mocap)
        ):
            self._grid = raycast.build_grid(
                self._gtype,
                self.m.geom_size,
                self._visible,
                d.geom_xpos,
                d.geom_xmat,
                raycast.GRID_CELL_M,
                raycast.GRID_MAX_CELLS,
            )
            self._grid_time = d.time
            self._grid_qpos = d.qpos.copy()
            self._grid_mocap = d.mocap_quat.ravel().copy()
            self.grid_builds += 1
        return self._grid

    def _kernel(self, origins, dirs, max_range, mask, exclude_body, normals, dist, gid, nrm) -> None:
        """The compiled kernel through the grid."""
        from usarsim.sim.raycast import cast_grid_kernel

        m, d = self.m, self.d
        cast_grid_kernel(
            origins,
            dirs,
            float(max_range),
            self._gtype,
            m.geom_size,
            m.geom_rbound,
            self._gbody,
            mask,
            d.geom_xpos,
            d.geom_xmat,
            int(exclude_body),
            bool(normals),
            dist,
            gid,
            nrm,
            *self._filed(),
        )

    def cast(
        self,
        origin: np.ndarray,
        dirs: np.ndarray,
        max_range: float,
        exclude_body: int,
        normals: bool = False,
        kind: str | None = None,
        reflect: bool | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Cast ``dirs`` (n x 3 unit vectors, MuJoCo frame) from ``origin``.

        Returns (distance, normals, geom ids): distance is ``inf`` where nothing is
        hit within ``max_range``.  ``kind`` (``ir``, ``camera``, ``laser``, ``sonar``)
        lets the rays pass through the materials that kind sees through, and grids
        in proportion to their porosity.  Mirrors reflect the rays of MIRROR_KINDS
        when ``reflect`` is true, by default when no normals are asked for (range
        readings; sensors that walk along the straight line past each surface ask
        for normals and see the mirror's face): the distance is then the length of
        the whole path and the geom and normal those of the last surface.
        """
        dirs = np.ascontiguousarray(dirs, dtype=float).reshape(-1, 3)
        origins = np.broadcast_to(np.asarray(origin, dtype=float), dirs.shape)
        return self.cast_from(origins, dirs, max_range, exclude_body, normals, kind, reflect)

    def cast_from(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        max_range: float,
        exclude_body: int,
        normals: bool = False,
        kind: str | None = None,
        reflect: bool | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Cast ray i from ``origins[i]`` along ``dirs[i]`` (n x 3 each, MuJoCo frame)."""
        dirs = np.ascontiguousarray(dirs, dtype=float).reshape(-1, 3)
        origins = np.ascontiguousarray(origins, dtype=float).reshape(-1, 3)
        n = len(dirs)
        self.rays_cast += n
        dist = np.empty(n)
        gid = np.empty(n, np.int32)
        nrm = np.zeros((n, 3))
        if self._effects and kind is not None:
            if reflect is None:
                reflect = not normals
            reflect = bool(reflect) and self._mirror is not None and kind in MIRROR_KINDS
            porous = self._porosity is not None and kind in POROUS_KINDS
            if reflect or porous:
                self._cast_effects(
                    origins, dirs, float(max_range), int(exclude_body), kind, reflect, porous, dist, gid, nrm
                )
                return dist, (nrm if normals else None), gid
        if self.backend == "compiled":  # the fast path
            mask = self._masks.get(kind, self._visible) if kind else self._visible
            self._kernel(origins, dirs, max_range, mask, exclude_body, normals, dist, gid, nrm)
        else:
            self._cast_plain(origins, dirs, float(max_range), int(exclude_body), normals, kind, dist, gid, nrm)
        return dist, (nrm if normals else None), gid

    def count_walls(
        self,
        starts: np.ndarray,
        ends: np.ndarray,
        *,
        kind: str | None = None,
        end_margin: float = 0.0,
        stop_at_first: bool = False,
        step: float = WALL_STEP_M,
    ) -> np.ndarray:
        """Walls crossed on each segment ``starts[i]`` -> ``ends[i]`` (n x 3 each, MuJoCo frame).

        As USARSim counted obstacles between two radios (protocol.md 12.3): a trace along
        the segment, then another from ``step`` (0.2 m) beyond each hit, until the end is
        reached.  Only the static solids of the world count (robots, movable objects and
        victims are not seen); a hit where the segment enters a solid is one wall, so a
        wall thicker than ``step`` is left through its far face without counting twice, and
        a solid that begins less than ``step`` beyond the point where the segment entered
        the one before counts as part of it.  ``kind`` lets the materials that kind sees
        through pass (glass); ``end_margin`` stops each segment that far short of its end
        (a target lying on a surface is not behind it); ``stop_at_first`` stops a segment
        at its first wall (occlusion tests).
        """
        starts = np.ascontiguousarray(starts, dtype=float).reshape(-1, 3)
        ends = np.ascontiguousarray(ends, dtype=float).reshape(-1, 3)
        n = len(starts)
        counts = np.zeros(n, dtype=np.int64)
        delta = ends - starts
        length = np.linalg.norm(delta, axis=1)
        left = length - end_margin
        active = np.flatnonzero(left > 1e-9)
        if not len(active):
            return counts
        dirs = np.zeros_like(delta)
        dirs[active] = delta[active] / length[active, None]
        origins = starts.copy()
        mask = self._solid
        if kind is not None and kind in self._see_through:
            mask = mask & ~self._see_through[kind]
        for _ in range(MAX_WALL_HITS):
            if not len(active):
                break
            k = len(active)
            dist, gid, nrm = np.empty(k), np.empty(k, np.int32), np.zeros((k, 3))
            self._cast_solid(origins[active], dirs[active], float(left[active].max()), mask, dist, gid, nrm)
            hit = dist < left[active]
            entering = hit & (np.einsum("ij,ij->i", nrm, dirs[active]) < 0.0)
            counts[active[entering]] += 1
            moved = dist[hit] + step
            idx = active[hit]
            origins[idx] += dirs[idx] * moved[:, None]
            left[idx] -= moved
            keep = hit & (left[active] > 0.0)
            if stop_at_first:
                keep &= counts[active] == 0
            active = active[keep]
        return counts

    def _cast_solid(self, origins, dirs, max_range, mask, dist, gid, nrm) -> None:
        """Straight rays against the geoms of ``mask`` only (no body excluded), with normals."""
        if self.backend == "compiled":
            self._kernel(origins, dirs, max_range, mask, -1, True, dist, gid, nrm)
            return
        # mj_multiRay filters by group only: hide every other visible geom in an unseen group
        hide = self._visible & ~mask
        saved = self.m.geom_group[hide].copy()
        self.m.geom_group[hide] = 5
        try:
            self._cast_mujoco(origins, dirs, max_range, -1, True, dist, gid, nrm)
        finally:
            self.m.geom_group[hide] = saved

    def _cast_plain(self, origins, dirs, max_range, exclude_body, normals, kind, dist, gid, nrm) -> None:
        """Straight rays: the nearest surface that ``kind`` does not see through."""
        if self.backend == "compiled":
            mask = self._masks.get(kind, self._visible) if kind else self._visible
            self._kernel(origins, dirs, max_range, mask, exclude_body, normals, dist, gid, nrm)
        elif kind in self._see_through:
            # mj_multiRay filters by group only: hide the see-through geoms in an unseen group
            hide = self._see_through[kind]
            saved = self.m.geom_group[hide].copy()
            self.m.geom_group[hide] = 5
            try:
                self._cast_mujoco(origins, dirs, max_range, exclude_body, normals, dist, gid, nrm)
            finally:
                self.m.geom_group[hide] = saved
        else:
            self._cast_mujoco(origins, dirs, max_range, exclude_body, normals, dist, gid, nrm)

    def _passes(self, dirs: np.ndarray, geoms: np.ndarray) -> np.ndarray:
        """Whether rays along ``dirs`` pass the grids ``geoms``: a hash of the quantised
        direction and the grid (splitmix64's finaliser, S. Vigna, "Further scramblings of
        Marsaglia's xorshift generators", 2017), as a number in [0, 1), below the porosity."""
        q = np.round(dirs / POROSITY_DIR_QUANTUM).astype(np.int64).view(np.uint64)
        h = self._salt[geoms].copy()
        with np.errstate(over="ignore"):
            for k in range(3):
                h = h ^ q[:, k]
                h = h + np.uint64(0x9E3779B97F4A7C15)
                h = (h ^ (h >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
                h = (h ^ (h >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
                h = h ^ (h >> np.uint64(31))
        u = (h >> np.uint64(11)).astype(float) * (1.0 / 2.0**53)
        return u < self._porosity[geoms]  # type: ignore[index]  # called for porous casts: the world has grids

    def _cast_effects(self, origins, dirs, max_range, exclude_body, kind, reflect, porous, dist, gid, nrm) -> None:
        """Rays that may pass grids and reflect off mirrors: each ray is cast again from
        just beyond a grid it passes (entering and leaving it) and from a mirror in the
        mirrored direction (its own robot then in sight), until it ends on a surface, runs
        out of range or has been reflected MAX_BOUNCES times."""
        n = len(dirs)
        o = origins.copy()
        v = dirs.copy()
        travelled = np.zeros(n)
        bounces = np.zeros(n, np.int64)
        dist[:] = np.inf
        gid[:] = -1
        nrm[:] = 0.0
        active = np.arange(n)
        for _ in range(MAX_LEGS):
            if not len(active):
                break
            k = len(active)
            left = max_range - travelled[active]
            hd = np.empty(k)
            hg = np.empty(k, np.int32)
            hn = np.zeros((k, 3))
            reflected = bounces[active] > 0
            for sel, body in ((~reflected, exclude_body), (reflected, -1)):
                if not sel.any():
                    continue
                idx = active[sel]
                d_, g_, n_ = np.empty(len(idx)), np.empty(len(idx), np.int32), np.zeros((len(idx), 3))
                self._cast_plain(o[idx], v[idx], float(left[sel].max()), body, True, kind, d_, g_, n_)
                hd[sel], hg[sel], hn[sel] = d_, g_, n_
            hit = np.isfinite(hd) & (hd <= left)
            g = np.where(hit, hg, 0)
            passing = np.zeros(k, dtype=bool)
            if porous:
                grid = hit & (self._porosity[g] > 0)  # type: ignore[index]  # porous: the world has grids
                if grid.any():
                    passing[grid] = self._passes(v[active[grid]], g[grid])
            bouncing = np.zeros(k, dtype=bool)
            if reflect:
                bouncing = hit & ~passing & self._mirror[g] & (bounces[active] < MAX_BOUNCES)  # type: ignore[index]  # reflect: the world has mirrors
            final = hit & ~passing & ~bouncing
            fi = active[final]
            dist[fi] = travelled[fi] + hd[final]
            gid[fi] = hg[final]
            nrm[fi] = hn[final]
            if passing.any():
                pi = active[passing]
                step = hd[passing] + RAY_RESTART_M
                o[pi] += v[pi] * step[:, None]
                travelled[pi] += step
            if bouncing.any():
                ri = active[bouncing]
                nb = hn[bouncing]
                hit_at = o[ri] + v[ri] * hd[bouncing][:, None]
                out = v[ri] - 2.0 * np.einsum("ij,ij->i", v[ri], nb)[:, None] * nb
                out /= np.linalg.norm(out, axis=1, keepdims=True)
                o[ri] = hit_at + out * RAY_RESTART_M
                v[ri] = out
                travelled[ri] += hd[bouncing] + RAY_RESTART_M
                bounces[ri] += 1
            active = active[passing | bouncing]

    def _cast_mujoco(self, origins, dirs, max_range, exclude_body, normals, dist, gid, nrm) -> None:
        starts = np.flatnonzero(np.any(origins[1:] != origins[:-1], axis=1)) + 1
        bounds = [0, *starts.tolist(), len(dirs)]
        for a, b in zip(bounds[:-1], bounds[1:]):
            k = b - a
            g = np.zeros(k, np.int32)
            dd = np.zeros(k)
            nn = np.zeros(3 * k)
            mujoco.mj_multiRay(
                self.m,
                self.d,
                origins[a].copy(),
                dirs[a:b].reshape(-1).copy(),
                RAY_GROUPS,
                1,
                exclude_body,
                g,
                dd,
                nn if normals else None,
                k,
                max_range,
            )
            miss = (g < 0) | (dd < 0) | (dd > max_range)
            dd[miss] = np.inf
            g[miss] = -1
            dist[a:b] = dd
            gid[a:b] = g
            if normals:
                nrm[a:b] = nn.reshape(k, 3)
