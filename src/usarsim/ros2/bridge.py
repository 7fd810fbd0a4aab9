"""The ROS 2 bridge: robots of a running simulator on the ROS 2 graph.

The bridge is an ordinary protocol client in a process of its own (DDS and rclpy never share the
simulation's interpreter): it connects to a simulator (this one or any USARSim server), spawns
its robots, asks each for its GETGEO and GETCONF, and then turns what the robots send into ROS 2
messages and ROS 2 commands into protocol lines.  docs/ros2.md has the topic and frame tables.

Threads: the main thread owns the sockets (reads the robots' messages, publishes, and in
lock-step mode drives the clock); rclpy's executor runs in a second thread and only queues what
subscribers and services ask for, which the main thread carries out between reads.
"""

from __future__ import annotations

import logging
import queue
import selectors
import threading
import time
from collections.abc import Callable
from typing import Any

from usarsim.client.blocking import World
from usarsim.client.core import ClientError
from usarsim.protocol import messages as M

from .convert import ros_pose
from .robot import NODE_NAME, RobotBridge, RobotSpec, b_time

log = logging.getLogger("usarsim.ros2")

REAL_TIME_REFUSAL = "the simulator runs in real time: start it with --lockstep"


class Bridge:
    """Robots of one simulator on one ROS 2 domain (see the module's docstring)."""

    def __init__(
        self,
        world: World,
        *,
        period: float = 0.1,
        rtf: float = 1.0,
        frame_prefix: bool = True,
        stamped: bool = False,
        bag: str | None = None,
        camera_hz: float = 5.0,
        map_tf: bool = False,
    ):
        import rclpy
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        from rclpy.signals import SignalHandlerOptions

        self.world = world
        self.period = period
        self.rtf = rtf
        self.frame_prefix = frame_prefix
        self.stamped = stamped
        self.camera_hz = camera_hz
        self.map_tf = map_tf
        self.robots: dict[str, RobotBridge] = {}
        self.commands: queue.SimpleQueue[tuple[RobotBridge | None, Any]] = queue.SimpleQueue()
        self.sim_time = 0.0
        self.paused = False
        self._steps_asked = 0
        self._step_done = threading.Condition()
        # a plain flag, not an Event: stop() runs in a signal handler, which must take no lock
        self._halt = False
        self.context = rclpy.Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        from rclpy.experimental import EventsExecutor
        from rclpy.node import Node

        self.node = Node(NODE_NAME, context=self.context)
        # reliable: both reliable subscribers (RViz, Nav2) and best-effort ones (sensor data QoS) match it
        self.qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
        tf_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
        # as tf2_ros's static broadcaster: the latest message kept for subscribers that come later
        static_qos = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
            history=HistoryPolicy.KEEP_LAST,
        )
        from rosgraph_msgs.msg import Clock
        from std_srvs.srv import Trigger
        from tf2_msgs.msg import TFMessage

        self._clock_pub = self.node.create_publisher(Clock, "/clock", self.qos)
        self._tf_pub = self.node.create_publisher(TFMessage, "/tf", tf_qos)
        self._tf_static_pub = self.node.create_publisher(TFMessage, "/tf_static", static_qos)
        self._static: list[Any] = []
        for name, handler in (
            ("pause", self._switch("pause")),
            ("resume", self._switch("resume")),
            ("step", self._srv_step),
        ):
            self.node.create_service(Trigger, f"/usarsim/{name}", handler)
        self.recorder = None
        if bag:
            from .bag import BagWriter

            self.recorder = BagWriter(bag)
        # rclpy's events executor: the default one builds a wait set of every publisher's QoS
        # events each time it looks (milliseconds with 16 robots' 420 publishers), holding the
        # interpreter lock while the main thread publishes a burst of readings
        self.executor = EventsExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._spin_thread = threading.Thread(target=self._spin, name="ros2-executor", daemon=True)
        self._spin_thread.start()

    # rclpy's thread ---------------------------------------------------------------------------
    def _spin(self) -> None:
        while not self._halt:
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception as exc:  # an exception in a callback: logged, the bridge goes on
                if self._halt:
                    break
                log.warning("ROS 2 callback failed: %s", exc)

    def _switch(self, what: str) -> Callable[[Any, Any], Any]:
        """The service that pauses or resumes the clock (``what``: "pause" or "resume")."""

        def handle(request: Any, response: Any) -> Any:
            if not self.world.lockstep:
                response.success, response.message = False, REAL_TIME_REFUSAL
            else:
                self.commands.put((None, what))
                response.success, response.message = True, f"{what}d"
            return response

        return handle

    def _srv_step(self, request: Any, response: Any) -> Any:
        if not self.world.lockstep:
            response.success, response.message = False, REAL_TIME_REFUSAL
            return response
        with self._step_done:
            before = self.sim_time
            self.commands.put((None, "step"))
            self._step_done.wait_for(lambda: self.sim_time > before or self._halt, timeout=10.0)
            ok = self.sim_time > before
        response.success = ok
        response.message = f"simulated time {self.sim_time:.3f} s" if ok else "the step did not complete"
        return response

    # building -----------------------------------------------------------------------------------
    def add_robot(self, spec: RobotSpec) -> RobotBridge:
        name = spec.name or f"robot{len(self.robots) + 1}"
        robot = self.world.spawn(
            spec.class_name,
            name,
            start=spec.start,
            location=spec.location,
            rotation=None if spec.location is None else (0.0, 0.0, spec.yaw),
        )
        rb = RobotBridge(self, robot, f"{name}/" if self.frame_prefix else "")
        self.robots[name] = rb
        self._subscribe(rb)
        self._static.extend(rb.static_transforms())
        log.info(
            "robot %s (%s) on the ROS 2 graph as /%s/..., cmd_vel: %s",
            name,
            spec.class_name,
            name,
            rb.kinematics.kind if rb.kinematics.kind != "none" else "not taken",
        )
        return rb

    def _subscribe(self, rb: RobotBridge) -> None:
        from geometry_msgs.msg import Twist, TwistStamped

        def twist(m: Any) -> None:
            rb.on_twist(m.linear.x, m.linear.y, m.linear.z, m.angular.z)

        def twist_stamped(m: Any) -> None:
            twist(m.twist)

        plain, stamped = ("cmd_vel_unstamped", "cmd_vel") if self.stamped else ("cmd_vel", "cmd_vel_stamped")
        self.node.create_subscription(Twist, f"{rb.ns}/{plain}", twist, self.qos)
        self.node.create_subscription(TwistStamped, f"{rb.ns}/{stamped}", twist_stamped, self.qos)
        from geometry_msgs.msg import PointStamped
        from sensor_msgs.msg import JointState

        def joints(m: Any) -> None:
            rb.on_joints(list(m.name), list(m.position))

        def report(m: Any) -> None:
            rb.on_report(m.point.x, m.point.y, m.point.z, m.header.frame_id)

        self.node.create_subscription(JointState, f"{rb.ns}/joint_commands", joints, self.qos)
        self.node.create_subscription(PointStamped, f"{rb.ns}/report_victim", report, self.qos)

    def publish_static(self) -> None:
        from tf2_msgs.msg import TFMessage

        msg = TFMessage(transforms=list(self._static))
        self._tf_static_pub.publish(msg)
        self._record("/tf_static", msg, 0.0)

    def transform(self, stamp: float, parent: str, child: str, location: Any, rotation: Any) -> Any:
        """A TransformStamped of a USARSim pose (location, roll/pitch/yaw) of ``child`` in ``parent``."""
        from geometry_msgs.msg import TransformStamped

        ts = TransformStamped()
        ts.header.stamp = b_time(stamp)
        ts.header.frame_id = parent
        ts.child_frame_id = child
        (x, y, z), q = ros_pose(location, rotation)
        tr = ts.transform.translation
        tr.x, tr.y, tr.z = x, y, z
        r = ts.transform.rotation
        r.x, r.y, r.z, r.w = q
        return ts

    def send_tf(self, transforms: list[Any], stamp: float) -> None:
        from tf2_msgs.msg import TFMessage

        msg = TFMessage(transforms=transforms)
        self._tf_pub.publish(msg)
        self._record("/tf", msg, stamp)

    def _record(self, topic: str, msg: Any, stamp: float) -> None:
        if self.recorder is not None:
            self.recorder.write(topic, msg, stamp)

    # running ------------------------------------------------------------------------------------
    def publish_clock(self, t: float) -> None:
        from rosgraph_msgs.msg import Clock

        if t < self.sim_time:
            return
        with self._step_done:
            self.sim_time = t
            self._step_done.notify_all()
        msg = Clock(clock=b_time(t))
        self._clock_pub.publish(msg)
        self._record("/clock", msg, t)

    def _dispatch(self, only: list[RobotBridge] | None = None) -> None:
        for rb in only if only is not None else list(self.robots.values()):
            for msg in rb.robot.take_messages():
                if isinstance(msg, M.Result) and getattr(msg, "item_type", "") == "Victim":
                    log.info("robot %s: victim report: %s", rb.name, msg)
                rb.handle(msg)
        if self.camera_hz > 0:
            for rb in list(self.robots.values()):
                if rb.cameras and self.sim_time >= rb.next_picture:
                    rb.next_picture = self.sim_time + 1.0 / self.camera_hz
                    for camera, compressed, raw, info in rb.camera_wanted():
                        rb.publish_picture(rb.robot.time or self.sim_time, camera, compressed, raw, info)

    def _carry_out(self) -> int:
        """Send the queued commands; returns the steps asked for (lock-step)."""
        steps = 0
        while True:
            try:
                rb, what = self.commands.get_nowait()
            except queue.Empty:
                return steps
            if rb is not None:
                try:
                    rb.robot.send(what)
                except ClientError as exc:
                    rb.warn_once("send", f"could not send a command: {exc}")
            elif what == "pause":
                self.paused = True
                log.info("paused at %.3f s", self.sim_time)
            elif what == "resume":
                self.paused = False
                log.info("resumed at %.3f s", self.sim_time)
            elif what == "step":
                steps += 1

    def run(self, duration: float | None = None, ready: Callable[[], None] | None = None) -> None:
        """Bridge until :meth:`stop`, or for ``duration`` simulated seconds."""
        self.publish_static()
        if ready is not None:
            ready()
        start_wall = time.monotonic()
        start_sim = self.sim_time
        selector: selectors.BaseSelector | None = None
        while not self._halt:
            if duration is not None and self.sim_time - start_sim >= duration - 1e-9:
                return
            gone = [rb.name for rb in self.robots.values() if rb.robot.closed]
            if gone:
                raise ClientError(f"the simulator closed the connection of {', '.join(gone)}")
            steps = self._carry_out()
            if self.world.lockstep:
                if self.paused and steps == 0:
                    time.sleep(0.01)
                    start_wall, start_sim = time.monotonic(), self.sim_time
                    continue
                t = self.world.step(self.period)
                self._dispatch()
                self.publish_clock(t)
                if self.rtf > 0 and not self.paused:
                    ahead = (self.sim_time - start_sim) / self.rtf - (time.monotonic() - start_wall)
                    while ahead > 0 and not self._halt:
                        time.sleep(min(ahead, 0.05))
                        ahead = (self.sim_time - start_sim) / self.rtf - (time.monotonic() - start_wall)
            else:
                # each robot's lines published as soon as they are read, not after every robot's
                if selector is None:
                    selector = selectors.DefaultSelector()
                    for rb in self.robots.values():
                        selector.register(rb.robot.fileno(), selectors.EVENT_READ, rb)
                readable = [key.data for key, _ in selector.select(0.01)]
                for rb in readable:
                    rb.robot.update(0.0)  # ClientError when the simulator closed it: the bridge stops
                    self._dispatch([rb])
                    t = rb.robot.time
                    if t is not None and t > self.sim_time:
                        self.publish_clock(t)
                if not readable:
                    self._dispatch([])

    def stop(self) -> None:
        """Stop :meth:`run` (safe in a signal handler)."""
        self._halt = True

    def close(self) -> None:
        self._halt = True
        with self._step_done:
            self._step_done.notify_all()
        self._spin_thread.join(timeout=5.0)
        try:
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        finally:
            if self.context.ok():
                self.context.try_shutdown()
        if self.recorder is not None:
            self.recorder.close()
