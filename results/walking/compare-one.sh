#!/bin/bash
# One run of the six-agent comparison: trains (or resumes) CMP/<run>, evaluates it and
# writes its record; compare-runs.sh calls it, one process per run.
# usage: compare-one.sh ESRL PYTHON CMP RUN          (see compare-runs.sh; RECORDS and
#        TRAIN_ARGS as there)
set -euo pipefail
ESRL=$1; PY=$2; CMP=$3; name=$4
HERE=$(cd "$(dirname "$0")" && pwd)
agent=${name%-s*}; seed=${name##*-s}
run="$CMP/$name" rec="$HERE/${RECORDS:-compare}/$name" log="$CMP/$name.log"
t0=$(date +%s)
if [ -f "$run/summary.json" ] && grep -q '"finished": *true' "$run/summary.json"; then
    echo "[$name] finished before"
elif [ -d "$run/checkpoint" ]; then
    "$ESRL" train --resume "$run" --threads 1 --no-progress >>"$log" 2>&1
else
    # shellcheck disable=SC2086  # TRAIN_ARGS is a list of flags
    "$ESRL" train "$agent" --preset walking --seed "$seed" --threads 1 --out "$run" \
        ${TRAIN_ARGS:-} --no-progress >>"$log" 2>&1
fi
"$ESRL" eval "$run" --episodes 10 >"$run.eval.txt"
policy=$run
if [ -f "$run/best/best.json" ]; then
    "$ESRL" eval "$run/best" --episodes 10 >"$run.best-eval.txt"
    policy=$run/best
fi
"$PY" - "$run" "$rec" <<'PY'
import json, shutil, sys
from pathlib import Path
run, rec = Path(sys.argv[1]), Path(sys.argv[2])
def strip(src, dst):
    e = json.loads(src.read_text())
    for i, ep in enumerate(e["episodes"]):
        trace = ep.pop("trace", None)
        if i == 0 and trace:  # the path of episode 0, for Fig. 5c
            ep["trace"] = {k: [round(v, 4) for v in trace[k]] for k in ("time", "x", "y")}
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text(json.dumps(e, indent=1))
rec.mkdir(parents=True, exist_ok=True)
for f in ["config.toml", "metrics.csv", "summary.json"]:
    shutil.copy(run / f, rec / f)
strip(run / "eval.json", rec / "eval.json")
if (run / "best" / "best.json").is_file():
    (rec / "best").mkdir(exist_ok=True)
    shutil.copy(run / "best" / "best.json", rec / "best" / "best.json")
    strip(run / "best" / "eval.json", rec / "best" / "eval.json")
PY
pics="$CMP/pictures/$name"
rm -rf "$pics"
if "$PY" -m esrl_rs.report --gait "$policy" --out "$pics" --dpi 100 --start 20 >/dev/null; then
    mkdir -p "$rec/pictures"
    cp "$pics"/gait/*/*.png "$rec/pictures/"
else
    echo "[$name] gait pictures failed" >&2
fi
echo "[$name] done in $(( $(date +%s) - t0 )) s: record in $rec"
