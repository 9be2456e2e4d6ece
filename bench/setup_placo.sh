#!/usr/bin/env bash
# The placo walking peer lives in its own venv (.venv-placo) because PyPI's placo pins pin==3.8.0
# (the main venv has pin 4.1.0; one venv cannot hold both).
#
# example-robot-data (the data wheel only: URDFs and meshes, no Python loader, no pin requirement)
# gives the peer the same TALOS URDF as the main venv's example_robot_data.load("talos").
# Idempotent: does nothing but print the versions when .venv-placo already has these versions.
#
#     bash bench/setup_placo.sh && .venv-placo/bin/python bench/peer_placo.py bench/placo/example_plan.json out/placo.npz
set -euo pipefail
cd "$(dirname "$0")/.."
PLACO=0.10.2
PIN=3.8.0
ERD=5.0.0
NUMPY=2.3.5
VERSIONS_CHECK="
import importlib.metadata as md
expected = {'placo': '${PLACO}', 'pin': '${PIN}', 'example-robot-data': '${ERD}', 'numpy': '${NUMPY}'}
installed = {name: md.version(name) for name in expected}
assert installed == expected, installed
import placo
print(' '.join(f'{name} {version}' for name, version in installed.items()))
"
if [ -x .venv-placo/bin/python ] && .venv-placo/bin/python -c "${VERSIONS_CHECK}" 2>/dev/null; then
  exit 0
fi
rm -rf .venv-placo
python3 -m venv .venv-placo
.venv-placo/bin/pip install --quiet --upgrade pip
.venv-placo/bin/pip install --quiet "placo==${PLACO}" "pin==${PIN}" "example-robot-data==${ERD}" "numpy==${NUMPY}"
.venv-placo/bin/python -c "${VERSIONS_CHECK}"
