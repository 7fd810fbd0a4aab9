"""The options of ``usarsim serve``: ports, limits, pictures, wireless, recording and scoring."""

from __future__ import annotations

import argparse

from usarsim.cli.options import (
    FOXGLOVE_DEFAULT,
    FOXGLOVE_PORT,
    _micros,
    _Parser,
    _port,
    _port_offset,
    _size,
    _speed,
    _threads,
    _variant,
)
from usarsim.sim.settings import ANTIALIAS


def _model_name(text: str) -> str:
    """``--wireless-model``: a radio model's name, a lower-case word (the registry of
    usarsim.sim.radio checks it when the server starts, with the closest names)."""
    name = text.strip().lower()
    if not name.isidentifier():
        raise argparse.ArgumentTypeError(f"a radio model's name is a word such as waf or perfect, got {text!r}")
    return name


def add_serve_parser(sub: argparse._SubParsersAction[_Parser]) -> argparse.ArgumentParser:
    """Add ``serve`` and its options to the sub-commands ``sub``; return its parser."""

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
        "--variant",
        type=_variant,
        metavar="N",
        help="serve variant N of the world: its victims, false alarms, RFID tags and movable debris placed "
        "from the seed N by the world's variation rules, some doorways closed or opened (docs/world-files.md, "
        "'Variants'); the same N gives the same arena. Default: the world as its file places things",
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
        metavar="MODEL",
        type=_model_name,
        help="radio propagation model: waf (wall attenuation factor, the USARSim manual's constants; the "
        "default unless the world names one), waf2009 (the later USARSim code's constants), "
        "distance (walls ignored), perfect (every link holds), or a plugin's (docs/architecture.md)",
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
        "--report-phases",
        choices=("grid", "spread"),
        default=None,
        help="grid (the default without --ros2): every robot reports at the same instants, so the "
        "physics runs in the longest stretches; spread (the default with --ros2): each robot on a "
        "phase of its own (an eighth of a period apart), so many robots' readings come in small "
        "groups, not one burst, and reach ROS 2 sooner (docs/ros2.md)",
    )
    s.add_argument(
        "--no-textures",
        action="store_true",
        help="cameras see plain colours instead of the materials' textures (the quickest pictures)",
    )
    s.add_argument(
        "--antialias",
        type=int,
        choices=ANTIALIAS,
        default=4,
        help="multisampling of the cameras' pictures, samples a pixel (default: %(default)s; 0: none, about "
        "twice the pictures a second on a machine without a GPU, with jagged edges)",
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
        "--team-map",
        default=None,
        metavar="MAP.yaml",
        help="where the team hands its map in (a map_server YAML file and its picture, written by the "
        "controller before the run ends): when the server stops the map is scored against the world's "
        "ground truth and its score goes into --score-file under 'map' (docs/scoring.md, 'Map quality')",
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
    return s
