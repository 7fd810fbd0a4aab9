"""ROS 2 for usarsim's robots, without a ROS installation (the ``ros2`` extra: ROS 2 Jazzy's
wheels), and without rclpy in the simulator's process.

* :mod:`.cli` -- ``usarsim ros2``: the bridge's command line;
* :mod:`.bridge` -- the bridge: a protocol client, an rclpy node, the clock and its services;
* :mod:`.robot` -- one robot's topics: readings to ROS 2 messages, ROS 2 commands to lines;
* :mod:`.convert` -- USARSim's axes and drives to ROS's, plain numbers (no rclpy);
* :mod:`.bag` -- rosbag2 recordings of what the bridge publishes;
* :mod:`.setup` and :mod:`.tf2_build` -- the environment rclpy needs, and tf2_msgs built once;
* :mod:`.bench` -- ``usarsim bench --ros2``.

docs/ros2.md is the user's guide.
"""
