"""Robot cameras on the simulation's side: which camera each tile of the MultiView shows
(manual 3.2.6; protocol.md 11), the viewports a robot chose (SET {Type Viewports}, 5.4),
and the snapshots the render thread draws from (protocol.md 10; with each robot's chassis,
which a free camera may follow)."""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import mujoco

from usarsim.sim import frames, robotspec
from usarsim.sim.pictures import SceneTables, scene_tables

if TYPE_CHECKING:
    from usarsim.sensors.camera import CameraItem
    from usarsim.sim.render import Snapshot
    from usarsim.sim.robot import SimRobot
    from usarsim.sim.simulation import Simulation


class Cameras:
    """The MultiView's state: how many robot cameras it shows at most (``multiview_cameras``),
    and which."""

    def __init__(self, sim: Simulation):
        self.sim = sim
        self._multiview_cameras = 4
        self._multiview: list[tuple[int, str]] | None = None
        # the model the MultiView was chosen in: robots come and go only with a new model
        # (a spawn or a removal builds it again), so a new model is when to choose again
        self._multiview_model = None
        self._tables: tuple[object, SceneTables] | None = None  # the model's, once a camera needs them

    @staticmethod
    def cameras_of(r: SimRobot) -> list[CameraItem]:
        """The robot's cameras (items of the camera kind), in the robot file's order."""
        return cast("list[CameraItem]", [s for s in r.sensors if s.KIND == "camera"])

    @property
    def multiview_cameras(self) -> int:
        return self._multiview_cameras

    @multiview_cameras.setter
    def multiview_cameras(self, n: int) -> None:
        self._multiview_cameras = max(1, int(n))
        self._multiview = None

    def multiview(self) -> list[tuple[int, str]]:
        """The robot cameras the MultiView shows, tile by tile: the first camera chosen by
        each robot's viewports (else its first camera), robots in the order they were
        spawned, at most ``multiview_cameras`` of them."""
        if self._multiview is not None and self._multiview_model is self.sim.model:
            return self._multiview
        out = []
        for uid in sorted(self.sim.robots):
            r = self.sim.robots[uid]
            cams = [s.name for s in self.cameras_of(r)]
            shown = [v for v in r.viewports if v.lower() in (c.lower() for c in cams)]
            if shown or cams:
                out.append((uid, (shown or cams)[0]))
            if len(out) >= self.multiview_cameras:
                break
        self._multiview, self._multiview_model = out, self.sim.model
        return out

    def set_viewports(self, uid: int, names: list[str | None]) -> list[tuple[str, str]]:
        """SET {Type Viewports}: viewport n shows the robot's camera ``names[n]`` (None or
        ``Disable``: off).  Returns (what viewport n shows: the camera, ``Disabled`` or
        ``None`` for an unknown camera; ``OK``/``Failed``) for each."""
        r = self.sim.robots.get(uid)
        cams = {s.name.lower(): s.name for s in self.cameras_of(r)} if r is not None else {}
        shown, result = [], []
        for name in names:
            if name is None or name.lower() in ("disable", "disabled"):
                result.append(("Disabled", "OK"))
            elif name.lower() in cams:
                shown.append(cams[name.lower()])
                result.append((cams[name.lower()], "OK"))
            else:
                result.append(("None", "Failed"))
        if r is not None:
            r.viewports = tuple(shown)
            self._multiview = None
        return result

    def render_snapshot(self, reuse: Snapshot | None = None) -> Snapshot:
        """A copy of the state for the render thread (taken between steps): ``reuse``, the
        previous snapshot, is refilled when the model is still the same."""
        from usarsim.sim.render import CameraState, Snapshot

        m = self.sim.model
        if reuse is not None and reuse.model is m:
            snap = reuse
            snap.cameras = {}
        else:
            snap = Snapshot(model=m, data=mujoco.MjData(m), time=0.0)
        mujoco.mj_copyData(snap.data, m, self.sim.data)
        snap.time = self.sim.time
        snap.robots = {r.name.lower(): r.uid for r in self.sim.robots.values()}
        snap.bodies = {r.name.lower(): r.handle.body_id for r in self.sim.robots.values()}  # a free camera follows one
        snap.multiview = list(self.multiview())
        beyond_colour = False
        for r in self.sim.robots.values():
            for cam in self.cameras_of(r):
                cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, robotspec.camera_name(r.prefix, cam.name))
                if cid >= 0:
                    picture = getattr(cam, "picture", "colour")
                    beyond_colour = beyond_colour or picture != "colour"
                    snap.cameras[(r.uid, cam.name.lower())] = CameraState(
                        cam_id=cid,
                        fov_rad=float(getattr(cam, "fov_rad", cam.config.def_fov_rad)),
                        omni=cam.OMNI,
                        picture=picture,
                        max_depth_m=float(getattr(cam.config, "max_depth_m", 10.0)),
                        size=(int(cam.config.width_px), int(cam.config.height_px)),
                    )
            # the chase view behind and above the robot (robotspec.CHASE_CAMERA)
            cid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, robotspec.chase_camera_name(r.prefix))
            if cid >= 0:
                snap.cameras.setdefault(
                    (r.uid, robotspec.CHASE_CAMERA.lower()),
                    CameraState(cam_id=cid, fov_rad=robotspec.CHASE_FOV_RAD, omni=False),
                )
        snap.tables = self.scene_tables() if beyond_colour else None
        snap.cold_robots = frozenset(r.uid for r in self.sim.robots.values() if r.battery_empty)
        snap.relays = tuple(tuple(frames.to_mj_vec(r.location).tolist()) for r in self.sim.entities.relays)
        return snap

    def scene_tables(self) -> SceneTables:
        """What thermal and label cameras see of each geom of the model (built once per model)."""
        m = self.sim.model
        if self._tables is None or self._tables[0] is not m:
            wheels = {r.uid: frozenset(w.name for w in r.config.wheels) for r in self.sim.robots.values()}
            self._tables = (m, scene_tables(m, self.sim.world, wheels))
        return self._tables[1]
