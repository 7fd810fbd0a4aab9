"""The bench's client processes: ``python -m usarsim.bench --client PORT POSES SECONDS`` drives
N P2ATs (POSES: a JSON list of x, y, z, yaw); ``--round-trip-client PORT ROBOT COUNT`` times
COUNT lock-step round trips, with a P2AT when ROBOT is 1 (usarsim.bench.clients)."""

from __future__ import annotations

import asyncio
import json
import sys

from usarsim.bench.clients import drive_clients, round_trip_client


def main(argv: list[str]) -> int:
    if len(argv) == 4 and argv[0] == "--client":
        asyncio.run(drive_clients(int(argv[1]), json.loads(argv[2]), float(argv[3])))
        return 0
    if len(argv) == 4 and argv[0] == "--round-trip-client":
        round_trip_client(int(argv[1]), argv[2] == "1", int(argv[3]))
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
