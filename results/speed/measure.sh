#!/usr/bin/env bash
# Speed figures of issue 38, measured side by side on one machine with nothing else running:
#   bash results/speed/measure.sh ESRL PEER_PYTHON OUT_DIR
# ESRL: the release binary; PEER_PYTHON: a Python with numpy, mujoco and (optionally) torch
# (../shared/peers); OUT_DIR gets one log per measurement.
set -euo pipefail
esrl=${1:?esrl binary}; py=${2:?python with the packages of the peers}; out=${3:?output folder}
peers="$(cd "$(dirname "$0")/../../.." && pwd)/shared/peers"
mkdir -p "$out"
lscpu | grep -E "Model name|^CPU\(s\)|L2 cache|Flags" | sed 's/Flags:.*avx512f.*/Flags: (AVX-512)/' > "$out/machine.txt"
# This core's FMA limit: NumPy's float32 2048^3 product on one thread (best of 5).
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 "$py" -c "
import time, numpy as np
a = np.random.rand(2048, 2048).astype(np.float32); b = a.copy(); a @ b
times = []
for _ in range(5):
    t0 = time.perf_counter(); a @ b; times.append(time.perf_counter() - t0)
t = min(times)
print(f'numpy float32 2048^3, 1 thread: {2 * 2048**3 / t / 1e9:.1f} GFLOP/s')" > "$out/fma-limit.txt"
# One SAC update of the MLP 256x256 networks at the walking recipe's batch (64) and the
# peer's (256), 1 and 2 threads; the paper-size LSTM at 256 x 8.
for b in 64 256; do for t in 1 2; do
  "$esrl" bench update --arch mlp --batch $b --threads $t --json
done; done > "$out/update-mlp.jsonl"
"$esrl" bench update --arch lstm --threads 1 --json > "$out/update-lstm.jsonl"
if "$py" -c "import torch" 2>/dev/null; then
  "$py" "$peers/torch_sac_step.py" --archs mlp --batch 64 --threads 1,2 > "$out/torch-mlp-b64.txt" 2>&1
  "$py" "$peers/torch_sac_step.py" --archs mlp --batch 256 --threads 1,2 > "$out/torch-mlp-b256.txt" 2>&1
fi
# Physics: the walking env against MuJoCo stepping the same URDF at the same 4 x 6.25 ms.
"$esrl" bench env --steps 40000 --json > "$out/env.json"
"$py" "$peers/mujoco_urdf.py" "$(dirname "$0")/../../assets/humanoid.urdf" --dt 0.00625 --substeps 4 \
  > "$out/mujoco-urdf.txt" 2>&1 || true
"$esrl" bench env --steps 40000 --json >> "$out/env.json"
# A generation of the recipe at 1 and 2 threads.
"$esrl" bench es --preset walking --json > "$out/es-walking.json"
"$esrl" bench es --preset walker --json > "$out/es-walker.json"
# The recipe's first 80,000 env steps, seed 11, at 1 and 2 threads (as the issue measured).
for t in 1 2; do
  rm -rf "$out/run80k-t$t"
  /usr/bin/time -f "%e s wall, %U s user" "$esrl" train es-sac --steps 80000 --seed 11 \
    --threads $t --out "$out/run80k-t$t" --no-progress 2> "$out/run80k-t$t.log"
  rm -rf "$out/run80k-t$t/replay" "$out/run80k-t$t/checkpoint" "$out/run80k-t$t/best"
done
