#!/bin/bash
# Finishes the six-agent comparison on the walking preset (issue 16) once its 18 runs are
# trained, and copies its record here:
#   1. Table 1 of every run's last checkpoint (`table-last.*`: the last RL actor of ES runs);
#   2. Table 1 of the policy each run hands over (`--eval-best`: ES runs' `best/`);
#   3. each run's config, metrics and evaluations (collect.py, traces removed) into compare/;
#   4. Fig. 5 from the handed-over policies' evaluations, and the gait pictures (from 20 s
#      of episode 0) of each agent's best run (most finishes from the 10 starts, then the
#      longest distance);
#   5. Table 1's learning columns at equal generations/episodes (equal-index.py).
# usage: finish-compare.sh ESRL PYTHON CMP_DIR      (PYTHON with esrl_rs installed)
# A run that is not finished is trained by step 1 (the same command resumes it).
set -euo pipefail
ESRL=$1; PY=$2; CMP=$3
HERE=$(cd "$(dirname "$0")" && pwd)
# PRESET and OUT only for trying the script on a small comparison.
PRESET=${PRESET:-walking}; OUT=${OUT:-$HERE/compare}
args=(compare --preset "$PRESET" --seeds 3 --jobs 2 --threads 1 --eval-episodes 10 --out "$CMP" --no-progress)
"$ESRL" "${args[@]}"
cp "$CMP/table.md" "$CMP/table-last.md"; cp "$CMP/table.csv" "$CMP/table-last.csv"
"$ESRL" "${args[@]}" --eval-best
mkdir -p "$OUT"
cp "$CMP"/table.md "$CMP"/table.csv "$CMP"/table-last.md "$CMP"/table-last.csv "$OUT"/
names=()
for d in "$CMP"/*-s[0-9]; do names+=("$(basename "$d")=$d"); done
"$PY" "$HERE/collect.py" "$OUT" "${names[@]}"
# Fig. 5 and every run's gait pictures into CMP/report; the record keeps Fig. 5 and the gait
# pictures of each agent's best run.
"$PY" -m esrl_rs.report --out "$CMP/report" --dpi 100 --start 20 --eval-best "$CMP"/*-s[0-9]
mkdir -p "$OUT/figures/gait"
cp "$CMP"/report/fig5*.png "$CMP"/report/table1.* "$OUT/figures/"
"$PY" - "$CMP" <<'PY' | while read -r name; do cp -r "$CMP/report/gait/$name" "$OUT/figures/gait/"; done
import json, sys
from pathlib import Path
best = {}
for d in sorted(Path(sys.argv[1]).glob("*-s[0-9]")):
    agent = d.name.rsplit("-s", 1)[0]
    ev = d / "best" / "eval.json" if agent.startswith("es-") else d / "eval.json"
    m = json.loads(ev.read_text())["mean"]
    key = (m["finished"], m["gait"]["distance"])
    if agent not in best or key > best[agent][0]:
        best[agent] = (key, d.name)
for _, name in best.values():
    print(name)
PY
# Table 1's learning columns at equal generations/episodes (the paper's budget), from the
# same runs' curves.
"$PY" "$HERE/equal-index.py" "$CMP" --out "$OUT/equal-index.md"
echo "record in $OUT"
