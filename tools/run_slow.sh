#!/bin/sh
# The slow tests (marked @pytest.mark.slow, kept out of `make test` by pyproject's addopts):
# experiments over every bundled scene and the like. Run from the repository root:
#     tools/run_slow.sh            (or: make slow)
# Extra arguments go to pytest, e.g. tools/run_slow.sh -x --durations=10
set -e
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-$( [ -x .venv/bin/python ] && echo .venv/bin/python || echo python3 )}"
exec env MPLBACKEND="${MPLBACKEND:-Agg}" "$PYTHON" -m pytest -q -m slow "$@"
