#!/usr/bin/env bash
# Interleaved timing of esrl-nn and PyTorch on the same shapes, single thread, same session:
#   crates/nn/scripts/compare.sh [rounds] [obs_dim]
# Each round runs the PyTorch twin (scripts/torch_nn_bench.py) and `esrl_nn::bench::run`
# (examples/nn_bench.rs) back to back on the same CPU, so machine load hits both alike, and
# prints both JSON lines and the esrl/torch ratios (wall median, wall minimum, on-CPU mean).
set -euo pipefail
rounds=${1:-3}
obs=${2:-43}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
cd "$root"
cargo build --release -q -p esrl-nn --example nn_bench
cpu=$(( $(nproc) - 1 ))
for r in $(seq 1 "$rounds"); do
  echo "round $r load $(cut -d' ' -f1-3 /proc/loadavg)"
  t=$(python3 "$here/torch_nn_bench.py" --obs "$obs")
  e=$(taskset -c "$cpu" target/release/examples/nn_bench "$obs" 21)
  echo "$t"
  echo "$e"
  python3 - "$t" "$e" <<'PY'
import json, sys
t, e = json.loads(sys.argv[1]), json.loads(sys.argv[2])
for k in ("actor", "critic", "mlp_actor", "mlp_critic"):
    r = [e[k + "_ms"] / t[k + "_ms"], e["min_ms"][k] / t["min_ms"][k]]
    if k in e.get("cpu_ms", {}) and t.get("cpu_ms", {}).get(k):
        r.append(e["cpu_ms"][k] / t["cpu_ms"][k])
    print(f"  {k:10} esrl/torch  median {r[0]:.2f}  min {r[1]:.2f}" + (f"  cpu {r[2]:.2f}" if len(r) > 2 else ""))
PY
done
