#!/usr/bin/env bash
# The TSID 1.10 peer lives in its own venv (.venv-tsid) because its PyPI wheels need pin 4.0.0
# (the main venv has pin 4.1.0; tsid 1.10.0 was built against 4.0.0 and crashes with 4.1.0).
#
# libtsid 1.10.0 is on PyPI only as cp314 wheels although it is a plain C++ library, and its
# sdist does not build on 3.11 without the Eigen/urdfdom headers. So we download the cp314
# manylinux wheel and retag it py3-none (`wheel tags`) before installing it.
# mujoco (the version of pyproject.toml: the peer loads the binary model our side saves) runs
# the peer in the same MuJoCo closed loop as our tick (bench/talos_tick.py).
# Idempotent: does nothing when `.venv-tsid/bin/python -c "import tsid, mujoco"` already works.
#
#     bash bench/setup_tsid.sh && .venv-tsid/bin/python bench/peer_tsid.py --ticks 5000
set -euo pipefail
cd "$(dirname "$0")/.."
MUJOCO=$(sed -n 's/^ *"mujoco==\([0-9.]*\)".*/\1/p' pyproject.toml)
if [ -x .venv-tsid/bin/python ] && .venv-tsid/bin/python -c "import tsid, mujoco; assert mujoco.__version__ == '${MUJOCO}'" \
    2>/dev/null; then
  exit 0
fi
PIN=4.0.0
TSID=1.10.0
ERD=5.0.0
NUMPY=2.4.6
WHEEL=0.47.0
LIBTSID_WHL="libtsid-${TSID}-0-cp314-cp314-manylinux_2_28_x86_64.whl"

rm -rf .venv-tsid
python3 -m venv .venv-tsid
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
.venv-tsid/bin/pip install --quiet --upgrade pip
.venv-tsid/bin/pip install --quiet "wheel==${WHEEL}" "numpy==${NUMPY}" "pin==${PIN}" \
  "example-robot-data-loaders==${ERD}"
.venv-tsid/bin/pip download --quiet "libtsid==${TSID}" --no-deps --only-binary=:all: \
  --python-version 3.14 --implementation cp --abi cp314 --platform manylinux_2_28_x86_64 -d "$tmp"
.venv-tsid/bin/wheel tags --python-tag py3 --abi-tag none "$tmp/${LIBTSID_WHL}"
# Re-pin pin: tsid declares an unpinned `pin` requirement, and 4.1.0 breaks its ABI.
.venv-tsid/bin/pip install --quiet "$tmp/libtsid-${TSID}-0-py3-none-manylinux_2_28_x86_64.whl" \
  "tsid==${TSID}" "pin==${PIN}" "mujoco==${MUJOCO}"
.venv-tsid/bin/python - <<EOF
import warnings
warnings.simplefilter("ignore", RuntimeWarning)
import mujoco, pinocchio, tsid
assert pinocchio.__version__ == "${PIN}", pinocchio.__version__
assert mujoco.__version__ == "${MUJOCO}", mujoco.__version__
print("tsid", tsid.__version__ if hasattr(tsid, "__version__") else "${TSID}", "pinocchio", pinocchio.__version__)
EOF
