"""The optional parts of usarsim and the packages each needs.

The simulator itself (``usarsim serve``, the clients, the environments) needs only the core
install.  Sweeps and their reports (Ray, Arrow, matplotlib) and recordings (Foxglove's SDK, the
MCAP reader) and the ROS 2 bridge (rclpy) are extras: ``pip install 'usarsim[sweep]'``,
``'usarsim[record]'``, ``'usarsim[ros2]'`` or ``'usarsim[all]'``.  A command that needs a
missing one says so in one line.
"""

from __future__ import annotations

import importlib.util

from usarsim.errors import UsarsimError

# extra -> the modules it installs (pyproject.toml [project.optional-dependencies])
EXTRAS: dict[str, tuple[str, ...]] = {
    "sweep": ("ray", "pyarrow", "matplotlib"),
    "record": ("foxglove", "mcap", "zstandard"),
    "ros2": ("rclpy", "sensor_msgs", "nav_msgs", "rosgraph_msgs", "std_srvs", "visualization_msgs", "rosbags"),
}


class MissingExtraError(UsarsimError):
    """A command needs an extra that is not installed."""


def missing(extra: str) -> list[str]:
    """The modules of ``extra`` that cannot be imported here."""
    return [m for m in EXTRAS[extra] if importlib.util.find_spec(m) is None]


def require(extra: str, what: str) -> None:
    """Raise MissingExtraError, naming the extra and how to install it, when ``what`` (the
    feature asked for, e.g. "usarsim sweep") cannot run for want of one of its modules."""
    absent = missing(extra)
    if absent:
        raise MissingExtraError(
            f"{what} needs the '{extra}' extra ({', '.join(absent)} not installed): "
            f"pip install 'usarsim[{extra}]' (in a clone: pip install -e '.[{extra}]')"
        )
