"""The ``usarsim`` command: argument parsing and wiring only."""

from __future__ import annotations

import argparse
import asyncio
import difflib
import faulthandler
import logging
import os
import re
import signal
import sys
from pathlib import Path

from usarsim import __version__

log = logging.getLogger("usarsim")


def _speed(text: str) -> float | None:
    if text.lower() == "max":
        return None
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0 or 'max', got {text!r}") from None
    if not (v > 0 and v < 1e6):
        raise argparse.ArgumentTypeError(f"expected a number > 0 or 'max', got {text!r}")
    return v


def _int_within(low: int, high: int, what: str):
    """An argument type: an integer ``low..high`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = None
        if v is None or not low <= v <= high:
            raise argparse.ArgumentTypeError(f"expected {what} {low}..{high}, got {text!r}")
        return v

    return parse


_port = _int_within(0, 65535, "a port number")
_micros = _int_within(0, 1_000_000, "microseconds")


def _step_grace_s(args: argparse.Namespace) -> float:
    """``--step-grace-us`` in seconds (usarsim.server.ordering.STEP_GRACE_S by default)."""
    from usarsim.server.ordering import STEP_GRACE_S

    return STEP_GRACE_S if args.step_grace_us is None else args.step_grace_us / 1e6


def _threads(text: str) -> str:
    """``--physics-threads``: a number of threads (0: none) or 'auto'."""
    value = text.strip().lower()
    if value == "auto" or (value.isdigit() and int(value) <= 256):
        return value
    raise argparse.ArgumentTypeError(f"expected a number of threads from 0 to 256 or 'auto', got {text!r}")


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 320x240, got {text!r}") from None
    if not (1 <= w <= 1920 and 1 <= h <= 1080):
        raise argparse.ArgumentTypeError(f"a picture from 1x1 to 1920x1080, got {text!r}")
    return w, h


# The ports ``usarsim serve`` listens on when none is given, by option; ``--port-offset N``
# adds N to each (a second server beside the first needs nothing else).
FOXGLOVE_PORT = 8765  # Foxglove's own default for a live WebSocket connection
FOXGLOVE_DEFAULT = -1  # --foxglove without a port: FOXGLOVE_PORT plus --port-offset (resolve_foxglove_port)
DEFAULT_PORTS = {
    "port": 3000,
    "truth_port": 3989,
    "image_port": 5003,
    "web_port": 8080,
    "wcs_port": 5874,
    "wss_port": 50000,
    "cominterface_port": 7435,
}


def resolve_ports(
    given: dict[str, int | None], offset: int = 0, from_file: dict[str, int | None] | None = None
) -> dict[str, int]:
    """Every listener's port: the one given on the command line, else the one of the
    --wireless-config file (ComServer, ComServerInterface), else the default plus ``offset``.
    A port given explicitly (0 included) keeps its value.  ValueError names the option whose
    default the offset puts beyond 65535 (or below 1)."""
    from_file = from_file or {}
    ports = {}
    for name, default in DEFAULT_PORTS.items():
        value = given.get(name)
        if value is None:
            value = from_file.get(name)
        if value is None:
            value = default + offset
            if not 1 <= value <= 65535:
                option = "--" + name.replace("_", "-")
                raise ValueError(
                    f"--port-offset {offset} puts the default of {option} ({default}) at {value}, outside 1..65535"
                )
        ports[name] = value
    return ports


def resolve_foxglove_port(given: int | None, offset: int = 0) -> int | None:
    """--foxglove's port: None when not asked for, FOXGLOVE_PORT plus ``offset`` when asked
    for without a port, else the port given (0 included, a free one)."""
    if given is None:
        return None
    return FOXGLOVE_PORT + offset if given == FOXGLOVE_DEFAULT else given


def _port_offset(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number 0..{65535 - 50000}, got {text!r}") from None
    if not 0 <= v <= 65535 - 50000:
        raise argparse.ArgumentTypeError(
            f"expected a number 0..{65535 - 50000} (the WSS port is 50000 + N), got {text!r}"
        )
    return v


class _Parser(argparse.ArgumentParser):
    """argparse, with a usage error said in one line (no usage block before it), naming the
    command's --help, and "did you mean" for a misspelt command, choice or option."""

    def parse_args(self, args=None, namespace=None):  # noqa: ANN001, ANN201 (argparse's signature)
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            msg = "unrecognized arguments: " + " ".join(extras)
            command = self._subparser(getattr(parsed, "command", None))
            guess = next(
                (
                    g
                    for e in extras
                    if e.startswith("--")
                    for g in difflib.get_close_matches(e.split("=")[0], command._option_string_actions, n=1)
                ),
                None,
            )
            if guess:
                msg += f" (did you mean {guess}?)"
            command.error(msg)
        return parsed

    def _subparser(self, command: str | None) -> argparse.ArgumentParser:
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction) and command in action.choices:
                return action.choices[command]
        return self

    def error(self, message: str):  # noqa: ANN201 (argparse's signature: never returns)
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            options = re.findall(r"'([^']*)'", choice.group(2))
            guess = difflib.get_close_matches(choice.group(1), options, n=1)
            if guess:
                message += f" (did you mean {guess[0]!r}?)"
        self.exit(2, f"{self.prog}: error: {message}; see '{self.prog} --help'\n")


_VERBOSE_HELP = "more log output: -v logs connections, spawns and removals, -vv everything (debug)"


def _add_verbose(parser: argparse.ArgumentParser, dest: str) -> None:
    parser.add_argument("-v", "--verbose", action="count", default=0, dest=dest, help=_VERBOSE_HELP)


def build_parser() -> argparse.ArgumentParser:
    from usarsim.config.world import WIRELESS_MODELS

    p = _Parser(
        prog="usarsim",
        description="A USARSim-compatible robot simulator on MuJoCo. Controllers written for USARSim 3.x "
        "connect on TCP port 3000 and drive simulated robots unmodified.",
        epilog="Run 'usarsim COMMAND --help' for the options of a command.",
    )
    p.add_argument("--version", action="version", version=f"usarsim {__version__}")
    _add_verbose(p, "verbose")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    s = sub.add_parser(
        "serve",
        help="run the simulator and its servers",
        description="Load a world and serve the USARSim control protocol until SIGINT/SIGTERM.",
    )
    s.add_argument(
        "--world",
        default="DM-USAR_yellow",
        help="world name (see 'usarsim worlds') or path of a world file (default: %(default)s)",
    )
    s.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (default: %(default)s, this machine only; 0.0.0.0 exposes the "
        "simulator to the network)",
    )
    s.add_argument("--port", type=_port, default=None, help="control port (default: 3000; 0 picks a free port)")
    s.add_argument(
        "--port-offset",
        type=_port_offset,
        default=0,
        metavar="N",
        help="add N to the default of every port (control 3000, ground truth 3989, image 5003, web "
        "8080, ComServer 5874, WSS 50000, ComServerInterface 7435, Foxglove 8765 with --foxglove), "
        "to run a second server beside "
        "the first: --port-offset 100 listens on 3100, 4089...; a port given explicitly keeps its "
        "value (default: %(default)s)",
    )
    s.add_argument("--seed", type=int, default=0, help="seed of every random generator (default: %(default)s)")
    s.add_argument(
        "--speed",
        type=_speed,
        default=1.0,
        metavar="FACTOR|max",
        help="simulated seconds per wall-clock second: 1 is real time (default), 4 runs four times "
        "faster, 'max' as fast as the machine can",
    )
    s.add_argument(
        "--lockstep",
        action="store_true",
        help="the world stands still until a client sends STEP {Time seconds}; the server then "
        "advances that much simulated time and replies STEPPED {Time t}",
    )
    s.add_argument(
        "--poll-us",
        type=int,
        default=None,
        metavar="US",
        help="lock-step: after each request the server polls its sockets for up to this many "
        "microseconds before it sleeps, which answers a fast controller's next STEP sooner at the "
        "cost of that much processor time a request; 0 never polls (default: 500 with "
        "--lockstep, else 0)",
    )
    s.add_argument(
        "--step-grace-us",
        type=_micros,
        default=None,
        metavar="US",
        help="lock-step: a STEP is carried out once every line that reached the server before it, on "
        "any connection, is handled, and no other control connection has received anything for "
        "this many microseconds (a line a client's TCP stack held back arrives within it; "
        "default: 200)",
    )
    s.add_argument(
        "--max-connections",
        type=int,
        default=256,
        help="control connections at most; one more is refused and logged (default: %(default)s)",
    )
    s.add_argument(
        "--max-robots",
        type=int,
        default=None,
        help="robots in the world at most; an INIT beyond it is refused and logged (default: --max-connections)",
    )
    s.add_argument(
        "--max-line-bytes",
        type=int,
        default=8192,
        help="longest control line; a longer one is dropped and logged (default: %(default)s)",
    )
    s.add_argument(
        "--max-pending-kb",
        type=int,
        default=256,
        help="output waiting for a slow client beyond which its sensor and status lines are "
        "held latest-wins, replies kept (default: %(default)s)",
    )
    s.add_argument(
        "--max-viewers",
        type=int,
        default=16,
        help="connections at most on the image and ground-truth ports each; one more is refused "
        "and logged (default: %(default)s)",
    )
    s.add_argument(
        "--max-wireless-connections",
        type=int,
        default=64,
        metavar="N",
        help="connections at most on the ComServer, WSS and ComServerInterface ports each; one more is "
        "refused and logged (default: %(default)s)",
    )
    s.add_argument(
        "--max-web-connections",
        type=int,
        default=64,
        metavar="N",
        help="open connections at most on the web console port; a request beyond them is answered "
        "503 and logged (default: %(default)s)",
    )
    s.add_argument(
        "--truth-port",
        type=_port,
        default=None,
        help="ground-truth service port (default: 3989; 0 picks a free port): "
        "'{Class c} {Name n}' -> where every matching robot, victim, tag... is",
    )
    s.add_argument(
        "--image-port",
        type=_port,
        default=None,
        help="image server port (default: 5003; 0 picks a free port): clients send 'OK' for a "
        "picture of the MultiView or of the robot camera bound to them",
    )
    s.add_argument("--no-image", action="store_true", help="do not serve pictures (no image server, no rendering)")
    s.add_argument(
        "--image-type",
        default="normal",
        choices=["raw", "superb", "good", "normal", "fair", "bad"],
        help="picture encoding: raw BGR or JPEG of that quality (UPIS ImageType; default: %(default)s)",
    )
    s.add_argument(
        "--image-size",
        type=_size,
        default=(640, 480),
        metavar="WxH",
        help="size of a bound robot camera's picture (default: 640x480)",
    )
    s.add_argument(
        "--multiview-cameras",
        type=int,
        default=4,
        metavar="N",
        help="MultiView CameraNum: robot cameras shown at most (default: %(default)s)",
    )
    s.add_argument(
        "--multiview-columns",
        type=int,
        default=0,
        metavar="N",
        help="MultiView WideMode: 0 lays the tiles in a box, N > 0 puts N in a row (default: %(default)s)",
    )
    s.add_argument(
        "--multiview-tile",
        type=_size,
        default=(320, 240),
        metavar="WxH",
        help="MultiView CameraXres x CameraYres, the size of each tile (default: 320x240)",
    )
    s.add_argument(
        "--frame-skip",
        type=int,
        default=0,
        metavar="N",
        help="UPIS FrameSkip: render a new picture for every (N+1)-th request, repeat the last one "
        "otherwise (default: %(default)s)",
    )
    s.add_argument(
        "--max-fps",
        type=float,
        default=30.0,
        help="frame budget: new pictures per second, all image clients together, so that cameras do "
        "not slow the physics (default: %(default)s)",
    )
    s.add_argument(
        "--wcs-port",
        type=_port,
        default=None,
        metavar="P",
        help="wireless ComServer port (default: 5874, or ListenPort of --wireless-config; 0 picks a "
        "free port): REGISTER, LISTEN, OPEN, GETSS; links relayed while the radio signal holds",
    )
    s.add_argument(
        "--wss-port",
        type=_port,
        default=None,
        metavar="P",
        help="Wireless Simulation Server control port (default: 50000; 0 picks a free port): "
        "INIT, GETSS, DNS, REVERSEDNS and relay ports per robot pair",
    )
    s.add_argument(
        "--cominterface-port",
        type=_port,
        default=None,
        metavar="P",
        help="ComServerInterface port (default: 7435, or iListenPort of --wireless-config; 0 picks a "
        "free port): GETPOS and GETOBS",
    )
    s.add_argument(
        "--wireless-model",
        default=None,
        choices=WIRELESS_MODELS,
        help="radio propagation model: waf (wall attenuation factor, the USARSim manual's constants; the "
        "default unless the world names one), waf2009 (the later USARSim code's constants), "
        "distance (walls ignored), perfect (every link holds)",
    )
    s.add_argument(
        "--wireless-config",
        default=None,
        metavar="FILE",
        help="an ini file in the form of USARSim's USARComServer.ini: ListenPort, bDebug, ePdo, eDo, eN, "
        "eCutoff, eMaxObs, eAttenFac (and Model, CacheDistance, iListenPort); its constants override "
        "the world's",
    )
    s.add_argument(
        "--no-wireless",
        action="store_true",
        help="do not simulate wireless communication (no ComServer, WSS or ComServerInterface)",
    )
    s.add_argument(
        "--robot-dir",
        action="append",
        default=[],
        metavar="DIR",
        help="a folder of robot files of your own (one YAML file per class, named after the class); "
        "clients INIT them by class name like the shipped robots; may be repeated",
    )
    s.add_argument(
        "--web-port",
        type=_port,
        default=None,
        metavar="P",
        help="operator console port (default: 8080; 0 picks a free port): open "
        "http://HOST:P/ in a browser to watch the world, spawn and drive robots with their video "
        "and sensors, and send any command",
    )
    s.add_argument("--no-web", action="store_true", help="do not serve the operator console")
    s.add_argument(
        "--shadows",
        action="store_true",
        help="cameras draw the shadows of the lights that cast them (about half the pictures a second "
        "on a machine without a GPU; default: off)",
    )
    s.add_argument(
        "--physics-threads",
        type=_threads,
        default=None,
        metavar="N",
        help="threads of MuJoCo's own pool, which solves robots that do not touch on several cores "
        "(the same results bit for bit): 0 for none, 'auto' (default) for one a core but one "
        "from 32 robots on (none on a 2-core machine: the sensors and the server need the other)",
    )
    s.add_argument(
        "--sensors-inline",
        action="store_true",
        help="take sensor readings on the simulation thread itself instead of a thread of their own "
        "that works while the physics runs on (the same readings either way; slower)",
    )
    s.add_argument(
        "--no-textures",
        action="store_true",
        help="cameras see plain colours instead of the materials' textures (the quickest pictures)",
    )
    s.add_argument(
        "--record",
        default=None,
        metavar="FILE.mcap",
        help="record the run to an MCAP file: every line each client sent and received on every port "
        "(for 'usarsim replay'), and the world, robots, lasers, poses, battery, radio links and "
        "log in Foxglove's schemas (docs/recording.md)",
    )
    s.add_argument(
        "--record-format",
        choices=("foxglove", "ros2"),
        default="foxglove",
        help="foxglove (default): the MCAP file above; ros2: a rosbag2 folder (the name less .mcap) of "
        "what the --ros2 bridge publishes, for 'ros2 bag play' (docs/ros2.md)",
    )
    s.add_argument(
        "--ros2",
        action="append",
        default=[],
        metavar="CLASS[@START][:NAME]",
        help="start the ROS 2 bridge beside the server with this robot (repeat for more): 'usarsim "
        "ros2 --robot ...' in a process of its own, stopped with the server (docs/ros2.md)",
    )
    s.add_argument(
        "--record-cameras",
        type=float,
        default=0.0,
        metavar="FPS",
        help="with --record or --foxglove: also every robot camera's picture (JPEG), FPS a simulated "
        "second (default: 0, none; rendering costs the CPU: 5 is a good rate)",
    )
    s.add_argument(
        "--record-camera-size",
        type=_size,
        default=(320, 240),
        metavar="WxH",
        help="with --record-cameras: the pictures' size (default: 320x240)",
    )
    s.add_argument(
        "--score",
        action="store_true",
        help="keep the run's score (victims found, floor explored, distance, collisions, robots lost, "
        "radio contact: docs/scoring.md) and print it every 10 simulated seconds and at the end",
    )
    s.add_argument(
        "--score-file",
        default=None,
        metavar="FILE.json",
        help="write the run's final score as JSON when the server stops (docs/scoring.md)",
    )
    s.add_argument(
        "--foxglove",
        type=_port,
        nargs="?",
        const=FOXGLOVE_DEFAULT,
        default=None,
        metavar="PORT",
        help=f"serve the run live to Foxglove over its WebSocket protocol, subprotocol foxglove.sdk.v1 "
        f"(default port {FOXGLOVE_PORT} plus --port-offset; 0 picks a free port): open Foxglove and "
        "connect to ws://HOST:PORT (docs/recording.md)",
    )

    v = sub.add_parser(
        "validate",
        help="check a world, robot, RNDF or MDF file",
        description="Load a world or robot file (or a shipped world or robot class by name, "
        "as 'usarsim worlds' and 'usarsim robots' list them), build its MuJoCo model "
        "and print a one-line "
        "summary, or the error with the file, the key (and the object it is in), "
        "what is allowed and, for a misspelt key, the closest valid one. It also "
        "refuses a start pose inside a solid, a robot file whose class_name is not "
        "its file name, a Gripper whose fingers are not links of the robot and a "
        "RollerTable whose surface is no chassis piece. A DARPA "
        "route network (.rndf) or mission (.mdf) file is checked the same way (an MDF "
        "against the RNDF beside it); its errors name the line.",
    )
    v.add_argument(
        "path",
        metavar="PATH|NAME",
        help="path of a .yaml world or robot file, or of a .rndf or .mdf file; or the name of a "
        "shipped world (DM-USAR_yellow) or robot class (P2AT)",
    )

    w = sub.add_parser("worlds", help="list the worlds that come with usarsim")
    r = sub.add_parser("robots", help="list the robot classes that come with usarsim")

    b = sub.add_parser(
        "bench",
        help="measure the real-time factor with N robots",
        description="Spawn N P2ATs with their full sensor kit, each driven by its own TCP client "
        "over loopback, run S simulated seconds as fast as possible and report the "
        "real-time factor beside that of bare mj_step on the same model.",
    )
    b.add_argument("--robots", type=int, default=1, help="number of robots (default: %(default)s)")
    b.add_argument("--seconds", type=float, default=10.0, help="simulated seconds to run (default: %(default)s)")
    b.add_argument("--world", default="DM-USAR_yellow", help="world (default: %(default)s)")
    b.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    b.add_argument(
        "--cameras",
        action="store_true",
        help="measure the image server instead: frames per second a client gets of a P2AT's camera, "
        "beside bare MuJoCo rendering plus JPEG encoding of the same view, and their ratio; and "
        "what textures cost: the same camera served from the world in plain colours",
    )
    b.add_argument(
        "--sizes",
        type=_size,
        nargs="+",
        default=[(320, 240), (640, 480)],
        metavar="WxH",
        help="with --cameras: picture sizes (default: 320x240 640x480)",
    )
    b.add_argument("--frames", type=int, default=60, help="with --cameras: frames per size (default: %(default)s)")
    b.add_argument(
        "--round-trips",
        action="store_true",
        help="measure lock-step STEP/STEPPED round trips a second (4 ms steps) of a client in another "
        "process, with no robot and with one P2AT, and against a bare echo server on the same "
        "event loop (what the machine allows)",
    )
    b.add_argument(
        "--count", type=int, default=5000, help="with --round-trips: round trips timed (default: %(default)s)"
    )
    b.add_argument(
        "--profile",
        action="store_true",
        help="profile the simulation thread, the measuring thread and the server's event loop during "
        "the run and print where the time goes (physics, split by MuJoCo's timers into collision, "
        "making and solving the constraints and the rest; each sensor type, ray casting, report "
        "scheduling, building readings, formatting, socket writes, waiting for the interpreter lock)",
    )
    b.add_argument(
        "--record",
        action="store_true",
        help="measure what recording costs: runs without and with 'serve --record' (every channel but "
        "cameras), alternately; prints both real-time factors and the recording's size per "
        "robot-minute",
    )
    b.add_argument(
        "--targets",
        action="store_true",
        help="one sitting of every benchmark the scaling targets of a 2-core machine are judged by "
        "(16, 64 and 256 robots, round trips, cameras), --runs times in turn, and a table of each "
        "target against every run, with the machine and the time (5 to 6 minutes on a 2-core machine)",
    )
    b.add_argument(
        "--runs",
        type=int,
        default=3,
        help="with --targets: runs of each benchmark; with --ros2: runs each way (default: %(default)s)",
    )
    b.add_argument(
        "--ros2",
        action="store_true",
        help="the ROS 2 bridge: N P2ATs in real time, alternately without and with 'usarsim ros2' and a "
        "subscriber of every topic in another process; the real-time factor reached, each topic's "
        "rate and missed readings, and the delay from the simulated time of a reading to its "
        "delivery (docs/ros2.md)",
    )
    b.add_argument(
        "--counts",
        type=int,
        nargs="+",
        default=[16, 64, 256],
        metavar="N",
        help="with --targets: robot counts (default: 16 64 256; the targets are set at those)",
    )
    b.add_argument(
        "--env",
        action="store_true",
        help="measure the learning environments instead: Gymnasium steps per second of one P2AT at a "
        "0.1 s control period in lock-step, and PettingZoo steps per second of a team (--team)",
    )
    b.add_argument("--team", type=int, default=8, help="with --env: robots in the team (default: %(default)s)")
    b.add_argument("--steps", type=int, default=300, help="with --env: steps timed (default: %(default)s)")
    rp = sub.add_parser(
        "replay",
        help="replay a recording against a fresh server and compare",
        description="Start a server with the recording's world, seed and options (always in "
        "lock-step, on free ports), send every client line of the recording "
        "(usarsim serve --record) again in the order the server saw them, and "
        "compare every server line with the recorded one. A lock-step recording "
        "replays identically; a real-time one is replayed at its recorded "
        "simulated times and the report says how far the outputs differ. Image "
        "and wireless connections are not replayed. A recording the server did not "
        "close (killed, crashed) is replayed up to where it ends, with a warning "
        "saying where; a damaged file, or one that is not a recording, is refused "
        "in one line (exit 1; the traceback with -v).",
    )
    rp.add_argument("path", metavar="FILE.mcap", help="a recording made with usarsim serve --record")
    rp.add_argument(
        "--check",
        action="store_true",
        help="stop at the first server line that differs, name its connection, simulated time and "
        "both lines, and exit 1; exit 0 only when every line is identical",
    )
    rp.add_argument(
        "--timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="how long to wait for a recorded server line before calling it missing (default: %(default)s)",
    )
    from usarsim.sweep.cli import add_parsers as add_sweep_parsers

    add_sweep_parsers(sub)  # 'usarsim sweep' and 'usarsim report' (docs/experiments.md)
    from usarsim.ros2.cli import add_parser as add_ros2_parser

    r2 = add_ros2_parser(sub)  # 'usarsim ros2' (docs/ros2.md)
    for command in (s, v, w, r, b, rp, r2):  # -v and -vv after the command too: 'usarsim serve -v'
        _add_verbose(command, "verbose_after")
    return p


def _setup_logging(verbose: int) -> None:
    level = logging.WARNING if verbose == 0 else logging.INFO if verbose == 1 else logging.DEBUG
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def _raise_file_limit(want: int = 65536) -> None:
    """Every connection, relay port and link is a file descriptor: lift the soft limit on
    them towards the hard one (a desktop's default soft limit, 1024, is less than what the
    servers' own limits allow together)."""
    try:
        import resource
    except ImportError:  # not on this platform
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    target = want if hard == resource.RLIM_INFINITY else min(want, hard)
    if soft != resource.RLIM_INFINITY and soft < target:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
            log.debug("open files limit raised from %d to %d", soft, target)
        except (ValueError, OSError) as exc:
            log.warning("open files limit stays at %d (%s)", soft, exc)


def cmd_serve(args) -> int:
    from usarsim.config.catalog import resolve_world
    from usarsim.errors import UsarsimError
    from usarsim.server.app import Application
    from usarsim.server.config import ServeConfig
    from usarsim.server.listener import call_on_loop

    try:
        world = resolve_world(args.world)
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    for d in args.robot_dir:
        if not os.path.isdir(d):
            print(f"usarsim: error: --robot-dir {d}: no such folder", file=sys.stderr)
            return 1
    try:
        from usarsim.config.robot import class_name_problem, load_robot

        for d in args.robot_dir:
            for path in sorted(Path(d).glob("*.yaml")):
                # a broken robot file is reported now, not when a client asks for it
                problem = class_name_problem(load_robot(path))
                if problem is not None:
                    print(f"usarsim: error: {path}: {problem}", file=sys.stderr)
                    return 1
    except UsarsimError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    from usarsim.server.image import IMAGE_TYPES, ImageSettings

    image = ImageSettings(
        image_type=IMAGE_TYPES[args.image_type],
        width=args.image_size[0],
        height=args.image_size[1],
        camera_num=max(1, args.multiview_cameras),
        wide_mode=max(0, args.multiview_columns),
        tile_width=args.multiview_tile[0],
        tile_height=args.multiview_tile[1],
        frame_skip=max(0, args.frame_skip),
        max_fps=args.max_fps,
    )
    wireless = wfile = None
    if not args.no_wireless:
        from usarsim.sim.radio import load_wireless_file, resolve_model

        try:
            wfile = load_wireless_file(args.wireless_config) if args.wireless_config else None
            layer = wfile.radio if wfile is not None else None
            resolve_model(world.wireless, layer, model=args.wireless_model)  # reported now, not at start
        except UsarsimError as exc:
            print(f"usarsim: error: {exc}", file=sys.stderr)
            return 1
    try:
        ports = resolve_ports(
            {name: getattr(args, name) for name in DEFAULT_PORTS},
            args.port_offset,
            {"wcs_port": wfile.listen_port, "cominterface_port": wfile.interface_port} if wfile is not None else None,
        )
    except ValueError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    if not args.no_wireless:
        from usarsim.server.wireless import WirelessOptions

        wireless = WirelessOptions(
            wcs_port=ports["wcs_port"],
            wss_port=ports["wss_port"],
            interface_port=ports["cominterface_port"],
            model=args.wireless_model,
            config=layer,
            debug=bool(wfile and wfile.debug),
            max_connections=max(1, args.max_wireless_connections),
        )
    control_port = ports["port"]
    from usarsim.sim.settings import SimSettings

    threads = args.physics_threads
    try:
        config = ServeConfig(
            world=world,
            sim=SimSettings(
                shadows=args.shadows,
                textures=not args.no_textures,
                physics_threads=None if threads in (None, "auto") else int(threads),
                sensor_thread=not args.sensors_inline,
            ),
            host=args.host,
            port=control_port,
            seed=args.seed,
            speed=args.speed,
            lockstep=args.lockstep,
            max_connections=args.max_connections,
            robot_dirs=tuple(args.robot_dir),
            truth_port=ports["truth_port"],
            image_port=None if args.no_image else ports["image_port"],
            image=image,
            wireless=wireless,
            web_port=None if args.no_web else ports["web_port"],
            max_robots=args.max_robots,
            max_line_bytes=max(64, args.max_line_bytes),
            max_pending_bytes=max(4, args.max_pending_kb) * 1024,
            max_viewers=max(1, args.max_viewers),
            max_web_connections=max(2, args.max_web_connections),
            record=args.record if args.record_format == "foxglove" else None,
            foxglove_port=resolve_foxglove_port(args.foxglove, args.port_offset),
            run_options=run_options(args),
            record_cameras_fps=max(0.0, args.record_cameras),
            record_camera_size=args.record_camera_size,
            score=args.score,
            score_file=args.score_file,
            step_grace_s=_step_grace_s(args),
        )
    except ValueError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    app = Application(config, on_score_line=lambda line: print(f"usarsim: {line}", flush=True))

    _raise_file_limit()

    async def main() -> None:
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        # a simulation that stopped on an error (a bug) leaves nothing to serve: the server stops,
        # so that its clients see the connection close instead of a world that stands still
        app.facade.when_failed(lambda exc: call_on_loop(loop, stop.set))
        try:
            await app.start()
        except OSError as exc:
            which = getattr(exc, "usarsim_listener", f"the control port {control_port} (--port)")
            print(f"usarsim: error: cannot listen on {args.host}, {which}: {exc.strerror}", file=sys.stderr)
            raise SystemExit(1) from exc
        for service, host, port in app.listeners():
            print(f"usarsim: {service} listening on {host}:{port}", flush=True)
        if app.web is not None:
            where = "127.0.0.1" if args.host in ("", "0.0.0.0") else args.host
            where = f"[{where}]" if ":" in where else where
            print(f"usarsim: operator console at http://{where}:{app.web.port}/", flush=True)
        if app.recorder is not None and args.record:
            print(
                f"usarsim: recording to {args.record} (written as it goes: a server that is killed loses "
                "about its last second)",
                flush=True,
            )
        bridge = await _start_ros2_bridge(args, app) if args.ros2 else None
        mode = "lock-step" if args.lockstep else ("max speed" if args.speed is None else f"speed {args.speed:g}x")
        log.info("world %s loaded (%d start poses), %s, seed %d", world.name, len(world.start_poses), mode, args.seed)
        await stop.wait()
        failure = app.facade.failure
        if failure is not None:
            print(
                f"usarsim: error: the simulation stopped on an unexpected error ({failure!r}; the log has the "
                "traceback): the server stops",
                file=sys.stderr,
                flush=True,
            )
        log.info("shutting down")
        if bridge is not None:
            await _stop_ros2_bridge(bridge)
        await app.stop()
        if app.recorder is not None and args.record and os.path.isfile(args.record):
            rec = app.recorder
            print(
                f"usarsim: recorded {args.record}: {os.path.getsize(args.record) / 1e6:.1f} MB, {rec.chunks} "
                f"transcript chunks, {rec.messages} other messages, {rec.pictures} camera pictures",
                flush=True,
            )
        if failure is not None:
            raise SystemExit(1)

    from usarsim.server.polling import new_event_loop, poll_seconds

    poll_s = poll_seconds(args.lockstep, args.poll_us)
    try:
        with asyncio.Runner(loop_factory=lambda: new_event_loop(poll_s)) as runner:
            runner.run(main())
    except SystemExit as exc:
        return int(exc.code or 0)
    return 0


async def _start_ros2_bridge(args, app) -> asyncio.subprocess.Process:
    """``usarsim ros2`` for the robots of ``--ros2``, in a process of its own, on the control
    port just opened; its lines go to this server's output."""
    port = next(p for service, _, p in app.listeners() if service == "control")
    host = "127.0.0.1" if args.host in ("", "0.0.0.0", "::") else args.host
    cmd = [sys.executable, "-m", "usarsim", "ros2", "--host", host, "--port", str(port)]
    image = next((p for service, _, p in app.listeners() if service == "image"), None)
    if image is not None:
        cmd += ["--image-port", str(image)]
    else:
        cmd += ["--camera-hz", "0"]
    if args.lockstep:
        cmd.append("--lockstep")
    for robot in args.ros2:
        cmd += ["--robot", robot]
    if args.record and args.record_format == "ros2":
        cmd += ["--bag", args.record.removesuffix(".mcap")]
    log.info("starting the ROS 2 bridge: %s", " ".join(cmd[1:]))
    return await asyncio.create_subprocess_exec(*cmd, stdin=asyncio.subprocess.DEVNULL, start_new_session=True)


async def _stop_ros2_bridge(proc: asyncio.subprocess.Process) -> None:
    if proc.returncode is None:
        proc.terminate()
        try:
            await asyncio.wait_for(proc.wait(), 15.0)
        except TimeoutError:
            proc.kill()
            await proc.wait()
    if proc.returncode not in (0, -signal.SIGTERM):
        print(f"usarsim: the ROS 2 bridge exited {proc.returncode} (its error is above)", file=sys.stderr)


def run_options(args) -> dict:
    """The options of ``serve`` that a replay needs to start the same server (in a
    recording's metadata)."""
    return {
        "robot_dirs": [os.path.abspath(d) for d in args.robot_dir],
        "wireless": not args.no_wireless,
        "wireless_model": args.wireless_model,
        "wireless_config": os.path.abspath(args.wireless_config) if args.wireless_config else None,
        "max_robots": args.max_robots,
        "max_connections": args.max_connections,
        "max_line_bytes": args.max_line_bytes,
    }


def validate_target(text: str) -> str:
    """What ``usarsim validate`` checks: ``text`` itself when it is a file (or looks like a
    path), else the shipped world or robot class of that name (any case; ``USARBot.P2AT``
    too), as ``serve --world`` and INIT find them."""
    from usarsim.config.catalog import robot_files, world_files
    from usarsim.config.reader import did_you_mean
    from usarsim.errors import ConfigError

    p = Path(text)
    if p.exists() or p.suffix.lower() in (".yaml", ".yml", ".rndf", ".mdf") or os.sep in text:
        return text
    bare = text.split(".", 1)[1] if text.lower().startswith("usarbot.") else text
    for name, files in ((text, world_files()), (bare, robot_files())):
        for stem, path in files.items():
            if stem.lower() == name.lower():
                return str(path)
    known = {**world_files(), **robot_files()}
    raise ConfigError(f"'{text}' is no file, shipped world or robot class{did_you_mean(bare, known)}")


def check_robot_items(robot) -> None:
    """What ``usarsim validate`` checks of a robot's items beyond their own settings: each
    type is a registered plugin, a Gripper's ``fingers`` are links of the robot and a
    RollerTable's ``surface`` is the index of one of its chassis pieces (both checked when
    the robot is spawned, too late for the author of the file).  Raises ConfigError."""
    from usarsim.config.reader import did_you_mean
    from usarsim.effecters.gripper import Gripper
    from usarsim.effecters.roller_table import RollerTable
    from usarsim.errors import ConfigError, PluginNotFoundError
    from usarsim.sensors import make_item

    def key_of(item, plugin, field_name: str) -> str:  # the setting as written: surface, Surface
        names = {field_name.lower(), *(a.lower() for a, f in type(plugin).ALIASES.items() if f == field_name)}
        raw = next((str(k) for k in item.params if str(k).lower() in names), None)
        return f"{item.key_path}.{raw}" if raw is not None else item.key_path

    links = [ln.name for ln in robot.links]
    for item in robot.items:
        try:
            plugin = make_item(item, robot, 0, "validate")
        except PluginNotFoundError as exc:
            raise ConfigError(str(exc), path=robot.path, key=f"{item.key_path}.type") from None
        if isinstance(plugin, Gripper):
            fingers = plugin.config.fingers
            for f in [fingers] if isinstance(fingers, str) else fingers:
                if f not in links:
                    hint = did_you_mean(str(f), links) if links else "; this robot has no links"
                    raise ConfigError(
                        f"unknown finger link '{f}': a Gripper's fingers are links of the robot{hint}",
                        path=robot.path,
                        key=key_of(item, plugin, "fingers"),
                    )
        if isinstance(plugin, RollerTable) and plugin.config.surface >= len(robot.chassis):
            n = len(robot.chassis)
            raise ConfigError(
                f"surface {plugin.config.surface} is out of range: it is the index of the chassis "
                f"piece that is the table's top, and this robot has {n} (chassis[0] to "
                f"chassis[{n - 1}])",
                path=robot.path,
                key=key_of(item, plugin, "surface"),
            )


def cmd_validate(args) -> int:
    from usarsim.config.catalog import file_kind
    from usarsim.config.reader import load_yaml, name_entries
    from usarsim.errors import ConfigError, UsarsimError

    path = args.path
    try:
        path = validate_target(args.path)
        kind = file_kind(path)
        if kind in ("rndf", "mdf"):
            from usarsim.config.rndf import describe_route_file

            print(describe_route_file(path))
        elif kind == "world":
            from usarsim.config.world import check_world_file
            from usarsim.sim.simulation import Simulation

            w = check_world_file(path)
            sim = Simulation(w)
            print(
                f"ok: world {w.name}: {len(w.objects)} objects, {len(w.start_poses)} start poses, "
                f"floor {w.floor.size[0]:g} x {w.floor.size[1]:g} m, MuJoCo model with {sim.model.ngeom} geoms"
            )
        else:
            from usarsim.config.robot import class_name_problem, load_robot
            from usarsim.sim.robotspec import robot_model_summary
            from usarsim.sim.simulation import describe_items

            r = load_robot(path)
            check_robot_items(r)
            items = describe_items(r)
            summary = robot_model_summary(r)
            problem = class_name_problem(r)  # last: what is wrong inside the file comes first
            if problem is not None:
                raise ConfigError(problem, path=path, key="class_name")
            print(
                f"ok: robot {r.class_name}: {r.steering_type}, {r.mass_kg:g} kg, {len(items)} sensors, "
                f"MuJoCo model with {summary}"
            )
    except UsarsimError as exc:
        if isinstance(exc, ConfigError) and exc.path == path:
            try:  # an error about an entry of a list names it (sensors[3] (RangeScanner 'Scanner1'))
                name_entries(exc, load_yaml(path))
            except UsarsimError:
                pass
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    return 0


def cmd_worlds(args) -> int:
    from usarsim.config.catalog import world_files
    from usarsim.config.world import load_world

    for path in world_files().values():
        w = load_world(path)
        print(f"{w.name}  {w.description}")
    return 0


def cmd_robots(args) -> int:
    from usarsim.config.catalog import robot_files
    from usarsim.config.robot import load_robot

    for path in robot_files().values():
        r = load_robot(path)
        kit = ", ".join(sorted({i.item_type for i in r.items}))
        drive = r.drive if r.steering_type in ("", "None") else f"{r.drive} ({r.steering_type})"
        print(f"{r.class_name:<11} {drive:<27} {r.description}\n{'':<11} {'':<27} kit: {kit}")
    return 0


def cmd_bench(args) -> int:
    from usarsim.errors import ConfigError

    try:
        return _bench(args)
    except ConfigError as exc:  # the world asked for: said in one line, as serve says it
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1


def _bench(args) -> int:
    from usarsim.bench import run_bench, run_camera_bench

    if args.env:
        return run_env_bench(args)
    if args.targets:
        from usarsim.bench.targets import run_targets_bench

        return run_targets_bench(args)
    if args.ros2:
        from usarsim.ros2.bench import run_ros2_bench

        return run_ros2_bench(args)
    if args.round_trips:
        from usarsim.bench import run_round_trip_bench

        return run_round_trip_bench(args)
    return run_camera_bench(args) if args.cameras else run_bench(args)


def cmd_replay(args) -> int:
    from usarsim.replay import main as replay_main

    return replay_main(args)


def run_env_bench(args) -> int:
    """Environment steps per second (usarsim.envs.bench_env), one robot and a team."""
    import json

    from usarsim.envs import bench_env

    one = bench_env(args.steps, world=args.world)
    team = bench_env(max(1, args.steps // 3), team=args.team, world=args.world) if args.team > 0 else None
    result = {
        "env_steps_per_s": round(one, 1),
        "control_period_s": 0.1,
        "team": args.team,
        "team_steps_per_s": None if team is None else round(team, 1),
        "cpu_count": os.cpu_count(),
    }
    if args.json:
        print(json.dumps(result))
    else:
        print(f"Explore-v0, one P2AT at 0.1 s: {one:.0f} env steps/s ({one * 0.1:.0f}x real time)")
        if team is not None:
            print(f"TeamExplore, {args.team} P2ATs: {team:.0f} team steps/s ({team * 0.1:.0f}x real time)")
    return 0


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
        if args.command in ("sweep", "report"):
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
    if hasattr(args, "handler"):  # sweep, report
        return args.handler(args)
    handler = {
        "serve": cmd_serve,
        "validate": cmd_validate,
        "worlds": cmd_worlds,
        "robots": cmd_robots,
        "bench": cmd_bench,
        "replay": cmd_replay,
    }[args.command]
    try:
        return handler(args)
    except BrokenPipeError:  # 'usarsim robots | head': the reader has all it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
