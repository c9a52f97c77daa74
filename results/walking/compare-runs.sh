#!/bin/bash
# Trains runs of the six-agent comparison on the walking preset one by one, as
# `esrl compare --preset walking --seeds 3 --threads 1 --out CMP` trains them (same folders,
# same configs), and writes each finished run's record into results/walking/compare/<run>/
# at once, so that a comparison spread over several machines keeps every run it finished:
#   CMP/<run>/            the run (checkpoints, replay), as `esrl compare` leaves it
#   compare/<run>/        config.toml, metrics.csv, summary.json, eval.json (the last
#                         checkpoint, `esrl eval RUN --episodes 10`), and for ES runs
#                         best/{best.json,eval.json} (`esrl eval RUN/best --episodes 10`);
#                         evaluations without their per-step traces but episode 0's path
#                         (time, x, y: Fig. 5c)
#                         and pictures/: the gait pictures (gait diagram, joint angles,
#                         side view; 20 s of episode 0) of the policy the run hands over,
#                         ES runs' best/, plain runs' last checkpoint
# usage: compare-runs.sh ESRL PYTHON CMP JOBS RUN...      (RUN = <agent>-s<seed>, e.g. td3-s1;
#        PYTHON: an absolute path, with esrl_rs installed; JOBS runs at a time, one thread each)
# A run folder with a checkpoint is resumed; a finished one is only evaluated and recorded.
# Environment: RECORDS  the records' folder under results/walking (default compare);
#              TRAIN_ARGS  flags added to a new run's `esrl train` (the equal-generations
#                          comparison: "--generations 411 --episodes 411 --steps 1000000000")
set -euo pipefail
ESRL=$(realpath "$1"); PY=$2; CMP=$3; JOBS=$4; shift 4
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$CMP" "$HERE/${RECORDS:-compare}"
export RECORDS TRAIN_ARGS
printf '%s\n' "$@" | xargs -P "$JOBS" -I{} bash "$HERE/compare-one.sh" "$ESRL" "$PY" "$CMP" {}
