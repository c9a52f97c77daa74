#!/bin/bash
# Screens of one lever each on `--preset walking`: ES-SAC, seed 0, 2 M env steps, one thread,
# the overlay overlays/NAME.toml on the preset; then `esrl eval --episodes 10` of the last
# checkpoint (the RL actor) and of RUN/best (the kept policy), and the record (config,
# metrics, summary, evaluations without traces) into runs/NAME-s0/ via collect.py.
# usage: screen-runs.sh ESRL PYTHON DIR JOBS NAME...   (NAME: an overlay, e.g. screen2m-ups05;
#        runs go to DIR/NAME-s0; one with a checkpoint is resumed)
# The table row: python screen.py NAME-s0=runs/NAME-s0
set -euo pipefail
ESRL=$(realpath "$1"); PY=$2; DIR=$3; JOBS=$4; shift 4
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$DIR"
one() {
    local name=$1 run="$DIR/$1-s0"
    if [ -f "$run/summary.json" ] && grep -q '"finished": *true' "$run/summary.json"; then
        :
    elif [ -d "$run/checkpoint" ]; then
        "$ESRL" train --resume "$run" --threads 1 --no-progress >>"$run.log" 2>&1
    else
        "$ESRL" train es-sac --preset walking --config "$HERE/overlays/$name.toml" --seed 0 \
            --steps 2000000 --threads 1 --out "$run" --no-progress >>"$run.log" 2>&1
    fi
    "$ESRL" eval "$run" --episodes 10 >"$run.eval.txt"
    "$ESRL" eval "$run/best" --episodes 10 >"$run.best-eval.txt"
    "$PY" "$HERE/collect.py" "$HERE/runs" "$name-s0=$run"
    echo "[$name] done: record in runs/$name-s0"
}
export -f one
export ESRL PY DIR HERE
printf '%s\n' "$@" | xargs -P "$JOBS" -I{} bash -c 'one {}'
