"""The ``usarsim`` command line: the top-level parser and every sub-command's options."""

from __future__ import annotations

import argparse

from usarsim import __version__
from usarsim.cli.options import _add_verbose, _Parser, _size, _variant
from usarsim.cli.serve_options import add_serve_parser
from usarsim.sim.settings import ANTIALIAS


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``usarsim`` command and all its sub-commands."""
    p = _Parser(
        prog="usarsim",
        description="A USARSim-compatible robot simulator on MuJoCo. Controllers written for USARSim 3.x "
        "connect on TCP port 3000 and drive simulated robots unmodified.",
        epilog="Run 'usarsim COMMAND --help' for the options of a command.",
    )
    p.add_argument("--version", action="version", version=f"usarsim {__version__}")
    _add_verbose(p, "verbose")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    s = add_serve_parser(sub)

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
    v.add_argument(
        "--variant",
        type=_variant,
        metavar="N",
        help="a world: check its variant N (victims, false alarms, RFID tags and debris placed from the "
        "seed N, docs/world-files.md): every victim reachable, nothing inside a solid",
    )

    w = sub.add_parser("worlds", help="list the worlds that come with usarsim")
    r = sub.add_parser(
        "robots",
        help="list the robot classes that come with usarsim (or draw them: --picture)",
        description="List the robot classes that come with usarsim, their drives and sensor kits; "
        "with --picture, draw each one as cameras see it (its body, tracks or wheels, arms and "
        "sensors' housings in its colours) in one PNG.",
    )
    r.add_argument(
        "--picture",
        metavar="PNG",
        help="write a picture of the robots, one tile each with its name, to this PNG file",
    )
    r.add_argument(
        "--robot",
        action="append",
        metavar="CLASS",
        help="with --picture: draw this class only (repeat for several; default: every shipped class)",
    )
    r.add_argument("--robot-dir", metavar="DIR", help="also take robot files from this folder (one file per class)")

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
        "what textures cost: the same camera served from the world in plain colours; the same "
        "camera's depth, thermal and label pictures; and what robots' looks cost: a row of six "
        "robots in view drawn with their looks and as their solid pieces only",
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
        "scheduling, building readings, formatting, socket writes, waiting for the interpreter lock); "
        "with --env: each env step's wall time, the environment's and the simulator's processor "
        "time, and bare mj_step of the same robots for one control period, timed after each of five "
        "stretches of steps (the share of bare physics is the stretches' median)",
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
        help="with --targets: runs of each benchmark; with --ros2: runs each way; with --league: runs "
        "(default: %(default)s)",
    )
    b.add_argument(
        "--radio-load",
        action="store_true",
        help="measure what the radio channel costs: --robots P2ATs (16 unless given) driving about while "
        "each sends every teammate --radio-rate messages a simulated second through the ComServer, "
        "under USARSim's channel and a SubT-like one (capacity, fading, loss) alternately, --runs pairs",
    )
    b.add_argument(
        "--radio-rate",
        type=float,
        default=10.0,
        help="with --radio-load: messages a simulated second to each teammate (default: %(default)s)",
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
        "--report-phases",
        choices=("grid", "spread"),
        default="spread",
        help="with --ros2: the simulator's report phases, as 'usarsim serve --report-phases' "
        "(default: %(default)s: each robot reports on a phase of its own)",
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
        "--league",
        action="store_true",
        help="the RoboCup Rescue virtual robot league's load: 4 P2ATs in real time, each with a 320x240 "
        "colour camera asked for 30 pictures a second and a 160x120 thermal camera asked for 10 through "
        "the image server, a 1040-beam laser at 30 sweeps a second and the rest of the kit; the real-time "
        "factor, each camera's pictures a second and each laser's sweeps a second over --seconds of wall "
        "time, --runs times",
    )
    b.add_argument(
        "--antialias",
        type=int,
        choices=ANTIALIAS,
        default=4,
        help="with --league: the simulator's multisampling of pictures, as 'usarsim serve --antialias' "
        "(default: %(default)s)",
    )
    b.add_argument(
        "--env",
        action="store_true",
        help="measure the learning environments instead: Gymnasium steps per second of one P2AT at a "
        "0.1 s control period in lock-step, and PettingZoo steps per second of a team (--team)",
    )
    b.add_argument("--team", type=int, default=8, help="with --env: robots in the team (default: %(default)s)")
    b.add_argument(
        "--worlds",
        type=int,
        default=4,
        help="with --env: worlds of the vector environment timed on the direct path, in turns with "
        "one world (0 or 1: none; default: %(default)s)",
    )
    b.add_argument(
        "--transport",
        choices=("tcp", "inproc", "both"),
        default="both",
        help="with --env: the environments' path to the simulator: a usarsim serve process over TCP, "
        "the in-process direct path, or both one after the other (default: %(default)s)",
    )
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
    from usarsim.maps.cli import add_parsers as add_map_parsers

    add_map_parsers(sub)  # 'usarsim map' and 'usarsim score-map' (docs/scoring.md)
    from usarsim.compete.cli import add_parser as add_compete_parser

    add_compete_parser(sub)  # 'usarsim compete' (docs/competitions.md)
    from usarsim.ros2.cli import add_parser as add_ros2_parser

    r2 = add_ros2_parser(sub)  # 'usarsim ros2' (docs/ros2.md)
    for command in (s, v, w, r, b, rp, r2):  # -v and -vv after the command too: 'usarsim serve -v'
        _add_verbose(command, "verbose_after")
    return p
