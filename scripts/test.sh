#!/usr/bin/env bash
# The one test command: every crate's tests and the end-to-end tests, in release mode.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --workspace
