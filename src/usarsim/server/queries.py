"""A control session's queries and settings: GETSTARTPOSES and the path nodes, GETGEO and
GETCONF of the robot and its items, and SET (joints, camera bindings, viewports, operations
on mounted items; protocol.md 5.4, 5.7, 5.8).

:class:`Queries` is a part of :class:`usarsim.server.session.Session`: it uses the session's
``ctx``, ``robot``, ``uid``, ``has_robot``, ``facade``, ``send``, ``refuse``, ``log_once`` and
``_answered``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from usarsim.controls import JointOrder
from usarsim.protocol import commands as C
from usarsim.protocol import messages as M
from usarsim.readings import ItemParams
from usarsim.sim.api import when_done

if TYPE_CHECKING:
    from usarsim.config.robot import RobotConfig
    from usarsim.server.session import SessionContext
    from usarsim.sim.api import Facade

log = logging.getLogger("usarsim.server")

NO_ROBOT = "no robot on this connection: send INIT first"

# SET {Type Joint} opcodes (protocol.md 5.4) -> joint orders (5.3f)
JOINT_OPCODES = {
    "angle": 0,
    "0": 0,
    "velocity": 1,
    "1": 1,
    "torque": 2,
    "2": 2,
    "brake": 3,
    "3": 3,
    "relangle": 10,
    "10": 10,
    "relvelocity": 11,
    "11": 11,
    "reltorque": 12,
    "12": 12,
}


class Queries:
    """The session's handlers of queries and settings (see the module's description)."""

    if TYPE_CHECKING:  # what the session (and its articulated parts) give
        ctx: SessionContext
        robot: RobotConfig | None
        uid: int

        @property
        def has_robot(self) -> bool: ...
        @property
        def facade(self) -> Facade: ...

        def send(self, msg: Any) -> None: ...
        def refuse(self, command: str, kind: str, reason: str, level: int = logging.WARNING) -> None: ...
        def log_once(self, kind: str, msg: str, *args: Any, level: int = logging.WARNING) -> None: ...
        def _answered(
            self,
            command: str,
            then: Callable[[Any], None] | None = None,
            refused: Callable[[BaseException], None] | None = None,
        ) -> Callable[..., None]: ...
        def package_geometry(self, item_type: str, name: str | None) -> Any: ...
        def package_configuration(self, item_type: str, name: str | None) -> Any: ...

    def on_get_start_poses(self, cmd: C.GetStartPoses) -> None:
        poses = tuple(
            M.StartPose(name=p.name, location=p.location, rotation=p.rotation) for p in self.facade.start_poses
        )
        self.send(M.StartPoses(poses=poses))

    def on_get_path_nodes(self, cmd: C.GetPathNodes) -> None:
        """``GETPATHNODES`` (UDK, protocol.md 5.8): the world's path nodes, laid out as start
        poses are (``NFO {PathNodes 0}`` for a world that has none)."""
        self.send(
            M.PathNodes(
                nodes=tuple(
                    M.StartPose(name=p.name, location=p.location, rotation=p.rotation)
                    for p in self.facade.world.path_nodes
                )
            )
        )

    def on_get_closest_path_node(self, cmd: C.GetClosestPathNode) -> None:
        """``GETCLOSESTPATHNODE {Location x,y,z}`` (UDK): ``NFO {Pathnode name} {Location x,y,z}``
        of the path node nearest to it."""
        nodes = self.facade.world.path_nodes
        where = cmd.location
        if where is None:
            self.refuse("GETCLOSESTPATHNODE", "malformed", "GETCLOSESTPATHNODE needs a {Location x,y,z}")
            return
        if not nodes:
            self.refuse(
                "GETCLOSESTPATHNODE",
                "no-path-nodes",
                f"world {self.facade.world_name} has no path nodes (a world file lists them under path_nodes)",
                level=logging.INFO,
            )
            return
        nearest = min(nodes, key=lambda p: math.dist(p.location, where))
        self.send(M.ClosestPathNode(name=nearest.name, location=nearest.location))

    def _items(self, item_type: str, name: str | None):
        assert self.robot is not None
        t = item_type.lower()
        canonical = self.facade.canonical_item_type(item_type)
        found = [
            d
            for d in self.facade.describe(self.robot)
            if d.item_type.lower() in (t, canonical.lower()) and (not name or d.name.lower() == name.lower())
        ]
        return found

    def on_get_geo(self, cmd: C.GetGeo) -> None:
        if self.robot is None:
            self.refuse("GETGEO", "before-init-query", NO_ROBOT, level=logging.INFO)
            return
        if not cmd.type:
            self.send(M.EmptyGeometry(item_type="", name=cmd.name))
            return
        if cmd.type.lower() == "robot":
            n = self.facade.robot_numbers(self.robot)
            self.send(
                M.RobotGeometry(
                    vehicle_type=n.vehicle_type,
                    class_name=n.class_name,
                    dimensions=n.dimensions,
                    cog=n.cog,
                    wheel_radius=n.wheel_radius,
                    wheel_separation=n.wheel_separation,
                    wheel_base=n.wheel_base,
                )
            )
            return
        if cmd.type.lower() in ("actuator", "mispkg"):
            self.send(self.package_geometry(cmd.type, cmd.name))
            return
        items = self._items(cmd.type, cmd.name)
        if not items:
            self.send(M.EmptyGeometry(item_type=cmd.type, name=cmd.name))
            return
        self.send(
            M.ItemGeometry(
                item_type=items[0].item_type,
                items=tuple(
                    M.ItemPose(name=d.name, location=d.location, orientation=d.orientation, mount=d.mount)
                    for d in items
                ),
            )
        )

    def on_get_conf(self, cmd: C.GetConf) -> None:
        if self.robot is None:
            self.refuse("GETCONF", "before-init-query", NO_ROBOT, level=logging.INFO)
            return
        if not cmd.type:
            self.send(M.EmptyConfiguration(item_type="", name=cmd.name))
            return
        if cmd.type.lower() == "robot":
            n = self.facade.robot_numbers(self.robot)
            self.send(
                M.RobotConfiguration(
                    vehicle_type=n.vehicle_type,
                    class_name=n.class_name,
                    steering_type=n.steering_type,
                    mass_kg=n.mass_kg,
                    max_speed=n.max_speed,
                    max_torque=n.max_torque,
                    max_front_steer=n.max_front_steer,
                    max_rear_steer=n.max_rear_steer,
                )
            )
            return
        if cmd.type.lower() in ("actuator", "mispkg"):
            self.send(self.package_configuration(cmd.type, cmd.name))
            return
        items = self._items(cmd.type, cmd.name)
        if not items:
            self.send(M.EmptyConfiguration(item_type=cmd.type, name=cmd.name))
            return
        confs = []
        for d in items:
            fields = self.facade.live_conf(self.uid, d.item_type, d.name) or d.conf
            confs.append(M.ItemConf(name=d.name, fields=tuple(fields)))
        self.send(M.ItemConfiguration(item_type=items[0].item_type, items=tuple(confs)))

    def on_set(self, cmd: C.Set) -> None:
        """``SET`` (protocol.md 5.4): a joint order, a camera binding, the viewports, or an
        operation on a mounted item, its Params handed on typed (their numbers, and the text
        as sent for items whose parameters are text)."""
        if not self.has_robot:
            self.refuse("SET", "before-init-query", NO_ROBOT, level=logging.INFO)
            return
        t = (cmd.type or "").lower()
        if t == "joint":
            order = JOINT_OPCODES.get((cmd.opcode or "0").lower())
            values = cmd.values
            if order is None or not values or not cmd.name:
                self.log_once(
                    "set-joint",
                    "SET {Type Joint} needs a Name, an Opcode (Angle, Velocity, Torque, "
                    "RelAngle, RelVelocity, RelTorque or 0/1/2/10/11/12) and a Params value",
                )
                return
            self.facade.drive_joints(self.uid, [JointOrder(cmd.name, values[0], order)])
            return
        if t == "camera" and (cmd.client is not None or cmd.robot is not None):
            self.on_bind_camera(cmd)
            return
        if t == "viewports":
            self.on_viewports(cmd)
            return
        done = self.facade.operate(
            self.uid, cmd.type, cmd.name, cmd.opcode, ItemParams(values=cmd.values, text=cmd.params)
        )
        when_done(done, self._answered("SET"))

    def on_bind_camera(self, cmd: C.Set) -> None:
        """``SET {Type Camera} {Robot r} {Name cam} {Client ip}``: the image server shows that
        robot camera to viewers at ``ip`` (or ``ip:port``); without Robot, releases them.
        No reply (protocol.md 5.4)."""
        bindings = self.ctx.camera_bindings
        client = (cmd.client or "").strip()
        if not client:
            self.log_once("bind", "SET {Type Camera} {Robot r} {Name cam} needs a {Client ip}; ignored")
            return
        if not cmd.robot:
            bindings.release(client)
            log.info("%s: image viewers at %s see the MultiView again", self.ctx.peer, client)
            return
        camera = cmd.name or "Camera"
        if not bindings.bind(client, cmd.robot, camera):
            self.log_once(
                "bind-full",
                "SET {Type Camera}: viewer address %.80r refused (longer than %d characters, "
                "or %d addresses bound already); ignored",
                client,
                bindings.MAX_ADDRESS,
                bindings.MAX_BINDINGS,
            )
            return
        log.info("%s: image viewers at %s see camera %s of robot %s", self.ctx.peer, client, camera, cmd.robot)

    def on_viewports(self, cmd: C.Set) -> None:
        """``SET {Type Viewports} {Config SingleView|QuadView} {Viewport1 cam} ...``: which of
        this robot's cameras are shown (the first in the MultiView); RES per viewport."""
        config = cmd.config or "SingleView"
        known = {"singleview": "SingleView", "0": "SingleView", "quadview": "QuadView", "1": "QuadView"}
        cfg = known.get(config.lower())
        count = 4 if cfg == "QuadView" else 1
        names: list[str | None] = [None] * max(count, max((i for i, _ in cmd.viewports), default=0))
        for index, cam in cmd.viewports:
            if 1 <= index <= len(names):
                names[index - 1] = cam

        def answer(result) -> None:
            time_s, states = result
            self.send(
                M.ViewportsResult(
                    time=time_s,
                    config=cfg or config,
                    config_status="OK" if cfg else "Failed",
                    viewports=tuple(
                        M.ViewportState(index=i + 1, camera=c, status=st) for i, (c, st) in enumerate(states)
                    ),
                )
            )

        when_done(self.facade.set_viewports(self.uid, names), self._answered("SET", answer))
