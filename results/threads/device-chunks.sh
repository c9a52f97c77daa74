#!/usr/bin/env bash
# rl.batch_chunks on a many-core machine (issue 20), about 3 minutes on 16 cores: one SAC
# update by network, batch chunks K and threads; then `train es-sac --preset paper
# --generations 3` at 1 and 16 threads with K = 1 and K = 8.
#
# Usage: bash results/threads/device-chunks.sh ESRL_BINARY OUT_DIR
# (e.g. with the device tool: carry target/release/esrl, OUT_DIR = $OUT). CHUNKS, THREADS,
# TRAIN_THREADS and GENERATIONS override the lists above for a short trial.
set -euo pipefail
esrl=$1
out=$2
mkdir -p "$out"
nproc > "$out/machine.txt"
lscpu >> "$out/machine.txt" 2>/dev/null || true
for arch in lstm mlp; do
  for k in ${CHUNKS:-1 4 8 16}; do
    for t in ${THREADS:-1 2 4 8 16}; do
      "$esrl" bench update --arch "$arch" --threads "$t" --batch-chunks "$k" --json
    done
  done
done > "$out/update.jsonl"
printf '[rl]\nbatch_chunks = 8\n' > "$out/k8.toml"
for k in 1 8; do
  cfg=()
  if [ "$k" = 8 ]; then cfg=(--config "$out/k8.toml"); fi
  for t in ${TRAIN_THREADS:-1 16}; do
    start=$(date +%s%N)
    "$esrl" train es-sac --preset paper --seed 0 --generations "${GENERATIONS:-3}" --threads "$t" \
      "${cfg[@]}" --no-progress --out "$out/paper-k$k-t$t" > /dev/null
    echo "paper K=$k threads=$t $(( ($(date +%s%N) - start) / 1000000 )) ms" >> "$out/train.txt"
    rm -rf "$out/paper-k$k-t$t/replay"
  done
done
cat "$out/train.txt"
