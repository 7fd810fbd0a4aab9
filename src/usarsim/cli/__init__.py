"""The ``usarsim`` command: argument parsing and wiring only."""

from __future__ import annotations

import faulthandler
import logging
import os
import sys

from usarsim.cli.commands import (
    check_robot_items,
    cmd_bench,
    cmd_replay,
    cmd_robots,
    cmd_validate,
    cmd_worlds,
    run_env_bench,
    validate_target,
)
from usarsim.cli.options import (
    DEFAULT_PORTS,
    FOXGLOVE_DEFAULT,
    FOXGLOVE_PORT,
    resolve_foxglove_port,
    resolve_ports,
)
from usarsim.cli.parser import build_parser
from usarsim.cli.serve import cmd_serve, run_options

__all__ = [
    "DEFAULT_PORTS",
    "FOXGLOVE_DEFAULT",
    "FOXGLOVE_PORT",
    "build_parser",
    "check_robot_items",
    "cmd_bench",
    "cmd_replay",
    "cmd_robots",
    "cmd_serve",
    "cmd_validate",
    "cmd_worlds",
    "main",
    "resolve_foxglove_port",
    "resolve_ports",
    "run_env_bench",
    "run_options",
    "validate_target",
]


def _setup_logging(verbose: int) -> None:
    level = logging.WARNING if verbose == 0 else logging.INFO if verbose == 1 else logging.DEBUG
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    # a crash in native code (MuJoCo, the GL driver, numba's kernels) prints the Python side of
    # every thread's stack on stderr instead of dying silently
    if not faulthandler.is_enabled():
        faulthandler.enable()
    parser = build_parser()
    args = parser.parse_args(argv)
    args.verbose += getattr(args, "verbose_after", 0)  # 'usarsim -v serve' and 'usarsim serve -v' alike
    _setup_logging(args.verbose)
    if args.command is None:
        parser.print_help()
        return 2
    from usarsim.extras import MissingExtraError, require

    try:
        if args.command in ("sweep", "report", "compete"):
            require("sweep", f"usarsim {args.command}")
        elif args.command == "replay":
            require("record", "usarsim replay")
        elif args.command == "ros2":
            require("ros2", "usarsim ros2")
        elif args.command == "serve" and (args.ros2 or args.record_format == "ros2"):
            require("ros2", "usarsim serve --ros2")
            if args.record_format == "ros2" and not (args.record and args.ros2):
                raise MissingExtraError(
                    "--record-format ros2 records what the ROS 2 bridge publishes: give --record NAME and --ros2 ROBOT"
                )
            if args.foxglove is not None:
                require("record", "usarsim serve --foxglove")
        elif getattr(args, "record", None) or getattr(args, "foxglove", None) is not None:
            require("record", f"usarsim {args.command} --{'record' if args.record else 'foxglove'}")
    except MissingExtraError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    handler = (
        getattr(args, "handler", None)
        or {
            "serve": cmd_serve,
            "validate": cmd_validate,
            "worlds": cmd_worlds,
            "robots": cmd_robots,
            "bench": cmd_bench,
            "replay": cmd_replay,
        }[args.command]
    )  # sweep, report, compete, map, score-map, ros2 bring their own handler
    try:
        return handler(args)
    except BrokenPipeError:  # 'usarsim robots | head': the reader has all it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
