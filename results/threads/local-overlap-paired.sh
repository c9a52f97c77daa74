#!/bin/bash
# Paired timing of two esrl binaries (BASE, NEW), alternating, twice each: one update
# (MLP and LSTM, 1 and 2 threads), `bench es --preset quick --threads 2`, and
# `train es-sac --preset quick --seed 0 --generations 40` at 1 and 2 threads.
# usage: local-overlap-paired.sh BASE NEW OUT   (pause other work on the machine first)
set -euo pipefail
BASE=$1; NEW=$2; OUT=$3
mkdir -p "$OUT"; cd "$OUT"
for rep in 1 2; do
 for tag in base new; do
  if [ $tag = base ]; then B=$BASE; else B=$NEW; fi
  for arch in mlp lstm; do for t in 1 2; do
    echo "{\"tag\":\"$tag\",\"rep\":$rep,\"bench\":$($B bench update --arch $arch --threads $t --json)}" >> update.jsonl
  done; done
  echo "{\"tag\":\"$tag\",\"rep\":$rep,\"bench\":$($B bench es --preset quick --threads 2 --json)}" >> es.jsonl
  for t in 1 2; do
    rm -rf q; s=$(date +%s.%N)
    $B train es-sac --preset quick --seed 0 --generations 40 --threads $t --no-progress --out q >/dev/null 2>&1
    e=$(date +%s.%N)
    echo "$tag rep$rep quick g40 threads $t: $(echo "$e - $s" | bc) s" >> train.txt
  done
 done
done
