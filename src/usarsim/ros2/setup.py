"""What a process must set before it loads rclpy: the discovery range, the domain, the checks
that the ROS 2 extra is there, and tf2_msgs.

ROS 2 nodes find each other by multicast on the local network unless told otherwise.  The
simulator's own listeners answer on this machine only unless ``--host`` says otherwise, and the
bridge does the same: ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is ``LOCALHOST`` unless the environment
sets it (``SUBNET`` lets a ROS 2 machine of the network see the robots)."""

from __future__ import annotations

import os

from usarsim.errors import UsarsimError
from usarsim.extras import require

DISTRIBUTION = "jazzy"  # the wire format spoken: ROS 2 Jazzy Jalisco, the LTS release (May 2024 to May 2029)
DOMAIN_ID_MAX = 232  # Fast DDS derives its ports from the domain: 0..232 fit (ROS 2 docs, "The ROS_DOMAIN_ID")


class Ros2SetupError(UsarsimError):
    """ROS 2 cannot start here (extra missing, a bad domain, tf2_msgs unavailable)."""


def prepare(domain_id: int | None = None, what: str = "usarsim ros2") -> int:
    """Set the environment rclpy reads (call before the first ``import rclpy``); returns the
    domain id in use."""
    require("ros2", what)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if domain_id is None:
        text = os.environ.get("ROS_DOMAIN_ID", "0") or "0"
        try:
            domain_id = int(text)
        except ValueError:
            raise Ros2SetupError(f"ROS_DOMAIN_ID={text!r} is not a number (0 to {DOMAIN_ID_MAX})") from None
    if not 0 <= domain_id <= DOMAIN_ID_MAX:
        raise Ros2SetupError(f"ROS domain {domain_id} is out of range: 0 to {DOMAIN_ID_MAX}")
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    rmw = os.environ.get("RMW_IMPLEMENTATION", "")
    if rmw and rmw != "rmw_fastrtps_cpp":
        raise Ros2SetupError(
            f"RMW_IMPLEMENTATION={rmw}: the ROS 2 wheels carry Fast DDS only (rmw_fastrtps_cpp); unset it"
        )
    return domain_id
