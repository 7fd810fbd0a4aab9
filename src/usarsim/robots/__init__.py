"""Drive models (see :mod:`usarsim.robots.base`); importing this package registers every
built-in drive: skid (and tracked), ackermann, holonomic, aerial, legged, nautical, static."""

from usarsim.robots import ackermann, aerial, holonomic, legged, nautical, skid, static  # noqa: F401  (registration)
from usarsim.robots.base import DRIVES, DriveModel, drive_class, make_drive

__all__ = ["DRIVES", "DriveModel", "drive_class", "make_drive"]
