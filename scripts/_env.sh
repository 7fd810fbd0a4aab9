# Sourced by the scripts: pick the Python to install into.  A virtual environment
# in .venv when this Python can make one, else the Python on PATH.
if [ -z "${USARSIM_PYTHON:-}" ]; then
  if [ -x .venv/bin/python ] || python3 -m venv .venv >/dev/null 2>&1; then
    USARSIM_PYTHON=.venv/bin/python
  else
    USARSIM_PYTHON=python3
  fi
fi
