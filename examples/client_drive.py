"""Drive a P2AT with the Python client (usarsim.client): the same robot as drive_p2at.py, without
a line of protocol text.  It starts a lock-step simulator of its own, or connects to a running
one with --port (then in real time), turns away from walls and prints what it does.

    python examples/client_drive.py                 # a simulator of its own, 30 simulated seconds
    python examples/client_drive.py --port 3000     # a running 'usarsim serve'
"""

from __future__ import annotations

import argparse
import contextlib

from usarsim.client import connect, launch


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--port", type=int, help="a running simulator's control port (default: start one)")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--seconds", type=float, default=30.0, help="simulated seconds to drive (default 30)")
    args = ap.parse_args()
    with contextlib.ExitStack() as stack:
        if args.port is None:
            world = stack.enter_context(launch(seed=1)).connect()
        else:
            world = connect(args.host, args.port)
        stack.callback(world.close)
        robot = world.spawn("P2AT", start=world.start_poses[0].name)
        turning = False
        for _ in range(int(args.seconds / 0.1)):
            scan = robot.scan()
            ahead = scan.ranges[abs(scan.angles) < 0.35].min() if scan else 99.0
            touch = robot.reading("Touch")  # the front bumper: something low the laser misses
            if touch is not None and any(t.touching for t in touch.items):
                ahead = 0.0
            if ahead < 0.8 and not turning:
                print(f"t={world.time:5.1f} s: " + ("bumped into something" if ahead == 0.0 else
                                                     f"wall {ahead:.2f} m ahead") + ", turning")
            elif ahead > 1.5 and turning:
                print(f"t={world.time:5.1f} s: clear ahead, driving on")
            turning = ahead < 0.8 or (turning and ahead <= 1.5)
            robot.drive(left=-1.5, right=1.5) if turning else robot.drive(left=3.0, right=3.0)
            world.step(0.1) if world.lockstep else world.wait(0.1)
        x, y, yaw = robot.odometry()
        print(f"t={world.time:5.1f} s: odometry {x:.2f}, {y:.2f} m, heading {yaw:.2f} rad")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
