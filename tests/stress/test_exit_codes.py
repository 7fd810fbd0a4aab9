"""No crash at any scale: large runs end with exit code 0, every time.

``usarsim bench`` with many robots exits normally after printing its figures, and ``usarsim
serve`` with many robots connected exits on SIGTERM; each cycle repeated.  Before the
simulation thread was stopped in order, about one large run in two died at exit with a
segmentation fault (the interpreter finalised while that thread was still compiling a MuJoCo
model).  Reduced in CI; ``USARSIM_STRESS=full`` runs the README's sizes (256 robots for 5 s
in bench, 128 robots on serve, 20 cycles each)."""

from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import sys
import time

from stress_scale import scaled


def test_bench_exits_0_after_large_runs(tmp_path):
    robots, seconds, cycles = scaled(64, 256), scaled(1, 5), scaled(2, 20)
    codes = []
    for i in range(cycles):
        out = subprocess.run(
            [sys.executable, "-m", "usarsim", "bench", "--robots", str(robots), "--seconds", str(seconds), "--json"],
            capture_output=True,
            text=True,
            timeout=900,
            stdin=subprocess.DEVNULL,
        )
        codes.append(out.returncode)
        assert out.returncode == 0, (i, out.returncode, out.stderr[-3000:])
        result = json.loads(out.stdout.strip().splitlines()[-1])
        assert result["robots"] == robots and result["sim_seconds"] >= seconds - 0.05
    print(f"\nbench --robots {robots} --seconds {seconds}: {cycles} runs, exit codes {codes}")


def _serve_with_robots(tmp_path, robots: int, i: int) -> tuple[int, float]:
    from usarsim.bench import free_spots
    from usarsim.config.catalog import resolve_world

    err_path = tmp_path / f"serve{i}.err"
    with open(err_path, "w") as err:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "usarsim",
                "serve",
                "--port",
                "0",
                "--port-offset",
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
                "--max-connections",
                str(robots + 8),
            ],
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            stdin=subprocess.DEVNULL,
        )
        client = None
        try:
            ports: dict[str, int] = {}
            while "control" not in ports or "truth" not in ports:
                line = proc.stdout.readline()
                assert line, err_path.read_text()
                m = re.match(r"usarsim: (\w+) listening on [\d.]+:(\d+)", line)
                if m:
                    ports[m.group(1)] = int(m.group(2))
            poses = free_spots(resolve_world("DM-USAR_yellow"), robots)
            client = subprocess.Popen(
                [sys.executable, "-m", "usarsim.bench", "--client", str(ports["control"]), json.dumps(poses), "600"],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            deadline = time.monotonic() + 300
            while _robots_in_world(ports["truth"]) < robots:  # every robot in the world and driving
                assert time.monotonic() < deadline, f"{robots} robots never all stood in the world"
                time.sleep(0.5)
            time.sleep(1.0)
            t0 = time.monotonic()
            proc.send_signal(signal.SIGTERM)
            code = proc.wait(120)
            return code, time.monotonic() - t0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
            proc.stdout.close()
            if client is not None:
                client.kill()
                client.wait(10)


def _robots_in_world(truth_port: int) -> int:
    """How many robots the ground-truth service sees now."""
    with socket.create_connection(("127.0.0.1", truth_port), timeout=30) as s:
        s.sendall(b"{Class P2AT}\r\n")
        data = b""
        while b"{End}" not in data:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    return data.count(b"{Class P2AT}")


def test_serve_with_many_robots_exits_0_on_sigterm(tmp_path):
    robots, cycles = scaled(32, 128), scaled(2, 20)
    results = [_serve_with_robots(tmp_path, robots, i) for i in range(cycles)]
    print(
        f"\nserve with {robots} robots, SIGTERM: {cycles} runs, exit codes {[c for c, _ in results]}, "
        f"{min(t for _, t in results):.2f} to {max(t for _, t in results):.2f} s to exit"
    )
    assert all(c == 0 for c, _ in results), results
