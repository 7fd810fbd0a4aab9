"""A small USARSim controller: spawn a P2AT, drive it forward and turn away from what its
laser sees ahead.  Standard library only: a TCP socket and the USARSim text protocol.

Run ``usarsim serve`` in one terminal, then, in another::

    python examples/drive_p2at.py [--host 127.0.0.1] [--port 3000] [--start NAME]
                                  [--speed 2.0 | --speed max] [--seconds 30]

Every line ends with CR LF and is made of ``{Key value}`` segments.  The lines it uses:

    (server, on connect)  NFO {Gametype BotDeathMatch} {Level MyArena} {TimeLimit 0}
    GETSTARTPOSES         -> NFO {StartPoses 2} {Start1 -3.00,0.00,-0.25 0.00,0.00,0.00 Start2 ...}
                             (for each pose: name, x,y,z in metres, roll,pitch,yaw in radians)
    INIT {ClassName USARBot.P2AT} {Name Robot1} {Start Start1}    spawns the robot at a start pose
    GETCONF {Type Robot}  -> CONF {Type GroundVehicle} ... {MaxSpeed 5.3850} ...
                             (the fastest a wheel turns, rad/s: what --speed max uses)
    DRIVE {Left 2} {Right 2}      wheel speeds in rad/s; {Left -2} {Right 2} turns left on the spot
    (server, several times a second)
        SEN {Time 12.3} {Type RangeScanner} {Name Scanner1} {Resolution 0.0174} {FOV 3.1416}
            {Range 4.21,4.19,...}  the laser: distances in metres, the first beam the rightmost
    (server, when it cannot do what was asked)  ERROR {Command INIT} {Reason ...}

The server runs in real time and sends its lines as they come: the controller reads them and
answers a laser scan with a DRIVE whenever it changes what it does.
"""

import argparse
import re
import socket
import sys
import time

TIMEOUT_S = 5.0  # the longest wait for the server before giving up
NEAR_M = 1.0  # something closer than this ahead: turn away from it
CLEAR_M = 1.6  # ... until the way ahead is this clear
AHEAD_RAD = 0.35  # "ahead": the beams within 20 degrees of the robot's heading


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


class Server:
    """The connection: lines out, lines in, never waiting longer than TIMEOUT_S."""

    def __init__(self, host: str, port: int):
        self.sock = socket.create_connection((host, port), timeout=TIMEOUT_S)
        self.lines = self.sock.makefile("r", encoding="ascii", newline="\r\n")

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


def drive(server: Server, start: str | None, speed_arg: str, seconds: float) -> None:
    print(server.read())  # NFO {Gametype ...} {Level ...} {TimeLimit ...}
    server.send("GETSTARTPOSES")
    poses = server.wait_for("NFO", "StartPoses")
    tokens = segments(poses)[1].split() if int(field(poses, "StartPoses")) > 0 else []
    names = tokens[0::3]  # name, x,y,z, roll,pitch,yaw for each pose
    print(f"start poses: {', '.join(names) or 'none'}")
    start = start or (names[0] if names else None)
    if start is None:
        raise ConnectionError("the world has no start pose")
    server.send(f"INIT {{ClassName USARBot.P2AT}} {{Name Robot1}} {{Start {start}}}")
    print(f"INIT: a P2AT at start pose {start}")
    if speed_arg == "max":
        server.send("GETCONF {Type Robot}")
        speed = float(field(server.wait_for("CONF", "MaxSpeed"), "MaxSpeed"))
    else:
        speed = float(speed_arg)
    print(f"driving at {speed:.2f} rad/s for {seconds:g} s")

    doing = None
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        line = server.read()
        if not line.startswith("SEN") or field(line, "Type") != "RangeScanner":
            continue
        ranges = [float(r) for r in field(line, "Range").split(",")]
        step = float(field(line, "Resolution"))
        fov = float(field(line, "FOV"))
        # beam i points at yaw fov/2 - i*step (right is positive yaw): keep those near 0
        ahead = min(r for i, r in enumerate(ranges) if abs(fov / 2 - i * step) <= AHEAD_RAD)
        half = len(ranges) // 2
        left_is_freer = sum(ranges[half:]) > sum(ranges[:half])  # the first beams are on the right
        if doing == "forward" and ahead < NEAR_M:
            doing = "left" if left_is_freer else "right"
        elif doing != "forward" and (doing is None or ahead > CLEAR_M):
            doing = "forward"
        else:
            continue  # nothing changes
        left, right = {"forward": (speed, speed), "left": (-speed, speed), "right": (speed, -speed)}[doing]
        server.send(f"DRIVE {{Left {left:.3f}}} {{Right {right:.3f}}}")
        what = "forward" if doing == "forward" else f"turning {doing} on the spot"
        print(f"{time.monotonic() - t0:5.1f} s: {ahead:.2f} m ahead: {what}", flush=True)
    server.send("DRIVE {Left 0} {Right 0}")
    print("stopped")


def main() -> int:
    ap = argparse.ArgumentParser(description="Drive a P2AT, turning away from what its laser sees ahead.")
    ap.add_argument("--host", default="127.0.0.1", help="the server's address (default 127.0.0.1)")
    ap.add_argument("--port", type=int, default=3000, help="its control port (default 3000)")
    ap.add_argument("--start", help="the start pose to spawn at (default: the first the server lists)")
    ap.add_argument("--speed", default="2.0", help="wheel speed in rad/s, or 'max' (default 2.0)")
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to drive (default 30)")
    args = ap.parse_args()
    if args.speed != "max":
        try:
            float(args.speed)
        except ValueError:
            ap.error(f"--speed: a number of rad/s or 'max', not {args.speed!r}")
    try:
        server = Server(args.host, args.port)
    except OSError as exc:
        print(f"drive_p2at: cannot connect to {args.host}:{args.port} ({exc.strerror or exc}); "
              "is 'usarsim serve' running?", file=sys.stderr)
        return 1
    try:
        drive(server, args.start, args.speed, args.seconds)
    except TimeoutError:
        print(f"drive_p2at: the server at {args.host}:{args.port} did not answer within {TIMEOUT_S:g} s",
              file=sys.stderr)
        return 1
    except OSError as exc:  # ConnectionError among them
        print(f"drive_p2at: {exc}", file=sys.stderr)
        return 1
    finally:
        server.sock.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
