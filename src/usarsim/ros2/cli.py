"""``usarsim ros2``: the ROS 2 bridge's command line (docs/ros2.md)."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import time
from pathlib import Path
from typing import Any

log = logging.getLogger("usarsim.ros2")

OTHER_BRIDGE_WAIT_S = 3.0  # listen this long for another /clock publisher (discovery on a busy machine)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "ros2",
        help="put robots of a running simulator on the ROS 2 graph (Jazzy; pip install 'usarsim[ros2]')",
        description="Connect to a running simulator (usarsim serve, or any USARSim server) as an ordinary "
        "protocol client, spawn the robots given, and bridge each to ROS 2 (Jazzy's wire format) in "
        "its own namespace: scan, sonar/<name>, odom, ground_truth, imu, gps/fix, victims, battery "
        "published; cmd_vel (geometry_msgs/Twist) and cmd_vel_stamped (TwistStamped) taken; /clock "
        "in simulated time; /tf (ROBOT/odom -> ROBOT/base_link) and /tf_static (ROBOT/base_link "
        "-> every sensor). With a lock-step simulator (--lockstep) the bridge drives its clock "
        "and offers /usarsim/pause, /usarsim/resume and /usarsim/step (std_srvs/Trigger). Nodes "
        "on this machine only, unless ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET; domain from "
        "ROS_DOMAIN_ID or --domain. Stop with Ctrl-C. docs/ros2.md has the details.",
        epilog="example: usarsim ros2 --robot P2AT@PlayerStart1:robot1 --robot AirRobot@PlayerStart2:drone",
    )
    p.add_argument("--host", default="127.0.0.1", help="the simulator's host (default: %(default)s)")
    p.add_argument("--port", type=int, default=3000, help="the simulator's robot port (default: %(default)s)")
    p.add_argument(
        "--robot",
        action="append",
        default=[],
        metavar="CLASS[@START][:NAME]",
        help="a robot to spawn and bridge, e.g. P2AT@PlayerStart1:robot1 (repeat for more; NAME "
        "is its ROS namespace, default robot1, robot2, ...; START a start pose of the world, "
        "default the first)",
    )
    p.add_argument(
        "--robots",
        metavar="FILE.yaml",
        default=None,
        help="robots from a YAML list of {class, start, name} or {class, location: [x, y, z], yaw, name} "
        "(besides any --robot)",
    )
    p.add_argument(
        "--image-port",
        type=int,
        default=None,
        metavar="PORT",
        help="the simulator's image server, for the camera topics (default: the robot port + 2003, 5003 beside 3000)",
    )
    p.add_argument(
        "--camera-hz",
        type=float,
        default=5.0,
        metavar="HZ",
        help="pictures a simulated second of each camera that has a subscriber (default: %(default)s; "
        "0: no camera topics)",
    )
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="the simulator runs in lock-step (usarsim serve --lockstep): the bridge steps it",
    )
    p.add_argument(
        "--period",
        type=_positive,
        default=0.1,
        metavar="S",
        help="lock-step: the simulated seconds of one step, and of /usarsim/step (default: %(default)s)",
    )
    p.add_argument(
        "--rtf",
        type=float,
        default=1.0,
        metavar="X",
        help="lock-step: simulated seconds per wall second; 0 for as fast as it goes (default: %(default)s)",
    )
    p.add_argument(
        "--domain",
        type=int,
        default=None,
        metavar="N",
        help="ROS_DOMAIN_ID, 0 to 232 (default: the environment's, else 0)",
    )
    p.add_argument(
        "--no-frame-prefix",
        action="store_true",
        help="frames without the robot's name (odom, base_link): for a single robot and a stack "
        "configured with ROS's default frame names",
    )
    p.add_argument(
        "--map-tf",
        action="store_true",
        help="also publish map -> ROBOT/odom on /tf from ground truth (the robot's odometry origin in "
        "the world), for a stack that wants a map frame without a SLAM node",
    )
    p.add_argument(
        "--stamped",
        action="store_true",
        help="cmd_vel is geometry_msgs/TwistStamped (Nav2 with enable_stamped_cmd_vel) and cmd_vel_unstamped a Twist",
    )
    p.add_argument(
        "--bag",
        metavar="DIR",
        default=None,
        help="also record every published message into a new rosbag2 folder DIR (MCAP; ros2 bag play DIR)",
    )
    p.add_argument(
        "--duration",
        type=_positive,
        default=None,
        metavar="S",
        help="stop after S simulated seconds (default: run until Ctrl-C)",
    )
    p.add_argument(
        "--timeout",
        type=_positive,
        default=10.0,
        metavar="S",
        help="how long to wait for the simulator's replies (default: %(default)s)",
    )
    p.set_defaults(handler=cmd_ros2)
    return p


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not v > 0:
        raise argparse.ArgumentTypeError(f"{text} must be more than 0")
    return v


def robot_specs(args: argparse.Namespace) -> list[Any]:
    from .robot import RobotSpec

    specs = [RobotSpec.parse(text) for text in args.robot]
    if args.robots:
        import yaml  # type: ignore[import-untyped]  # PyYAML ships no type information (no types-PyYAML here)

        path = Path(args.robots)
        try:
            data = yaml.safe_load(path.read_text())
        except (OSError, yaml.YAMLError) as exc:
            raise ValueError(f"--robots {path}: {exc}") from None
        if not isinstance(data, list):
            raise ValueError(
                f"--robots {path}: a YAML list of robots ({{class: P2AT, start: PlayerStart1, name: robot1}}) expected"
            )
        for i, entry in enumerate(data):
            if not isinstance(entry, dict) or not isinstance(entry.get("class"), str):
                raise ValueError(f"--robots {path}: robot {i + 1} needs a 'class' (e.g. class: P2AT)")
            loc = entry.get("location")
            specs.append(
                RobotSpec(
                    entry["class"],
                    entry.get("start"),
                    entry.get("name"),
                    # the file's numbers as written (x, y, z by --robots' help): their count is not checked here
                    None if loc is None else tuple(float(v) for v in loc),  # type: ignore[arg-type]
                    float(entry.get("yaw", 0.0)),
                )
            )
    names = [s.name for s in specs if s.name]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"two robots named {', '.join(dup)}: each needs its own namespace")
    if not specs:
        raise ValueError(
            "no robot to bridge: give --robot CLASS@START:NAME (e.g. --robot P2AT@PlayerStart1:robot1) "
            "or --robots FILE.yaml"
        )
    return specs


def cmd_ros2(args: argparse.Namespace) -> int:
    from usarsim.errors import UsarsimError

    from .setup import DISTRIBUTION, prepare
    from .tf2_build import ensure_tf2_msgs

    try:
        specs = robot_specs(args)
        domain = prepare(args.domain)
        ensure_tf2_msgs()
    except (ValueError, UsarsimError) as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    from usarsim.client.blocking import World
    from usarsim.client.core import ClientError

    from .bridge import Bridge

    try:
        world = World(args.host, args.port, lockstep=args.lockstep, image_port=args.image_port, timeout=args.timeout)
    except ClientError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    bridge = None
    try:
        bridge = Bridge(
            world,
            period=args.period,
            rtf=args.rtf,
            frame_prefix=not args.no_frame_prefix,
            stamped=args.stamped,
            bag=args.bag,
            camera_hz=max(0.0, args.camera_hz),
            map_tf=args.map_tf,
        )
        other = _other_clock_publisher(bridge)
        if other:
            print(
                f"usarsim: error: {other} publishes /clock on ROS_DOMAIN_ID {domain} already (another bridge?): "
                f"give this one another domain (--domain N or ROS_DOMAIN_ID)",
                file=sys.stderr,
            )
            return 1
        added = 0
        for spec in specs:
            try:
                bridge.add_robot(spec)
                added += 1
            except ClientError as exc:
                log.error("robot %s not bridged: %s", spec.name or spec.class_name, exc)
        if not added:
            print("usarsim: error: no robot could be spawned", file=sys.stderr)
            return 1
        stop = bridge.stop
        import faulthandler

        faulthandler.register(signal.SIGUSR1, all_threads=True)  # kill -USR1: where every thread is
        signal.signal(signal.SIGINT, lambda *_: stop())
        signal.signal(signal.SIGTERM, lambda *_: stop())

        def ready() -> None:
            names = " ".join(f"/{n}" for n in bridge.robots)
            print(
                f"usarsim ros2: {added} robot(s) on ROS_DOMAIN_ID {domain} (ROS 2 {DISTRIBUTION}): {names}", flush=True
            )

        bridge.run(args.duration, ready)
        return 0
    except ClientError as exc:
        print(f"usarsim: error: the simulator at {args.host}:{args.port}: {exc}", file=sys.stderr)
        return 1
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    finally:
        if bridge is not None:
            bridge.close()
        world.close()


def _other_clock_publisher(bridge: Any) -> str | None:
    """Another /clock publisher on this domain (besides this bridge's own), heard within
    OTHER_BRIDGE_WAIT_S: its node, as the graph names it."""
    deadline = time.monotonic() + OTHER_BRIDGE_WAIT_S
    while time.monotonic() < deadline:
        if bridge.node.count_publishers("/clock") > 1:
            own = bridge.node.get_name()
            names = [i.node_name for i in bridge.node.get_publishers_info_by_topic("/clock")]
            other = next((n for n in names if n != own), own)  # two bridges share a node name
            return f"node {other}"
        time.sleep(0.05)
    return None
