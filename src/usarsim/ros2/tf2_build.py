"""tf2_msgs for /tf and /tf_static, where no wheel of it exists.

ROS 2's Python wheels carry every message package the bridge uses except tf2_msgs, whose one
message (``TFMessage``: ``geometry_msgs/TransformStamped[] transforms``) is what a tf2 listener
subscribes to.  rclpy publishes only compiled message types, so this module builds it once, from
the ``tf2_msgs`` folder beside it, into the Python environment (``sys.prefix``) with the ROS 2 build
tools the ``ros2`` extra installs, cmake and a C/C++ compiler: about 10 s on 2 cores.  The built
type is ROS 2's own: the same definition and so the same type hash, received by any tf2 listener.

    python -m usarsim.ros2.tf2_build        # build it now (scripts/test.sh does)
"""

from __future__ import annotations

import importlib
import logging
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

from usarsim.errors import UsarsimError

log = logging.getLogger("usarsim.ros2")

PACKAGE = Path(__file__).with_name("tf2_msgs")


class Tf2BuildError(UsarsimError):
    """tf2_msgs is not installed and cannot be built here."""


def have_tf2_msgs() -> bool:
    importlib.invalidate_caches()
    try:
        importlib.import_module("tf2_msgs.msg")
    except ImportError:
        return False
    return True


def ensure_tf2_msgs() -> None:
    """Import tf2_msgs, building it into this environment first if it is missing (one build
    at a time: processes that start together wait for the first one's)."""
    if have_tf2_msgs():
        return
    import fcntl

    try:
        lock = open(Path(sys.prefix) / ".usarsim-tf2-msgs.lock", "w")  # noqa: SIM115 (held until built)
    except OSError:
        lock = None
    try:
        if lock is not None:
            fcntl.flock(lock, fcntl.LOCK_EX)
        if not have_tf2_msgs():
            build_tf2_msgs()
    finally:
        if lock is not None:
            lock.close()
    if not have_tf2_msgs():
        raise Tf2BuildError(
            f"tf2_msgs was built into {sys.prefix} but does not import; run "
            f"'python -m usarsim.ros2.tf2_build' to see the build's output"
        )


def _missing_tools() -> list[str]:
    need = {
        "cmake": "cmake",
        "a C compiler": os.environ.get("CC", "cc"),
        "a C++ compiler": os.environ.get("CXX", "c++"),
    }
    return [what for what, exe in need.items() if shutil.which(exe) is None]


def build_tf2_msgs(verbose: bool = False) -> None:
    """Build the tf2_msgs package into ``sys.prefix`` (cmake configure, build, install)."""
    missing = _missing_tools()
    if missing:
        raise Tf2BuildError(
            f"/tf needs tf2_msgs, which is built on first use with cmake and a C/C++ compiler: "
            f"{' and '.join(missing)} not found (Debian: apt-get install cmake g++)"
        )
    prefix = sys.prefix
    if not os.access(prefix, os.W_OK):
        raise Tf2BuildError(
            f"/tf needs tf2_msgs, built on first use into the Python environment {prefix}, "
            f"which is not writable: run 'python -m usarsim.ros2.tf2_build' as its owner"
        )
    share = Path(prefix) / "share"
    if not (share / "rosidl_default_generators").is_dir():
        raise Tf2BuildError(
            "/tf needs tf2_msgs, built on first use with ROS 2's build tools, which are missing: "
            "pip install 'usarsim[ros2]'"
        )
    log.warning("building tf2_msgs (TFMessage, for /tf) into %s: once, about 10 s", prefix)
    t0 = time.monotonic()
    env = dict(
        os.environ,
        AMENT_PREFIX_PATH=prefix,
        CMAKE_PREFIX_PATH=prefix,
        PATH=f"{Path(sysconfig.get_path('scripts'))}{os.pathsep}{os.environ.get('PATH', '')}",
    )
    with tempfile.TemporaryDirectory(prefix="usarsim-tf2-msgs-") as build:
        steps = [
            [
                "cmake",
                "-S",
                str(PACKAGE),
                "-B",
                build,
                f"-DCMAKE_INSTALL_PREFIX={prefix}",
                "-DCMAKE_BUILD_TYPE=Release",
                f"-DPython3_EXECUTABLE={sys.executable}",
                "-DBUILD_TESTING=OFF",
            ],
            ["cmake", "--build", build, "-j", str(min(4, os.cpu_count() or 1))],
            ["cmake", "--install", build],
        ]
        for cmd in steps:
            out = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, capture_output=True, text=True)
            if verbose:
                sys.stderr.write(out.stdout + out.stderr)
            if out.returncode != 0:
                tail = "\n".join((out.stdout + out.stderr).strip().splitlines()[-15:])
                raise Tf2BuildError(f"building tf2_msgs failed at '{' '.join(cmd[:2])}':\n{tail}")
    log.warning("tf2_msgs built in %.1f s", time.monotonic() - t0)


def main() -> int:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        if have_tf2_msgs():
            print(f"tf2_msgs: already in {sys.prefix}")
            return 0
        build_tf2_msgs()
    except Tf2BuildError as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    if not have_tf2_msgs():
        print("usarsim: error: tf2_msgs was built but does not import", file=sys.stderr)
        return 1
    print(f"tf2_msgs: TFMessage built into {sys.prefix}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
