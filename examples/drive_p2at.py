"""A small USARSim controller: spawn a P2AT and explore.  It turns away from what its laser and
front sonars see ahead; when its bumper touches something, when it makes no headway for a
second (caught on something low that neither sees) or when it has not left one spot for two
seconds, it backs up and turns (stuck again on the same spot, it lunges forward instead, and
turns the other way).  Standard library only: a TCP socket and the USARSim text protocol.

Run ``usarsim serve`` (or ``bash scripts/serve.sh``) in one terminal, then, in another::

    python examples/drive_p2at.py [--host 127.0.0.1] [--port 3000] [--start NAME]
                                  [--speed 2.0 | --speed max] [--seconds 30] [--lockstep]

It prints one line per decision, with the simulated time since it started driving::

    t=  0.0 s forward 0.26 m/s (laser 3.38 m clear)
    t= 16.2 s turning left on the spot (sonar 0.46 m ahead: something below the laser)
    t= 16.8 s forward 0.26 m/s (laser 2.24 m clear)
    t= 20.0 s turning left on the spot (laser 0.65 m ahead)
    t= 36.0 s stuck for 1.0 s at (-3.77, -2.98): backing up, then turning left
    t= 37.0 s turning left to get away

Every line ends with CR LF and is made of ``{Key value}`` segments.  The lines it uses:

    (server, on connect)  NFO {Gametype BotDeathMatch} {Level MyArena} {TimeLimit 0}
    GETSTARTPOSES         -> NFO {StartPoses 2} {Start1 -3.00,0.00,-0.25 0.00,0.00,0.00 Start2 ...}
                             (for each pose: name, x,y,z in metres, roll,pitch,yaw in radians)
    INIT {ClassName USARBot.P2AT} {Name Robot1} {Start Start1}    spawns the robot at a start pose
    GETCONF {Type Robot}  -> CONF {Type GroundVehicle} ... {MaxSpeed 5.3850} ...
                             (the fastest a wheel turns, rad/s: what --speed max uses)
    GETGEO {Type Robot}   -> GEO {Type GroundVehicle} ... {WheelRadius 0.1300} {WheelSeparation 0.4712} ...
    PING {Id 1}           -> PONG {Id 1} {Time 6.1000}   (the simulated time: it stands still
                             on a server started with --lockstep, which this example checks)
    DRIVE {Left 2} {Right 2}      wheel speeds in rad/s; {Left -2} {Right 2} turns left on the spot
    STEP {Time 0.1}       -> STEPPED {Time 6.2000}   (lock-step only: advance the world 0.1 s)
    (server, several times a simulated second, from the robot's sensors)
        SEN {Time 12.3} {Type RangeScanner} {Name Scanner1} {Resolution 0.0174} {FOV 3.1416}
            {Range 4.21,4.19,...}  the laser: distances in metres, the first beam the rightmost
        SEN {Time 12.3} {Type Sonar} {Name F1 Range 5.0000} ... {Name R8 Range 5.0000}
            the sonars: F4 and F5 look ahead, below the laser; R4 and R5 behind
        SEN {Time 12.3} {Type Touch} {Name Touch Touch False}   the front bumper
        SEN {Time 12.3} {Type GroundTruth} {Name GroundTruth} {Location x,y,z} {Orientation r,p,y}
            where the robot is (its Odometry {Pose x,y,yaw} serves when there is no GroundTruth)
    (server, when it cannot do what was asked)  ERROR {Command INIT} {Reason ...}

In real time the server sends its lines as they come and the controller answers each laser
scan; with --lockstep (a server started with ``usarsim serve --lockstep``) the controller
advances the world itself, 0.1 s at a time, and answers the scans each step brings.
"""

import argparse
import math
import re
import socket
import sys
import time

TIMEOUT_S = 5.0  # the longest wait for the server before giving up
NEAR_M = 1.0  # the laser sees something closer than this ahead: turn away from it
CLEAR_M = 1.6  # ... until the way ahead is this clear
AHEAD_RAD = 0.35  # "ahead": the beams within 20 degrees of the robot's heading
SONAR_AHEAD = ("F4", "F5")  # the front sonars 10 degrees either side of ahead
SONAR_NEAR_M = 0.5  # a front sonar reads less than this: something (low, perhaps) ahead
SONAR_BEHIND = ("R4", "R5")
SONAR_BEHIND_M = 0.3  # backing up stops when something is this close behind
STUCK_S = 1.0  # moving less than PROGRESS_M and turning less than PROGRESS_RAD for this long: stuck
PROGRESS_M = 0.05
PROGRESS_RAD = 0.15
STAY_MAX_S = 2.0  # within PROGRESS_M of one place this long (turning on the spot, say): get away
GETAWAY_S = 1.0  # getting away: backing up for this long,
AGAIN_M = 0.15  # (stuck again within this of where it backed up from: lunging forward instead)
ESCAPE_RAD = 1.2  # then turning on the spot this far (about 70 degrees)
FREE_S = 2.0  # driving forward this long: it got away (the next turn may go either way)
STEP_S = 0.1  # lock-step: the world advances this much between decisions
# a P2AT's, when the server does not say (its CONF and GEO lines, protocol.md section 9)
MAX_WHEEL_RAD_S, WHEEL_RADIUS_M, WHEEL_SEPARATION_M = 5.385, 0.13, 0.4712


def segments(line: str) -> list[str]:
    """The contents of a line's {...} segments: 'SEN {Type X} {Range 1,2}' -> ['Type X', 'Range 1,2']."""
    return re.findall(r"\{([^{}]*)\}", line)


def field(line: str, key: str) -> str | None:
    """The value of segment ``key`` of a line, or None."""
    for seg in segments(line):
        k, _, value = seg.partition(" ")
        if k == key:
            return value
    return None


def numbers(text: str) -> list[float]:
    return [float(v) for v in text.split(",")]


class Unsuitable(Exception):
    """The server is not one this controller can drive as asked (a one-line reason)."""


class Server:
    """The connection: lines out, lines in, never waiting longer than TIMEOUT_S."""

    def __init__(self, host: str, port: int):
        self.sock = socket.create_connection((host, port), timeout=TIMEOUT_S)
        self.lines = self.sock.makefile("r", encoding="ascii", newline="\r\n")
        self.pings = 0

    def send(self, text: str) -> None:
        self.sock.sendall(text.encode("ascii") + b"\r\n")

    def read(self) -> str:
        line = self.lines.readline().strip()  # raises TimeoutError after TIMEOUT_S
        if not line:
            raise ConnectionError("the server closed the connection")
        if line.startswith("ERROR"):
            raise ConnectionError(f"the server refused a request: {line}")
        return line

    def wait_for(self, head: str, key: str) -> str:
        """Read until a line starting with ``head`` that has segment ``key`` (others are skipped)."""
        while True:
            line = self.read()
            if line.startswith(head) and field(line, key) is not None:
                return line

    def clock(self) -> float:
        """The server's simulated time (PING, and its PONG)."""
        self.pings += 1
        self.send(f"PING {{Id {self.pings}}}")
        while True:
            line = self.wait_for("PONG", "Time")
            if field(line, "Id") == str(self.pings):
                return float(field(line, "Time"))


class Explorer:
    """What the robot knows (its latest readings) and what it does: forward, turning on the
    spot, or getting away (backing up, then turning) from where it makes no headway."""

    def __init__(self, server: Server, wheel_speed: float, wheel_radius: float, wheel_separation: float):
        self.server = server
        self.speed = wheel_speed
        self.wheel_radius = wheel_radius
        # headway: at most PROGRESS_M and PROGRESS_RAD, and no more than a third of how far it
        # drives in STUCK_S, or turns on the spot (2 v / separation, which a skid-steered robot's
        # wheels slip down to about half)
        v = wheel_speed * wheel_radius
        self.progress_m = min(PROGRESS_M, v * STUCK_S / 3)
        self.progress_rad = min(PROGRESS_RAD, v / wheel_separation * STUCK_S / 3)
        self.t0 = None  # the simulated time of the first reading
        self.now = 0.0  # simulated seconds since then
        self.truth = None  # (x, y, yaw) from GroundTruth
        self.odometry = None  # (x, y, yaw) from Odometry
        self.sonar: dict[str, float] = {}
        self.touching = False
        # "forward", "left", "right" (on the spot), "back" or "lunge" (forward), "escape-left"/"escape-right"
        self.doing = None
        self.since = 0.0  # when it started doing it
        self.since_pose = None  # and where it was then
        self.backed = -math.inf  # when it last began to get away (backing up, or lunging forward)
        self.got_away_from = None  # (x, y) where it did
        self.tries = 0  # how many times in a row it tried to get away from there
        self.side = None  # the way it turns until it gets going again ("left", "right"; None: either)
        self.track: list[tuple[float, float, float, float]] = []  # (t, x, y, yaw) over the last STUCK_S
        self.anchor = None  # (t, x, y): where it came within PROGRESS_M of, and when
        self.driven_m = 0.0

    # what it knows -------------------------------------------------------------------
    @property
    def pose(self):
        return self.truth if self.truth is not None else self.odometry

    def where(self) -> str:
        p = self.pose
        return "(?, ?)" if p is None else f"({p[0]:.2f}, {p[1]:.2f})"

    def clock(self, t: float) -> None:
        """The simulated time of the latest line (a reading, or the end of a lock-step STEP)."""
        if self.t0 is None:
            self.t0 = t
        self.now = max(self.now, t - self.t0)

    def take(self, line: str) -> bool:
        """Note what a SEN line says; True for a laser scan (time to decide)."""
        kind = field(line, "Type")
        t = field(line, "Time")
        if t is not None:
            self.clock(float(t))
        if kind == "GroundTruth":
            (x, y, _), (_, _, yaw) = numbers(field(line, "Location")), numbers(field(line, "Orientation"))
            if self.truth is None:
                self.track, self.anchor = [], None  # from now on, where GroundTruth says (not odometry)
            self.truth = (x, y, yaw)
            self.moved()
        elif kind == "Odometry":
            self.odometry = tuple(numbers(field(line, "Pose")))
            if self.truth is None:
                self.moved()
        elif kind == "Sonar":
            for seg in segments(line):  # 'Name F4 Range 0.8123'
                parts = seg.split()
                if len(parts) == 4 and parts[0] == "Name" and parts[2] == "Range":
                    self.sonar[parts[1]] = float(parts[3])
        elif kind == "Touch":
            self.touching = " True" in line  # {Name Touch Touch True}
        return kind == "RangeScanner"

    def moved(self) -> None:
        x, y, yaw = self.pose
        if self.track:
            px, py, _ = self.track[-1][1:]
            self.driven_m += math.hypot(x - px, y - py)
        self.track.append((self.now, x, y, yaw))
        while len(self.track) > 2 and self.track[1][0] <= self.now - STUCK_S:
            self.track.pop(0)
        if self.anchor is None or math.hypot(x - self.anchor[1], y - self.anchor[2]) >= self.progress_m:
            self.anchor = (self.now, x, y)

    def stuck_for(self) -> float:
        """How long the robot has made no headway (moved less than progress_m and turned less
        than progress_rad), up to STUCK_S; 0 when it has."""
        if len(self.track) < 2:
            return 0.0
        (t, x, y, yaw), (t1, x1, y1, yaw1) = self.track[0], self.track[-1]
        if t1 - t < STUCK_S - 0.05:
            return 0.0
        if (
            math.hypot(x1 - x, y1 - y) < self.progress_m
            and abs(math.remainder(yaw1 - yaw, math.tau)) < self.progress_rad
        ):
            return t1 - t
        return 0.0

    def stayed_for(self) -> float:
        """How long the robot has been within progress_m of one place (turning or not)."""
        return 0.0 if self.anchor is None else self.now - self.anchor[0]

    def turned(self) -> float:
        """How far it turned since it began doing what it does (radians)."""
        if self.pose is None or self.since_pose is None:
            return 0.0
        return abs(math.remainder(self.pose[2] - self.since_pose[2], math.tau))

    # what it does --------------------------------------------------------------------
    def do(self, doing: str, why: str, side: str | None = None) -> None:
        """Drive the wheels for ``doing``; ``side``: the way it turns until it gets going again."""
        self.side = side or self.side
        s = self.speed
        left, right = {
            "forward": (s, s),
            "back": (-s, -s),
            "lunge": (s, s),
            "left": (-s, s),
            "right": (s, -s),
            "escape-left": (-s, s),
            "escape-right": (s, -s),
        }[doing]
        self.server.send(f"DRIVE {{Left {left:.3f}}} {{Right {right:.3f}}}")
        self.doing, self.since, self.since_pose = doing, self.now, self.pose
        print(f"t={self.now:5.1f} s {why}", flush=True)

    def get_away(self, why: str, side: str) -> None:
        """Back up (then turn); stuck again where it was a moment ago: lunge forward instead,
        every other time, and turn the other way (rocking free of what it is caught on)."""
        p = self.pose
        again = (
            p is not None
            and self.got_away_from is not None
            and self.now - self.backed < 2 * (GETAWAY_S + STUCK_S)
            and math.hypot(p[0] - self.got_away_from[0], p[1] - self.got_away_from[1]) < AGAIN_M
        )
        self.tries = self.tries + 1 if again else 0
        if self.tries % 2:
            side = "left" if side == "right" else "right"
        self.backed, self.got_away_from = self.now, p
        self.do(
            "lunge" if self.tries % 2 else "back",
            f"{why}: {'lunging forward' if self.tries % 2 else 'backing up'}, then turning {side}",
            side,
        )

    def decide(self, scan: str) -> None:
        ranges = numbers(field(scan, "Range"))
        step = float(field(scan, "Resolution"))
        fov = float(field(scan, "FOV"))
        # beam i points at yaw fov/2 - i*step (right is positive yaw): keep those near 0
        ahead = min(r for i, r in enumerate(ranges) if abs(fov / 2 - i * step) <= AHEAD_RAD)
        half = len(ranges) // 2
        freer = "left" if sum(ranges[half:]) > sum(ranges[:half]) else "right"  # the first beams are on the right
        low = min((self.sonar.get(n, math.inf) for n in SONAR_AHEAD), default=math.inf)
        behind = min((self.sonar.get(n, math.inf) for n in SONAR_BEHIND), default=math.inf)
        doing, in_for = self.doing, self.now - self.since
        if doing == "forward" and in_for >= FREE_S:
            self.side = None  # it got going again: the next obstacle may be turned from either way
        side = self.side or freer  # until then, it turns on the same way round: out of a dead end
        getting_away = doing in ("back", "lunge", "escape-left", "escape-right")
        since_backed = self.now - self.backed

        if doing not in ("back", "lunge") and since_backed >= STUCK_S and (stuck := self.stuck_for()):
            self.get_away(f"stuck for {stuck:.1f} s at {self.where()}", side)
        elif self.touching and not getting_away:
            self.get_away(f"bumper touching at {self.where()}", side)
        elif doing not in ("back", "lunge") and since_backed >= STAY_MAX_S and self.stayed_for() >= STAY_MAX_S:
            self.get_away(f"still at {self.where()} after {self.stayed_for():.1f} s", side)
        elif doing in ("back", "lunge"):
            if in_for >= GETAWAY_S or (doing == "back" and behind < SONAR_BEHIND_M):
                self.do(f"escape-{side}", f"turning {side} to get away", side)
        elif doing in ("escape-left", "escape-right"):
            if self.turned() >= ESCAPE_RAD:  # then on the same way round while the way is blocked
                self.forward_or_turn(ahead, low, side, force=True)
        elif doing in ("left", "right"):
            if ahead > CLEAR_M and low > SONAR_NEAR_M:
                self.forward_or_turn(ahead, low, side, force=True)
        else:  # forward, or nothing yet
            self.forward_or_turn(ahead, low, side, force=doing is None)

    def forward_or_turn(self, ahead: float, low: float, side: str, force: bool) -> None:
        if ahead < NEAR_M:
            self.do(side, f"turning {side} on the spot (laser {ahead:.2f} m ahead)", side)
        elif low < SONAR_NEAR_M:
            self.do(side, f"turning {side} on the spot (sonar {low:.2f} m ahead: something below the laser)", side)
        elif force or self.doing != "forward":
            self.do("forward", f"forward {self.speed * self.wheel_radius:.2f} m/s (laser {ahead:.2f} m clear)")


def drive(server: Server, start: str | None, speed_arg: str, seconds: float, lockstep: bool, address: str) -> None:
    print(server.read())  # NFO {Gametype ...} {Level ...} {TimeLimit ...}
    t1 = server.clock()
    time.sleep(0.5)
    server_lockstep = server.clock() == t1  # its clock stood still: it waits for STEP
    if server_lockstep and not lockstep:
        raise Unsuitable(
            f"the simulator on {address} runs in lock-step (usarsim serve --lockstep): "
            "add --lockstep to step its clock from here, or start it without --lockstep"
        )
    if lockstep and not server_lockstep:
        raise Unsuitable(
            f"the simulator on {address} runs in real time: leave out --lockstep "
            "(it is for a server started with usarsim serve --lockstep)"
        )
    server.send("GETSTARTPOSES")
    poses = server.wait_for("NFO", "StartPoses")
    tokens = segments(poses)[1].split() if int(field(poses, "StartPoses")) > 0 else []
    names = tokens[0::3]  # name, x,y,z, roll,pitch,yaw for each pose
    print(f"start poses: {', '.join(names) or 'none'}")
    start = start or (names[0] if names else None)
    if start is None:
        raise Unsuitable("the world has no start pose")
    server.send(f"INIT {{ClassName USARBot.P2AT}} {{Name Robot1}} {{Start {start}}}")
    print(f"INIT: a P2AT at start pose {start}")
    server.send("GETCONF {Type Robot}")
    conf = server.wait_for("CONF", "Type")
    speed = float(field(conf, "MaxSpeed") or MAX_WHEEL_RAD_S) if speed_arg == "max" else float(speed_arg)
    server.send("GETGEO {Type Robot}")
    geo = server.wait_for("GEO", "Type")
    wheel_radius = float(field(geo, "WheelRadius") or WHEEL_RADIUS_M)
    wheel_separation = float(field(geo, "WheelSeparation") or WHEEL_SEPARATION_M)
    print(
        f"driving at {speed:.2f} rad/s for {seconds:g} s" + (" (lock-step: 0.1 s a step)" if lockstep else ""),
        flush=True,
    )

    robot = Explorer(server, speed, wheel_radius, wheel_separation)
    if lockstep:
        server.send(f"STEP {{Time {STEP_S}}}")
    while robot.t0 is None or robot.now < seconds:
        line = server.read()
        if line.startswith("SEN") and robot.take(line):
            robot.decide(line)
        elif line.startswith("STEPPED"):
            robot.clock(float(field(line, "Time")))  # time goes on even when no reading comes
            server.send(f"STEP {{Time {STEP_S}}}")
    server.send("DRIVE {Left 0} {Right 0}")
    print(f"t={robot.now:5.1f} s stopped at {robot.where()}, {robot.driven_m:.1f} m driven")


def main() -> int:
    ap = argparse.ArgumentParser(
        description="Drive a P2AT around, turning away from what it sees ahead and "
        "backing away from where it gets stuck."
    )
    ap.add_argument("--host", default="127.0.0.1", help="the server's address (default 127.0.0.1)")
    ap.add_argument("--port", type=int, default=3000, help="its control port (default 3000)")
    ap.add_argument("--start", help="the start pose to spawn at (default: the first the server lists)")
    ap.add_argument("--speed", default="2.0", help="wheel speed in rad/s, or 'max' (default 2.0)")
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to drive, in simulated seconds (default 30)")
    ap.add_argument(
        "--lockstep",
        action="store_true",
        help="the server was started with --lockstep: advance its clock from here, 0.1 s a step",
    )
    args = ap.parse_args()
    if args.speed != "max":
        try:
            float(args.speed)
        except ValueError:
            ap.error(f"--speed: a number of rad/s or 'max', not {args.speed!r}")
    address = f"{args.host}:{args.port}"
    try:
        server = Server(args.host, args.port)
    except OSError as exc:
        why = "connection refused" if isinstance(exc, ConnectionRefusedError) else (exc.strerror or str(exc))
        print(
            f"drive_p2at: no simulator on {address} ({why}): start one with 'usarsim serve' (or bash scripts/serve.sh)",
            file=sys.stderr,
        )
        return 1
    try:
        drive(server, args.start, args.speed, args.seconds, args.lockstep, address)
    except Unsuitable as exc:
        print(f"drive_p2at: {exc}", file=sys.stderr)
        return 1
    except TimeoutError:
        print(f"drive_p2at: the server at {address} did not answer within {TIMEOUT_S:g} s", file=sys.stderr)
        return 1
    except OSError as exc:  # ConnectionError among them
        print(f"drive_p2at: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        try:
            server.send("DRIVE {Left 0} {Right 0}")
        except OSError:
            pass
        return 130
    finally:
        server.sock.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
