#!/usr/bin/env bash
# Interleaved timing of esrl-nn and PyTorch on the same shapes, single thread, same session:
#   crates/nn/scripts/compare.sh [rounds] [obs_dim]
# Each round runs the PyTorch twin (scripts/torch_nn_bench.py) and `esrl_nn::bench::run`
# (examples/nn_bench.rs) back to back, so machine load hits both alike; compare per-round
# ratios or the minimum over rounds.
set -euo pipefail
rounds=${1:-3}
obs=${2:-43}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
cd "$root"
cargo build --release -q -p esrl-nn --example nn_bench
for r in $(seq 1 "$rounds"); do
  echo "round $r load $(cut -d' ' -f1-3 /proc/loadavg)"
  python3 "$here/torch_nn_bench.py" --obs "$obs"
  taskset -c "$(nproc --ignore=1)" target/release/examples/nn_bench "$obs" 9
done
