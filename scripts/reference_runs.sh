#!/usr/bin/env bash
# Fixed-seed reference runs of every agent, for restructurings that must not change results:
# the six agents on the walking task (smoke preset: LSTM networks with burn-in), on the
# pendulum (MLP) and with 3 batch chunks on 2 threads, plus es-sac and td3 with the walking
# preset for 3,000 steps. Prints the SHA-256 of each run's metrics.jsonl and state.json (wall
# times removed) and of every checkpoint and best/ tensor file. Run it with the binary before
# and after a change and diff the outputs (about 15 s):
#   bash scripts/reference_runs.sh target/release/esrl /tmp/ref-a > a.txt   (and again: b.txt)
set -euo pipefail
BIN=$(realpath "$1"); OUT=$2; rm -rf "$OUT"; mkdir -p "$OUT"
printf 'rl = { batch_chunks = 3, batch_size = 6 }\n' > "$OUT/chunks.toml"
for a in es-sac es-td3 es-ddpg sac td3 ddpg; do
  case $a in es-*) n=(--generations 3);; *) n=(--episodes 3);; esac
  $BIN train $a --preset smoke "${n[@]}" --seed 7 --out "$OUT/$a-walk" >/dev/null 2>&1
  $BIN train $a --preset smoke --env pendulum "${n[@]}" --seed 7 --out "$OUT/$a-pend" >/dev/null 2>&1
  $BIN train $a --preset smoke --config "$OUT/chunks.toml" "${n[@]}" --seed 7 --threads 2 --out "$OUT/$a-chunks" >/dev/null 2>&1
done
$BIN train es-sac --preset walking --steps 3000 --seed 3 --out "$OUT/walking" >/dev/null 2>&1
$BIN train td3 --preset walking --steps 3000 --seed 3 --out "$OUT/walking-td3" >/dev/null 2>&1
cd "$OUT"
for r in */; do r=${r%/}
  python3 -c "
import json,sys
for l in open('$r/metrics.jsonl'):
    d=json.loads(l); d.pop('wall_s',None); print(json.dumps(d,sort_keys=True))" | sha256sum | sed "s|-|$r/metrics|"
  python3 -c "
import json
def strip(v):
    if isinstance(v,dict): return {k:strip(x) for k,x in v.items() if k not in ('wall_s','seconds')}
    if isinstance(v,list): return [strip(x) for x in v]
    return v
print(json.dumps(strip(json.load(open('$r/checkpoint/state.json'))),sort_keys=True))" | sha256sum | sed "s|-|$r/state|"
  for f in $r/checkpoint/*.safetensors $r/best/*.safetensors; do [ -f "$f" ] && sha256sum "$f"; done
done
