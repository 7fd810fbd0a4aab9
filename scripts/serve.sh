#!/usr/bin/env bash
# Install usarsim (its core: the simulator, its servers, clients and environments) and start the
# simulator on its default world (DM-USAR_yellow, port 3000).  Arguments go to 'usarsim serve'.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/_env.sh
if "$USARSIM_PYTHON" -c "import usarsim.cli, mujoco, numba" >/dev/null 2>&1; then
  "$USARSIM_PYTHON" -m pip install --quiet --disable-pip-version-check -e .
else
  echo "scripts/serve.sh: installing usarsim into ${USARSIM_PYTHON%/bin/python} (MuJoCo, numpy, numba...;" \
       "about 400 MB, a minute or two the first time)" >&2
  "$USARSIM_PYTHON" -m pip install --disable-pip-version-check --progress-bar on -e . \
    | grep --line-buffered -E '^(Collecting|Successfully|Building|Installing)' >&2 || true
  "$USARSIM_PYTHON" -c "import usarsim.cli" \
    || { echo "scripts/serve.sh: the install failed (see pip's messages above)" >&2; exit 1; }
fi
exec "$USARSIM_PYTHON" -m usarsim serve "$@"
