#!/usr/bin/env bash
# Install usarsim and start the simulator on its default world (DM-USAR_yellow, port 3000).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m pip install --quiet --disable-pip-version-check -e .
exec usarsim serve "$@"
