"""Drive a robot of 'usarsim ros2' forward for 5 simulated seconds, then print where its odometry
says it is: python examples/ros2_drive.py [ROBOT]   (ROBOT: its namespace, default robot1)."""

import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry

robot = sys.argv[1] if len(sys.argv) > 1 else "robot1"
rclpy.init()
node = rclpy.create_node("ros2_drive")
cmd_vel = node.create_publisher(Twist, f"/{robot}/cmd_vel", 10)
odom: list[Odometry] = []
node.create_subscription(Odometry, f"/{robot}/odom", odom.append, 10)
forward = Twist()
forward.linear.x = 0.3  # m/s
give_up = time.monotonic() + 60
while not odom or odom[-1].header.stamp.sec - odom[0].header.stamp.sec < 5:
    if time.monotonic() > give_up:
        sys.exit(f"no /{robot}/odom for a minute: is 'usarsim ros2' (or 'usarsim serve --ros2') running?")
    cmd_vel.publish(forward)
    rclpy.spin_once(node, timeout_sec=0.1)
cmd_vel.publish(Twist())  # stop
p = odom[-1].pose.pose.position
print(f"{robot}: x {p.x:.2f} m, y {p.y:.2f} m by odometry after 5 s at 0.3 m/s")
