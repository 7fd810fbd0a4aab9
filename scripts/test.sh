#!/usr/bin/env bash
# Install usarsim with its test dependencies and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/_env.sh
# Everything: the core, the extras (recordings, sweeps) and the test tools, since the suite tests
# every part.
echo "scripts/test.sh: installing usarsim with every extra and the test tools (pip install -e '.[test]')" >&2
"$USARSIM_PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[test]"
# The operator console's tests drive a headless Chromium: Debian's package (Playwright's own
# browser download is not used).  Without it those tests are skipped, with the reason.
if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1 \
    && command -v apt-get >/dev/null 2>&1; then
  sudo=""
  if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then sudo="sudo -n"; else sudo="none"; fi
  fi
  if [ "$sudo" = none ]; then
    echo "scripts/test.sh: no chromium and no root to install it (apt-get install chromium): the browser tests will be skipped" >&2
  else
    echo "scripts/test.sh: the operator console's tests drive a real browser: installing Debian's chromium" \
         "(apt-get install chromium, a few minutes the first time)" >&2
    { $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -q \
        && $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium; } \
        </dev/null >/dev/null \
      || echo "scripts/test.sh: could not install chromium: the browser tests will be skipped" >&2
  fi
fi
# The house style (pyproject.toml [tool.ruff]): a finding fails the run before any test.
"$USARSIM_PYTHON" -m ruff check src tests tools examples
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
# shared among one process per core, up to 4 (pytest-xdist); then the tests marked 'alone' (they
# time the wall clock: rates, pacing, deadlines) run by themselves, with no other test competing
# for the processors.  On 2 cores that takes the suite from about 12.5 minutes to 7 or 8.
if [ $# -gt 0 ]; then
  exec "$USARSIM_PYTHON" -m pytest -q "$@"
fi
workers="$(nproc 2>/dev/null || echo 1)"
if [ "$workers" -gt 4 ]; then workers=4; fi
if [ "$workers" -lt 2 ]; then
  exec "$USARSIM_PYTHON" -m pytest -q
fi
shared=0
"$USARSIM_PYTHON" -m pytest -q -n "$workers" -m "not alone" || shared=$?
alone=0
"$USARSIM_PYTHON" -m pytest -q -m alone || alone=$?
if [ "$shared" != 0 ]; then exit "$shared"; fi
exit "$alone"
