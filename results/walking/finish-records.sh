#!/bin/bash
# Writes the six-agent comparison's tables and figures from the runs' records in compare/
# (compare-runs.sh writes one per finished run, so the 18 runs may come from several
# machines):
#   compare/table-last.{md,csv}   Table 1 of every run's last checkpoint (ES runs: the last
#                                 RL actor), as `esrl compare` tabulates it
#   compare/table1.{md,csv}       Table 1 of the policy each run hands over (ES runs'
#                                 best/, plain runs' last checkpoint), as
#                                 `esrl compare --eval-best` tabulates it
#   compare/fig5*.png             Fig. 5 from the same evaluations (c: episode 0's path)
#   compare/equal-index.md        Table 1's learning columns at equal generations/episodes
#   compare/seeds.md              the gait of every run's handed-over policy and, per agent,
#                                 the seeds that meet the bar (seeds.py --compare)
# usage: finish-records.sh PYTHON [RECORDS]   (PYTHON with esrl_rs installed; RECORDS: the
#        records' folder, default compare; compare-equal-gen holds the comparison at equal
#        generations/episodes, whose records cut from the 4 M-step runs by
#        equal-gen-records.py keep no last checkpoint: then table-last is not written;
#        equal-index.md is written for compare only)
# Unfinished or missing runs are left out and listed in the tables' notes.
set -euo pipefail
PY=$1; RECORDS=${2:-compare}
HERE=$(cd "$(dirname "$0")" && pwd)
"$PY" - "$HERE/$RECORDS" <<'PY'
import shutil, sys, tempfile
from pathlib import Path
from esrl_rs.report import AGENT_ORDER, render_report
cmp = Path(sys.argv[1])
runs = [cmp / f"{a}-s{s}" for a in AGENT_ORDER for s in range(3)]
missing = [r.name for r in runs if not (r / "summary.json").is_file()]
runs = [r for r in runs if r not in [cmp / m for m in missing]]
# Records cut from longer runs (equal-gen-records.py) keep no last checkpoint's evaluation.
no_last = [r.name for r in runs if not (r / "eval.json").is_file()]
if no_last:
    print("no table-last: no last checkpoint's evaluation in " + ", ".join(no_last))
for best, stem in [(False, "table-last")] * (not no_last) + [(True, "table1")]:
    with tempfile.TemporaryDirectory() as tmp:
        rep = render_report(runs, tmp, dpi=100, gait=False, eval_best=best)
        for ext in ("md", "csv"):
            text = (Path(tmp) / f"table1.{ext}").read_text()
            if ext == "md" and missing:
                text += "- not in the table yet (no record): " + ", ".join(missing) + "\n"
            (cmp / f"{stem}.{ext}").write_text(text.replace(str(cmp.parent) + "/", ""))
        if best:
            for f in Path(tmp).glob("fig5*.png"):
                shutil.copy(f, cmp / f.name)
        for note in rep.notes:
            print(f"note ({stem}): {note}")
print(f"{len(runs)} runs tabulated; missing: {', '.join(missing) or 'none'}")
PY
if [ "$RECORDS" = compare ]; then
    (cd "$HERE" && "$PY" equal-index.py compare --out compare/equal-index.md)
fi
(cd "$HERE" && "$PY" seeds.py --compare "$RECORDS" > "$RECORDS/seeds.md")
echo "tables and Fig. 5 in $HERE/$RECORDS"
