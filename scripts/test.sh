#!/usr/bin/env bash
# Install usarsim with its test dependencies and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/_env.sh
"$USARSIM_PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[test]"
export MUJOCO_GL="${MUJOCO_GL:-egl}"
exec "$USARSIM_PYTHON" -m pytest -q "$@"
