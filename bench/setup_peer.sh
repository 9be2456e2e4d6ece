#!/usr/bin/env bash
# The Drake peer lives in its own venv (.venv-bench) so that the main one stays lean.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv-bench/bin/python ] || ! .venv-bench/bin/python -c "import pydrake" 2>/dev/null; then
  python3 -m venv .venv-bench
  .venv-bench/bin/pip install --quiet --upgrade pip
  .venv-bench/bin/pip install --quiet "drake>=1.40" numpy
fi
