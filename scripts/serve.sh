#!/usr/bin/env bash
# Install usarsim and start the simulator on its default world (DM-USAR_yellow, port 3000).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/_env.sh
"$USARSIM_PYTHON" -m pip install --quiet --disable-pip-version-check -e .
exec "$USARSIM_PYTHON" -m usarsim serve "$@"
