#!/usr/bin/env bash
# Install usarsim with its test dependencies and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/_env.sh
# Everything: the core, the extras (recordings, sweeps, ROS 2) and the test tools, since the suite tests
# every part.
echo "scripts/test.sh: installing usarsim with every extra and the test tools (pip install -e '.[test]')" >&2
"$USARSIM_PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[test]"
# Debian packages the tests need, installed once with apt-get when missing:
# * chromium: the operator console's tests drive a headless browser, Debian's (Playwright's own
#   browser download is not used); without it those tests are skipped, with the reason;
# * cmake and g++: the ROS 2 bridge's /tf needs tf2_msgs, which has no wheel and is built once into
#   the environment (python -m usarsim.ros2.tf2_build, below).
debs=()
if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then debs+=(chromium); fi
if ! command -v cmake >/dev/null 2>&1; then debs+=(cmake); fi
if ! command -v g++ >/dev/null 2>&1; then debs+=(g++); fi
if [ "${#debs[@]}" -gt 0 ] && command -v apt-get >/dev/null 2>&1; then
  sudo=""
  if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then sudo="sudo -n"; else sudo="none"; fi
  fi
  if [ "$sudo" = none ]; then
    echo "scripts/test.sh: ${debs[*]} missing and no root to install them (apt-get install ${debs[*]}):" \
         "the browser tests are skipped, the ROS 2 tests need cmake and g++" >&2
  else
    echo "scripts/test.sh: installing Debian's ${debs[*]} for the browser and ROS 2 tests" \
         "(apt-get install, a few minutes the first time)" >&2
    { $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -q \
        && $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${debs[@]}"; } \
        </dev/null >/dev/null \
      || echo "scripts/test.sh: could not install ${debs[*]}" >&2
  fi
fi
"$USARSIM_PYTHON" -m usarsim.ros2.tf2_build \
  || echo "scripts/test.sh: tf2_msgs could not be built: the ROS 2 tests of /tf will fail" >&2
# The house style (pyproject.toml [tool.ruff]: the lint rules and the layout ruff format gives): a
# finding fails the run before any test.
"$USARSIM_PYTHON" -m ruff check src tests tools examples
"$USARSIM_PYTHON" -m ruff format --check src tests tools examples
# The types (pyproject.toml [tool.mypy]: the protocol layer and the facade strictly): an error fails
# the run before any test.
"$USARSIM_PYTHON" -m mypy
export MUJOCO_GL="${MUJOCO_GL:-egl}"
# The virtual environment's bin folder first on PATH, as '. .venv/bin/activate' would put it, so
# that the tests find the 'usarsim' console script pip installed there (a Python that is no
# virtual environment installs it on PATH already).
venv_bin="$(dirname "$USARSIM_PYTHON")"
if [[ "$USARSIM_PYTHON" == */* && -f "$venv_bin/../pyvenv.cfg" ]]; then
  PATH="$(cd "$venv_bin" && pwd):$PATH"
  export PATH
fi
# With arguments, pytest runs what they select, as given.  The whole suite (no arguments) is
# shared among one process per core, up to 4 (pytest-xdist); beside it, in a process of its own,
# the tests marked 'ports' (the pages' commands, on the default ports: they mostly wait for robots
# driving in real time) run one at a time; then the tests marked 'alone' (they time the wall clock:
# rates, pacing, deadlines) run by themselves, with no other test competing for the processors.
if [ $# -gt 0 ]; then
  exec "$USARSIM_PYTHON" -m pytest -q "$@"
fi
# The fast tier first (tests/fast: the protocol, sessions, console and client logic with a fake
# facade; no MuJoCo, which USARSIM_FAST_TIER=1 makes fail to import): a fault there fails the run
# in seconds, before the physics tests start.
echo "scripts/test.sh: the fast tier (pytest -m fast: no physics, no sockets)" >&2
USARSIM_FAST_TIER=1 "$USARSIM_PYTHON" -m pytest -q -p no:cacheprovider tests/fast
workers="$(nproc 2>/dev/null || echo 1)"
if [ "$workers" -gt 4 ]; then workers=4; fi
if [ "$workers" -lt 2 ]; then
  exec "$USARSIM_PYTHON" -m pytest -q -m "not fast"
fi
beside="$(mktemp -d)"
"$USARSIM_PYTHON" -m pytest -q -p no:cacheprovider --basetemp "$beside/tmp" -m ports >"$beside/log" 2>&1 &
ports_pid=$!
shared=0
"$USARSIM_PYTHON" -m pytest -q -n "$workers" -m "not alone and not ports and not fast" || shared=$?
ports=0
wait "$ports_pid" || ports=$?
echo "scripts/test.sh: the pages' commands (tests marked 'ports', run beside the others):"
cat "$beside/log"
rm -rf "$beside"
alone=0
"$USARSIM_PYTHON" -m pytest -q -m alone || alone=$?
if [ "$shared" != 0 ]; then exit "$shared"; fi
if [ "$ports" != 0 ]; then exit "$ports"; fi
exit "$alone"
