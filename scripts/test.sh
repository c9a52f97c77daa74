#!/usr/bin/env bash
# The one test command: every crate's tests and the end-to-end tests (release mode), then the
# Python package's tests (builds py/ into .venv with maturin).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --workspace
bash scripts/test_py.sh
