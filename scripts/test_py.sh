#!/usr/bin/env bash
# Python package tests: builds `py/` (esrl_rs) in release mode into a virtual environment at
# the repo root (.venv) and runs pytest on py/tests. Works on a fresh machine and a clean clone.
#
# Environment:
#   PYTHON            interpreter that creates the venv (default python3, needs ≥ 3.9)
#   ESRL_BIN          the esrl CLI used by the parity tests (default: target/release/esrl,
#                     built here with cargo)
#   ESRL_ALLOW_NO_CLI=1  while the CLI is being written: a CLI that cannot be built or cannot
#                     train makes its tests skip (with the reason) instead of fail
#   CARGO_TARGET_DIR  defaults to the workspace's target/, so the crates compile once
#   PYTEST_ARGS       extra pytest arguments
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"

python="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
    "$python" -m venv .venv
fi
venv_python="$root/.venv/bin/python"
"$venv_python" -m pip install --quiet --disable-pip-version-check \
    "maturin>=1.9.4,<2" pytest numpy gymnasium matplotlib
# Ray is optional for users (`pip install "./py[ray]"`) but tested here: `python -m esrl_rs.ray`
# against `esrl train` on a local cluster (py/tests/test_ray.py).
"$venv_python" -m pip install --quiet --disable-pip-version-check "ray>=2.9"
# MuJoCo is the second engine of `python -m esrl_rs.sim2sim`; its tests are skipped without it.
"$venv_python" -m pip install --quiet --disable-pip-version-check "mujoco>=3.2" \
    || echo "test_py.sh: mujoco not installed; the sim-to-sim check is not tested" >&2
# moviepy lets Gymnasium's RecordVideo write the walk's frames (render_mode="rgb_array");
# its test is skipped without it.
"$venv_python" -m pip install --quiet --disable-pip-version-check moviepy \
    || echo "test_py.sh: moviepy not installed; RecordVideo is not tested" >&2
# pandas is optional (Run.to_pandas); its test is skipped without it.
"$venv_python" -m pip install --quiet --disable-pip-version-check pandas \
    || echo "test_py.sh: pandas not installed; Run.to_pandas() is not tested" >&2

# The CLI for the parity tests (release mode, shared target/).
if [ -z "${ESRL_BIN:-}" ]; then
    if cargo build --release -p esrl --bin esrl; then
        export ESRL_BIN="$CARGO_TARGET_DIR/release/esrl"
    elif [ "${ESRL_ALLOW_NO_CLI:-0}" = "1" ]; then
        echo "test_py.sh: the esrl CLI did not build; its tests skip (ESRL_ALLOW_NO_CLI=1)" >&2
    else
        echo "test_py.sh: the esrl CLI did not build (set ESRL_ALLOW_NO_CLI=1 to test without it)" >&2
        exit 1
    fi
fi

# Build the wheel in release mode and install it (a real install, not an editable one).
wheels="$CARGO_TARGET_DIR/wheels/esrl_rs"
rm -rf "$wheels"
"$root/.venv/bin/maturin" build --release --quiet -m py/Cargo.toml --out "$wheels" \
    --interpreter "$venv_python"
"$venv_python" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps \
    "$wheels"/esrl_rs-*.whl

# Run from py/tests so that the installed package, not py/python, is imported.
cd py/tests
status=0
"$venv_python" -m pytest -q -p no:cacheprovider ${PYTEST_ARGS:-} . || status=$?
if [ "$status" -eq 5 ]; then
    echo "test_py.sh: pytest collected no tests" >&2
fi
exit "$status"
