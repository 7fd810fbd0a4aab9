"""The ROS 2 tests' parts: the bridge (``usarsim ros2``) in a process of its own, and a probe: a
real rclpy node in the test's process that subscribes, publishes and calls services (the relay
between bridge and simulator is helpers.Tap)."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import rclpy


class Bridge:
    """``usarsim ros2`` in a process of its own."""

    def __init__(self, port: int, domain: int, *args: str, env: dict[str, str] | None = None):
        cmd = [sys.executable, "-m", "usarsim", "ros2", "--port", str(port), "--domain", str(domain), *args]
        self.proc = subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            start_new_session=True,
        )
        self.ready_line = self.proc.stdout.readline()  # the ready line, or '' when it failed
        self.stderr = ""

    @property
    def ready(self) -> bool:
        return self.ready_line.startswith("usarsim ros2:")

    def stop(self, timeout: float = 20.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            _, self.stderr = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.send_signal(signal.SIGUSR1)  # the bridge prints every thread's stack
            time.sleep(1.0)
            self.proc.kill()
            _, self.stderr = self.proc.communicate()
        return self.proc.returncode


class Probe:
    """A real rclpy node in the test's process: subscriptions kept in lists, publishers and
    service calls."""

    def __init__(self, domain: int):
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.signals import SignalHandlerOptions

        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain, signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node("usarsim_test_probe", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.received: dict[str, list[Any]] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def subscribe(self, topic: str, msg_type: Any, qos: Any = 50) -> list[Any]:
        out = self.received.setdefault(topic, [])

        def keep(msg: Any) -> None:
            with self._lock:
                out.append(msg)

        self.node.create_subscription(msg_type, topic, keep, qos)
        return out

    def messages(self, topic: str) -> list[Any]:
        with self._lock:
            return list(self.received.get(topic, []))

    def wait(self, predicate: Callable[[], Any], timeout: float = 20.0, what: str = "the condition") -> Any:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            value = predicate()
            if value:
                return value
            time.sleep(0.02)
        raise AssertionError(f"{what} did not come within {timeout:g} s")

    def publisher(self, topic: str, msg_type: Any) -> Any:
        pub = self.node.create_publisher(msg_type, topic, 10)
        self.wait(lambda: pub.get_subscription_count() > 0, what=f"a subscriber of {topic}")
        return pub

    def call(self, service: str, srv_type: Any, timeout: float = 20.0) -> Any:
        client = self.node.create_client(srv_type, service)
        assert client.wait_for_service(timeout_sec=timeout), f"no service {service}"
        future = client.call_async(srv_type.Request())
        self.wait(future.done, timeout, f"the reply of {service}")
        return future.result()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.context.try_shutdown()
