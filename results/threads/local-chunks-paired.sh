#!/bin/bash
# One SAC update, esrl beside PyTorch, in one go on an otherwise idle machine:
#   bash results/threads/local-chunks-paired.sh PYTHON_WITH_TORCH ESRL OUT
# PyTorch: ../shared/peers/torch_sac_step.py (MLP and paper LSTM, 1 and 2 threads) -> OUT/torch.jsonl
# esrl: `bench update` at (threads, batch chunks) = (1, 1), (2, 1), (2, 2), (2, 4), twice -> OUT/esrl.jsonl
set -euo pipefail
py=$1 esrl=$2 out=$3
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
"$py" "$here/../../../shared/peers/torch_sac_step.py" --archs mlp,lstm --threads 1,2 > "$out/torch.jsonl"
for rep in 1 2; do
  for arch in mlp lstm; do
    for cfg in "1 1" "2 1" "2 2" "2 4"; do
      set -- $cfg
      "$esrl" bench update --arch "$arch" --threads "$1" --batch-chunks "$2" --json >> "$out/esrl.jsonl"
    done
  done
done
