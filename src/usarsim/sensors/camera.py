"""Camera items (protocol.md 7.11, 6.7, 5.4): their base and registry, CONF, GEO and zoom.
Pictures come from the image server; over the control port a UT2004 camera sends no
SEN line.  Covers ``Camera`` and the omnidirectional ``OmniCam``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, TypeVar

import mujoco

from usarsim.readings import FieldValue, ItemParams, OperationResult, ZoomResult
from usarsim.sensors.base import ITEMS, Item, ItemConfig
from usarsim.sim.pictures import PICTURES
from usarsim.sim.robotspec import add_camera, add_housing

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView


IC = TypeVar("IC", bound=ItemConfig)
CC = TypeVar("CC", bound="CameraConfig")


class CameraItem(Item[IC]):
    """Base class of every camera plugin: a robot camera sends no SEN line over the control
    port; the image server draws what it sees (protocol.md 7.11, 10) with its current
    horizontal field of view, ``fov_rad``."""

    PERIODIC = False
    OMNI: ClassVar[bool] = False  # True for a camera that sees all around (the image server unrolls it)
    fov_rad: float

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """Its MuJoCo camera, and what other cameras see of it: a small dark case behind the
        lens (60 x 40 x 45 mm, an estimate for a robot's colour camera; none for an all-round
        camera, whose mirror stands free)."""
        add_camera(spec, chassis, self.item, prefix)
        if not self.OMNI:
            add_housing(
                spec, chassis, self.item, prefix, box=(0.04, 0.06, 0.045), rgb=(0.15, 0.15, 0.16), offset=(-0.022, 0, 0)
            )


CAMERAS = ITEMS.new("camera")


@dataclass(frozen=True, kw_only=True)
class CameraConfig(ItemConfig):
    """A camera's settings in a robot file (protocol.md 6.7, 7.11): its default, narrowest and widest horizontal
    field of view (rad), the range ``SET {Opcode Zoom}`` may move in, and the size of its pictures in pixels."""

    # UT CONF example (protocol.md 6.7): CameraDefFov 0.8727, CameraMinFov 0.3491,
    # CameraMaxFov 1.5708 (the zoom range of the UT test UI, 20 to 90 degrees).
    def_fov_rad: float = 0.8727
    min_fov_rad: float = 0.3491
    max_fov_rad: float = 1.5708
    width_px: int = 320  # RoboCup Rescue image tiles were 320 x 240 (protocol.md 7.11)
    height_px: int = 240
    # what its pictures show (usarsim.sim.pictures): colour, depth, thermal or label
    picture: str = "colour"
    max_depth_m: float = 10.0  # a depth picture's reach: farther reads 0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.picture not in PICTURES:
            raise ValueError(f"picture must be one of {', '.join(PICTURES)}, got {self.picture!r}")
        if not (0.0 < self.max_depth_m <= 65.535):
            raise ValueError(f"max_depth_m must be within (0, 65.535] (16-bit millimetres), got {self.max_depth_m}")
        if not (0.0 < self.min_fov_rad <= self.def_fov_rad <= self.max_fov_rad < math.pi * 2):
            raise ValueError(
                f"need 0 < min_fov <= def_fov <= max_fov, got {self.min_fov_rad}, {self.def_fov_rad}, "
                f"{self.max_fov_rad}"
            )
        if self.width_px < 1 or self.height_px < 1:
            raise ValueError("width_px and height_px must be >= 1")


@CAMERAS.register("Camera")
class Camera(CameraItem[CC]):
    """A robot camera: its current field of view changes with ``SET {Opcode Zoom}``."""

    LIVE_CONF = True  # CameraFov follows the zoom
    Config = CameraConfig
    ALIASES = {
        "CameraDefFov": "def_fov_rad",
        "CameraMinFov": "min_fov_rad",
        "CameraMaxFov": "max_fov_rad",
        "FOV": "def_fov_rad",
        "Width": "width_px",
        "Height": "height_px",
    }
    picture: str  # what its pictures show now (SET {Opcode Picture} changes it)

    def reset(self, view: WorldView) -> None:
        self.fov_rad = self.config.def_fov_rad
        self.picture = self.config.picture

    def zoom(self, fov: float) -> tuple[float, bool]:
        """Set the field of view: 0 restores the default, others are clamped to
        [min, max]; not ok when the value was reset or clamped (5.4)."""
        c = self.config
        if fov == 0.0:
            self.fov_rad = c.def_fov_rad
            return self.fov_rad, False
        clamped = min(max(fov, c.min_fov_rad), c.max_fov_rad)
        self.fov_rad = clamped
        return clamped, clamped == fov

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> ZoomResult | OperationResult | None:
        """``{Opcode Zoom}`` (UDK also ``FOV``), Params the new field of view in rad: a
        missing, negative or non-numeric value fails and keeps the current one.  ``{Opcode
        Picture} {Params depth}`` (an extension) makes its pictures colour, depth, thermal or
        label ones: RES OK, or Failed for another word."""
        if opcode.lower() == "picture":
            return self.set_picture(params.text)
        if opcode.lower() not in ("zoom", "fov"):
            return None
        if not params.values or params.values[0] < 0:
            return ZoomResult(((self.name, self.fov_rad, False),), self.TYPE)
        value, ok = self.zoom(params.values[0])
        return ZoomResult(((self.name, value, ok),), self.TYPE)

    def set_picture(self, text: str | None) -> OperationResult:
        word = (text or "").strip().lower()
        word = "colour" if word == "color" else word
        if word not in PICTURES:
            return OperationResult(ok=False)
        self.picture = word
        return OperationResult(ok=True)

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        """USARSim's keys (protocol.md 6.7), then the pinhole's intrinsics at the current zoom
        for a picture of ``width_px`` x ``height_px`` (extensions old clients skip): the focal
        lengths in pixels (square pixels: the same both ways) and the principal point, the
        picture's centre; and, for a camera whose pictures are not colour ones, what they are
        (``{Picture depth}``)."""
        picture = getattr(self, "picture", self.config.picture)
        extra: tuple[tuple[str, FieldValue], ...] = () if picture == "colour" else (("Picture", picture),)
        return (*self.fov_fields(), *self.intrinsics(), *extra)

    def fov_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        return (
            ("CameraDefFov", c.def_fov_rad),
            ("CameraMinFov", c.min_fov_rad),
            ("CameraMaxFov", c.max_fov_rad),
            ("CameraFov", getattr(self, "fov_rad", c.def_fov_rad)),
        )

    def intrinsics(self) -> tuple[tuple[str, FieldValue], ...]:
        c = self.config
        f = focal_length_px(getattr(self, "fov_rad", c.def_fov_rad), c.width_px)
        return (("FocalLength", (f, f)), ("PrincipalPoint", (c.width_px / 2.0, c.height_px / 2.0)))


def focal_length_px(hfov_rad: float, width_px: int) -> float:
    """A pinhole's focal length in pixels for a picture ``width_px`` wide that spans ``hfov_rad``
    (the image server draws with square pixels: the vertical field of view follows from it)."""
    return width_px / 2.0 / math.tan(hfov_rad / 2.0)


@dataclass(frozen=True, kw_only=True)
class OmniCamConfig(CameraConfig):
    """An omnidirectional camera's settings: a field of view fixed all around (360 degrees), which no zoom changes."""

    # An omnidirectional camera sees all around: a fixed 360 degree field of view.
    def_fov_rad: float = 2 * math.pi - 1e-6
    min_fov_rad: float = 2 * math.pi - 1e-6
    max_fov_rad: float = 2 * math.pi - 1e-6


@CAMERAS.register("OmniCam", "OmniCamera")
class OmniCam(Camera[OmniCamConfig]):
    """The omnidirectional camera of the OmniP2AT/OmniP2DX (protocol.md 9): no zoom."""

    OMNI = True

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        """USARSim's keys only: an all-round picture is no pinhole's (no intrinsics)."""
        return self.fov_fields()


@dataclass(frozen=True, kw_only=True)
class DepthCameraConfig(CameraConfig):
    """A depth camera's settings: a camera whose pictures are depths (16-bit millimetres)."""

    picture: str = "depth"


@CAMERAS.register("DepthCamera")
class DepthCamera(Camera[DepthCameraConfig]):
    """A camera whose pictures are depths along its axis in millimetres (usarsim.sim.pictures)."""


@dataclass(frozen=True, kw_only=True)
class ThermalCameraConfig(CameraConfig):
    """A thermal camera's settings: the league's thermal camera, 160 x 120 pixels (FLIR Lepton
    3.5 data sheet: 160 x 120, 57 degrees across), without zoom."""

    picture: str = "thermal"
    width_px: int = 160
    height_px: int = 120
    def_fov_rad: float = 0.9948  # 57 degrees
    min_fov_rad: float = 0.9948
    max_fov_rad: float = 0.9948


@CAMERAS.register("ThermalCamera")
class ThermalCamera(Camera[ThermalCameraConfig]):
    """A camera whose pictures are temperatures as 8-bit intensity (usarsim.sim.pictures)."""


@dataclass(frozen=True, kw_only=True)
class LabelCameraConfig(CameraConfig):
    """A label camera's settings: a camera whose pictures give each pixel's class and instance."""

    picture: str = "label"


@CAMERAS.register("LabelCamera")
class LabelCamera(Camera[LabelCameraConfig]):
    """The ground truth of a picture: each pixel's class and instance (usarsim.sim.pictures)."""
