"""Drive a P2AT with the Python client (usarsim.client): the same explorer as drive_p2at.py,
without a line of protocol text.  It starts a lock-step simulator of its own, or connects to a
running one with --port; it turns away from what its laser and front sonars see ahead, backs
away (then turns) when its bumper touches something, when it makes no headway for a second or
when it has not left one spot for two, and prints each decision.

    python examples/client_drive.py                        # a simulator of its own, 30 simulated s
    python examples/client_drive.py --port 3000            # a running 'usarsim serve' (real time)
    python examples/client_drive.py --port 3000 --lockstep # a running 'usarsim serve --lockstep'
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time

from usarsim.client import ClientError, ClientTimeout, connect, launch

SPEED = 3.0  # wheel speed, rad/s
WHEEL_RADIUS_M = 0.13  # a P2AT's (its GEO, protocol.md section 9): 3 rad/s is 0.39 m/s
NEAR_M, CLEAR_M = 1.0, 1.6  # the laser sees something this close ahead: turn until it is this clear
SONAR_NEAR_M = 0.5  # a front sonar (F4, F5: below the laser) reads less: something low ahead
STUCK_S, PROGRESS_M, PROGRESS_RAD = 1.0, 0.05, 0.15  # moving and turning less than this for 1 s: stuck
STAY_MAX_S = 2.0  # within PROGRESS_M of one place this long (turning on the spot, say): get away
BACK_S, ESCAPE_RAD = 1.0, 1.2  # getting away: back up for 1 s, then turn this far (70 degrees)
FREE_S = 2.0  # driving forward this long: it got away (the next turn may go either way)
NO_NEWS_S = 5.0  # real time: the longest the robot may hear nothing from the simulator


class Explorer:
    """Forward, turning on the spot, or getting away (backing up, then turning): one decision
    every tenth of a second, printed when it changes."""

    def __init__(self, world, robot):
        self.world, self.robot = world, robot
        self.t0 = 0.0  # the simulated time it started at: the times it prints count from there
        self.doing, self.since, self.start_yaw = None, 0.0, 0.0
        self.backed = -math.inf  # when it last began to back up
        self.side = None  # the way it turns until it gets going again (out of a dead end); None: either
        self.track: list[tuple[float, float, float, float]] = []  # (t, x, y, yaw): the last STUCK_S
        self.anchor = None  # (t, x, y): the place it has stayed within PROGRESS_M of since t

    def pose(self):
        truth = self.robot.ground_truth()  # ((x, y, z), (roll, pitch, yaw)), or None
        if truth is not None:
            return truth[0][0], truth[0][1], truth[1][2]
        return self.robot.odometry()  # (x, y, yaw) in odometry's frame, or None

    def do(self, doing: str, why: str, side: str | None = None) -> None:
        s = SPEED
        left, right = {"forward": (s, s), "back": (-s, -s), "left": (-s, s), "right": (s, -s)}[doing.split("-")[-1]]
        self.robot.drive(left=left, right=right)
        self.side = side or self.side
        self.backed = self.world.time if doing == "back" else self.backed
        self.doing, self.since = doing, self.world.time
        self.start_yaw = self.track[-1][3] if self.track else 0.0
        print(f"t={self.world.time - self.t0:5.1f} s {why}", flush=True)

    def stuck_for(self) -> float:
        """How long it has moved less than PROGRESS_M and turned less than PROGRESS_RAD (up to
        STUCK_S; 0: it made headway)."""
        if len(self.track) < 2:
            return 0.0
        (t, x, y, yaw), (t1, x1, y1, yaw1) = self.track[0], self.track[-1]
        still = math.hypot(x1 - x, y1 - y) < PROGRESS_M and abs(math.remainder(yaw1 - yaw, math.tau)) < PROGRESS_RAD
        return t1 - t if still and t1 - t >= STUCK_S - 0.05 else 0.0

    def decide(self) -> None:
        now, pose = self.world.time, self.pose()
        if pose is not None:
            self.track.append((now, *pose))
            while len(self.track) > 2 and self.track[1][0] <= now - STUCK_S:
                self.track.pop(0)
            if self.anchor is None or math.hypot(pose[0] - self.anchor[1], pose[1] - self.anchor[2]) >= PROGRESS_M:
                self.anchor = (now, pose[0], pose[1])
        scan = self.robot.scan()
        if scan is None:
            return
        ahead = float(scan.ranges[abs(scan.angles) < 0.35].min())
        freer = "left" if scan.ranges[scan.angles > 0].sum() > scan.ranges[scan.angles < 0].sum() else "right"
        sonar = self.robot.reading("Sonar")  # packed: every sonar of the robot
        low = min((i.range_m for i in sonar.items if i.name in ("F4", "F5")), default=math.inf) if sonar else math.inf
        touch = self.robot.reading("Touch")  # the front bumper
        touching = touch is not None and any(i.touching for i in touch.items)
        x, y = (pose[0], pose[1]) if pose else (math.nan, math.nan)
        turned = abs(math.remainder(pose[2] - self.start_yaw, math.tau)) if pose else 0.0
        doing, in_for, since_backed = self.doing, now - self.since, now - self.backed
        stayed = now - self.anchor[0] if self.anchor else 0.0
        if doing == "forward" and in_for >= FREE_S:
            self.side = None  # it got going again
        side = self.side or freer  # until then it turns on the same way round
        if doing != "back" and since_backed >= STUCK_S and (stuck := self.stuck_for()):
            self.do("back", f"stuck for {stuck:.1f} s at ({x:.2f}, {y:.2f}): backing up, then turning {side}", side)
        elif touching and doing not in ("back", "escape-left", "escape-right"):
            self.do("back", f"bumper touching at ({x:.2f}, {y:.2f}): backing up, then turning {side}", side)
        elif doing != "back" and since_backed >= STAY_MAX_S and stayed >= STAY_MAX_S:
            self.do("back", f"still at ({x:.2f}, {y:.2f}) after {stayed:.1f} s: backing up, then turning {side}", side)
        elif doing == "back":
            if in_for >= BACK_S:
                self.do(f"escape-{side}", f"turning {side} to get away", side)
        elif doing in ("escape-left", "escape-right") and turned < ESCAPE_RAD:
            pass  # still getting away
        elif doing in ("left", "right") and (ahead <= CLEAR_M or low <= SONAR_NEAR_M):
            pass  # still turning
        elif ahead < NEAR_M:
            self.do(side, f"turning {side} on the spot (laser {ahead:.2f} m ahead)", side)
        elif low < SONAR_NEAR_M:
            self.do(side, f"turning {side} on the spot (sonar {low:.2f} m ahead: something below the laser)", side)
        elif doing != "forward":
            self.do("forward", f"forward {SPEED * WHEEL_RADIUS_M:.2f} m/s (laser {ahead:.2f} m clear)")


def runs_in_lockstep(world, robot) -> bool:
    """Whether the server's clock stands still (it waits for STEP): nothing new arrives for
    the robot within a second of real time."""
    before = robot.time
    world.wait(1.0)
    return robot.time is None or robot.time == before


def drive(args) -> None:
    with contextlib.ExitStack() as stack:
        if args.port is None:
            world = stack.enter_context(launch(seed=1)).connect()
        else:
            where = f"{args.host}:{args.port}"
            try:
                world = connect(args.host, args.port, lockstep=args.lockstep)
            except ClientError as exc:
                if isinstance(exc.__cause__, OSError) and not isinstance(exc, ClientTimeout):
                    raise ClientError(
                        f"no simulator on {where}: start one with 'usarsim serve' (or bash scripts/serve.sh)"
                    ) from None
                raise
        stack.callback(world.close)
        start = args.start or world.start_poses[0].name
        robot = world.spawn("P2AT", start=start)
        if args.port is not None:
            lockstep = runs_in_lockstep(world, robot)
            if lockstep and not args.lockstep:
                raise ClientError(
                    f"the simulator on {where} runs in lock-step (usarsim serve --lockstep): add "
                    "--lockstep to step its clock from here, or start it without --lockstep"
                )
            if args.lockstep and not lockstep:
                raise ClientError(f"the simulator on {where} runs in real time: leave out --lockstep")
        print(f"a P2AT at {start} on {world.level}, for {args.seconds:g} simulated seconds", flush=True)
        explorer = Explorer(world, robot)
        t0 = explorer.t0 = world.time
        heard, heard_at = robot.time, time.monotonic()
        while world.time < t0 + args.seconds:
            world.step(0.1) if world.lockstep else world.wait(0.1)
            if robot.time != heard:
                heard, heard_at = robot.time, time.monotonic()
            elif time.monotonic() - heard_at > NO_NEWS_S:
                raise ClientTimeout(f"nothing from the simulator for {NO_NEWS_S:g} s")
            explorer.decide()
        robot.drive(left=0.0, right=0.0)
        odometry = robot.odometry()
        where = "odometry {:.2f}, {:.2f} m, heading {:.2f} rad".format(*odometry) if odometry else "no odometry"
        print(f"t={world.time - t0:5.1f} s stopped: {where}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--port", type=int, help="a running simulator's control port (default: start one)")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument(
        "--lockstep",
        action="store_true",
        help="with --port: the server was started with --lockstep; step its clock from here",
    )
    ap.add_argument("--start", help="the start pose (default: the world's first)")
    ap.add_argument("--seconds", type=float, default=30.0, help="simulated seconds to drive (default 30)")
    args = ap.parse_args()
    try:
        drive(args)
    except ClientError as exc:
        print(f"client_drive: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
