"""SIGTERM in the middle of load (issue: reliability): 16 robots driving, a viewer asking
for pictures and a console page's worth of listeners open; the server is gone within 5 s
and every client sees its connection closed."""

from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import sys
import time

import pytest
from stress_scale import scaled

# wall-clock rates and deadlines: run by itself when the suite is shared among processes (scripts/test.sh)
pytestmark = pytest.mark.alone


def test_sigterm_during_load_closes_everything_within_5_s(tmp_path):
    from usarsim.bench import free_spots
    from usarsim.config.catalog import resolve_world

    n = scaled(16, 32)
    err = open(tmp_path / "serve.err", "w")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "usarsim",
            "serve",
            "--port",
            "0",
            "--truth-port",
            "0",
            "--image-port",
            "0",
            "--web-port",
            "0",
            "--wcs-port",
            "0",
            "--wss-port",
            "0",
            "--cominterface-port",
            "0",
            "--speed",
            "max",
        ],
        stdout=subprocess.PIPE,
        stderr=err,
        text=True,
    )
    ports = {}
    try:
        while len(ports) < 7:
            line = proc.stdout.readline()
            assert line, (tmp_path / "serve.err").read_text()
            m = re.match(r"usarsim: (\w+) listening on [\d.]+:(\d+)", line)
            if m:
                ports[m.group(1)] = int(m.group(2))
        poses = free_spots(resolve_world("DM-USAR_yellow"), n)
        client = subprocess.Popen(
            [sys.executable, "-m", "usarsim.bench", "--client", str(ports["control"]), json.dumps(poses), "60"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        viewer = socket.create_connection(("127.0.0.1", ports["image"]), timeout=30)
        viewer.sendall(b"OK" * 4)
        others = [
            socket.create_connection(("127.0.0.1", ports[k]), timeout=10)
            for k in ("truth", "comserver", "wss", "cominterface", "web")
        ]
        time.sleep(3.0)
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        took = time.monotonic() - t0
        print(f"\nSIGTERM with {n} robots driving: the server exited in {took:.2f} s (code {proc.returncode})")
        assert took < 5.0 and proc.returncode == 0
        for s in [viewer, *others]:  # every connection was closed by the server
            s.settimeout(5)
            try:
                while s.recv(65536):
                    pass
            except ConnectionResetError:
                pass
            s.close()
        assert client.wait(10) is not None
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
        proc.stdout.close()
        err.close()
