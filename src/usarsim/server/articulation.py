"""A control session's articulated parts: mission packages (MISPKG, MISSTA's GEO and CONF),
the UDK's actuator API (ACT, GEO and CONF {Type Actuator}), the legacy CAMERA command and
MULTIDRIVE.

:class:`Articulation` is a part of :class:`usarsim.server.session.Session`: it uses the
session's ``robot``, ``facade``, ``uid``, ``actuator_api``, ``log_once``, ``_alive`` and
``_answered``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

from usarsim.controls import JointOrder
from usarsim.protocol import commands as C
from usarsim.protocol import messages as M
from usarsim.readings import ItemParams
from usarsim.sim.api import when_done

if TYPE_CHECKING:
    from usarsim.config.robot import Link, MissionPackage, RobotConfig
    from usarsim.sim.api import Facade


class Articulation:
    """The session's handlers of articulated parts (see the module's description)."""

    if TYPE_CHECKING:  # what the session gives
        robot: RobotConfig | None
        uid: int
        actuator_api: bool

        @property
        def facade(self) -> Facade: ...
        def log_once(self, kind: str, msg: str, *args: Any, level: int = logging.WARNING) -> None: ...
        def _alive(self) -> bool: ...
        def _answered(
            self,
            command: str,
            then: Callable[[Any], None] | None = None,
            refused: Callable[[BaseException], None] | None = None,
        ) -> Callable[..., None]: ...

    def on_multidrive(self, cmd: C.MultiDrive) -> None:
        """``MULTIDRIVE {Joint angle} ...``: absolute angles (protocol.md 5.3g)."""
        if self._alive() and cmd.joints:
            self.facade.drive_joints(self.uid, [JointOrder(name, value, 0) for name, value in cmd.joints])

    def on_mispkg(self, cmd: C.MisPkg) -> None:
        """``MISPKG {Name P} {Link n} {Value v} {Order o} ...`` and the older
        ``{Rotation roll,tilt,pan} {Order 0|1}`` (tilt to link 2, pan to link 1; protocol.md 5.6)."""
        if not self._alive():
            return
        pkg = self.robot.package(cmd.name or "") if self.robot is not None else None
        if pkg is None:
            self.log_once(
                f"mispkg:{cmd.name}", "MISPKG for an unknown mission package %r; ignored", cmd.name, level=logging.INFO
            )
            return
        commands = []
        for lc in cmd.links:
            if not 1 <= lc.link <= len(pkg.links):
                self.log_once(f"mispkg-link:{lc.link}", "MISPKG %s has no link %d; ignored", pkg.name, lc.link)
                continue
            commands.append(JointOrder(pkg.links[lc.link - 1], lc.value, lc.order))
        if cmd.rotation is not None:
            order = cmd.order or 0
            _, tilt, pan = cmd.rotation
            if len(pkg.links) >= 1:
                commands.append(JointOrder(pkg.links[0], pan, order))
            if len(pkg.links) >= 2:
                commands.append(JointOrder(pkg.links[1], tilt, order))
        if commands:
            self.facade.drive_joints(self.uid, commands)

    def on_camera(self, cmd: C.Camera) -> None:
        """Legacy ``CAMERA {Rotation r,p,y} {Zoom fov}`` (protocol.md 5.7): the pan-tilt and the zoom."""
        if not self._alive():
            return
        pkg = self.robot.package("CameraPanTilt") if self.robot is not None else None
        if cmd.rotation is not None and pkg is not None and len(pkg.links) >= 2:
            _, tilt, pan = cmd.rotation
            self.facade.drive_joints(self.uid, [JointOrder(pkg.links[0], pan, 0), JointOrder(pkg.links[1], tilt, 0)])
        if cmd.zoom is not None:
            zoomed = self.facade.operate(self.uid, "Camera", None, "Zoom", ItemParams(values=(cmd.zoom,)))
            when_done(zoomed, self._answered("CAMERA"))

    def on_act(self, cmd: C.Act) -> None:
        """``ACT {Name arm} {Link k} {Value v} [{Order o}] ...`` and ``ACT {Name arm} {Gripper 1|0}``
        (UDK actuator API, protocol.md 5.8): the links of the mission package named, counted
        from 0; the gripper whose fingers are on it (or the robot's only gripper).  No reply;
        a gripper answers as ``SET {Type Gripper}`` does (RES, then EFF)."""
        if not self._alive():
            return
        self.actuator_api = True
        assert self.robot is not None
        packages = self.robot.mission_packages
        pkg = self.robot.package(cmd.name) if cmd.name else (packages[0] if len(packages) == 1 else None)
        if pkg is None:
            known = ", ".join(p.name for p in packages) or "none"
            self.log_once(
                f"act:{cmd.name}",
                "ACT for an unknown actuator %r (this robot's: %s); ignored",
                cmd.name,
                known,
                level=logging.INFO,
            )
            return
        orders = []
        for lc in cmd.links:
            # ACT counts links from 0, as the UDK server did (it passed k straight to the
            # actuator's link array): {Link 0} is the link CONF, GEO and ASTA call Link 1
            if not 0 <= lc.link < len(pkg.links):
                self.log_once(
                    f"act-link:{lc.link}",
                    "ACT %s has no link %d (ACT counts links from 0: 0..%d); ignored",
                    pkg.name,
                    lc.link,
                    len(pkg.links) - 1,
                )
                continue
            orders.append(JointOrder(pkg.links[lc.link], lc.value, lc.order))
        if orders:
            self.facade.drive_joints(self.uid, orders)
        if cmd.gripper is not None:
            gripper = self._gripper_of(pkg)
            if gripper is None:
                # answered as SET {Type Gripper} on a gripper the robot does not have: RES Failed
                self.log_once(
                    "act-gripper",
                    "ACT {Gripper}: actuator %s has no gripper; answered Failed",
                    pkg.name,
                    level=logging.INFO,
                )
            gripped = self.facade.operate(
                self.uid, "Gripper", gripper or pkg.name, "Close" if cmd.gripper else "Open", ItemParams()
            )
            when_done(gripped, self._answered("ACT"))
        if cmd.sequence is not None:
            self.log_once(
                "act-sequence", "ACT {Sequence %d}: no stored sequences; ignored", cmd.sequence, level=logging.INFO
            )

    def _gripper_of(self, pkg: MissionPackage) -> str | None:
        """The gripper whose fingers are links of ``pkg``, else the robot's only gripper."""
        assert self.robot is not None
        grippers = [it for it in self.robot.items if it.item_type.lower() == "gripper"]
        for it in grippers:
            fingers = it.params.get("fingers") or it.params.get("Fingers") or ()
            if any(f in pkg.links for f in fingers):
                return it.name
        return grippers[0].name if len(grippers) == 1 else None

    def _package_links(self, p: MissionPackage) -> Iterator[Link]:
        """The robot's links of mission package ``p``, in its order (each one a link of the
        robot: the robot file is checked when it is read)."""
        assert self.robot is not None
        for n in p.links:
            ln = self.robot.link(n)
            assert ln is not None
            yield ln

    def _actuator_configuration(self, pkgs: list[MissionPackage]) -> M.ActuatorConfiguration:
        """CONF {Type Actuator}: each link's joint type, torque and value range (a joint
        without limits turns through -pi..pi, the range its Value is reported in)."""
        out = []
        for p in pkgs:
            links = []
            for i, ln in enumerate(self._package_links(p)):
                lo, hi = (ln.min_range, ln.max_range) if ln.limited else (-math.pi, math.pi)
                links.append(
                    M.ActuatorLinkConfiguration(
                        link=i + 1,
                        joint_type="Revolute" if ln.joint == "revolute" else "Prismatic",
                        max_torque=ln.max_torque,
                        min_value=lo,
                        max_value=hi,
                    )
                )
            out.append(M.ActuatorConfig(name=p.name, links=tuple(links)))
        return M.ActuatorConfiguration(actuators=tuple(out))

    def _actuator_geometry(self, pkgs: list[MissionPackage]) -> M.ActuatorGeometry:
        """GEO {Type Actuator}: the actuator's base at the robot's origin (mounted on the
        robot, named by its class), each link's joint pose relative to its parent link;
        ``Parent`` as the UDK printed it, the parent's index plus one (0: the base)."""
        robot = self.robot
        assert robot is not None
        out = []
        for p in pkgs:
            links = [
                M.ActuatorLinkGeometry(
                    link=f.link, parent=max(f.parent, 0), location=f.location, orientation=f.orientation
                )
                for f in self.facade.package_frames(robot, p)
            ]
            out.append(
                M.ActuatorPose(
                    name=p.name,
                    location=(0.0, 0.0, 0.0),
                    orientation=(0.0, 0.0, 0.0),
                    mount=robot.class_name,
                    links=tuple(links),
                )
            )
        return M.ActuatorGeometry(actuators=tuple(out))

    def _packages(self, name: str | None) -> list[MissionPackage]:
        assert self.robot is not None
        return [p for p in self.robot.mission_packages if not name or p.name.lower() == name.lower()]

    def package_geometry(
        self, item_type: str, name: str | None
    ) -> M.EmptyGeometry | M.ActuatorGeometry | M.MisPkgGeometry:
        """GEO {Type MisPkg} or {Type Actuator} (the latter turns the actuator API on)."""
        actuator = item_type.lower() == "actuator"
        if actuator:
            self.actuator_api = True
        pkgs = self._packages(name)
        if not pkgs:
            return M.EmptyGeometry(item_type=item_type, name=name)
        if actuator:
            return self._actuator_geometry(pkgs)
        robot = self.robot
        assert robot is not None
        return M.MisPkgGeometry(
            packages=tuple(
                M.PackageGeometry(
                    name=p.name,
                    links=tuple(
                        M.LinkGeometry(
                            link=f.link, parent_link=f.parent, location=f.location, orientation=f.orientation
                        )
                        for f in self.facade.package_frames(robot, p)
                    ),
                )
                for p in pkgs
            )
        )

    def package_configuration(
        self, item_type: str, name: str | None
    ) -> M.EmptyConfiguration | M.ActuatorConfiguration | M.MisPkgConfiguration:
        """CONF {Type MisPkg} or {Type Actuator} (the latter turns the actuator API on)."""
        if item_type.lower() == "actuator":
            self.actuator_api = True
        pkgs = self._packages(name)
        if not pkgs:
            return M.EmptyConfiguration(item_type=item_type, name=name)
        if item_type.lower() == "actuator":
            return self._actuator_configuration(pkgs)
        return M.MisPkgConfiguration(
            packages=tuple(
                M.PackageConfiguration(
                    name=p.name,
                    links=tuple(
                        M.LinkConfiguration(
                            link=i + 1,
                            joint_type="Revolute" if ln.joint == "revolute" else "Prismatic",
                            max_speed=ln.max_speed,
                            max_torque=ln.max_torque,
                            min_range=ln.min_range,
                            max_range=ln.max_range,
                        )
                        for i, ln in enumerate(self._package_links(p))
                    ),
                )
                for p in pkgs
            )
        )
