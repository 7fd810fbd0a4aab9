"""A minimal USARSim controller: spawn a P2AT, read its laser, drive it.

Run ``usarsim serve`` in one terminal, then ``python examples/drive_p2at.py``.
It uses nothing but a TCP socket and the USARSim text protocol, like any
controller written for USARSim 3.x.
"""

import socket
import sys
import time


def main(host: str = "127.0.0.1", port: int = 3000) -> None:
    sock = socket.create_connection((host, port))
    f = sock.makefile("rb")
    print(f.readline().decode().strip())  # NFO {Gametype BotDeathMatch} {Level ...} {TimeLimit 0}
    sock.sendall(b"GETSTARTPOSES\r\n")
    print(f.readline().decode().strip())
    sock.sendall(b"INIT {ClassName USARBot.P2AT} {Name Robot1} {Start PlayerStart1}\r\n")
    sock.sendall(b"DRIVE {Left 2} {Right 2}\r\n")  # 2 rad/s x 0.13 m wheels = 0.26 m/s forward
    start = time.monotonic()
    while time.monotonic() - start < 10:
        line = f.readline().decode().strip()
        if line.startswith("SEN") and "{Type RangeScanner}" in line:
            ranges = [float(v) for v in line.split("{Range ")[1].rstrip("}").split(",")]
            ahead = ranges[len(ranges) // 2]
            print(f"laser: {len(ranges)} beams, {ahead:.2f} m straight ahead")
            if ahead < 1.0:  # something close ahead: turn left on the spot
                sock.sendall(b"DRIVE {Left -1} {Right 1}\r\n")
            else:
                sock.sendall(b"DRIVE {Left 2} {Right 2}\r\n")
        elif line.startswith("SEN") and "{Type GroundTruth}" in line:
            print(line)
    sock.close()


if __name__ == "__main__":
    main(*(sys.argv[1:2] or ["127.0.0.1"]), *(int(p) for p in sys.argv[2:3]))
