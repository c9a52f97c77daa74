"""Table 1's learning columns at equal generations/episodes, from a comparison's runs.

`esrl compare` on the walking preset gives every agent the same 4 M environment steps. The
paper compares at equal generations (ES agents) and episodes (plain agents) instead; this
cuts every finished run's curve (the `curve` column of metrics.csv) at the same index N, by default
the shortest run's length, and summarises the cut curves as Table 1 does (Episodes-to-Target
against each agent's own target on the cut curves), with the environment steps each agent
had spent at index N. The gait columns need a policy at index N, which the runs do not keep:
they are not here.

usage: python equal-index.py CMP_DIR [N] [--out FILE.md]
"""
import argparse
import csv
import json
from collections import defaultdict
from pathlib import Path

from esrl_rs import metrics

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("cmp", type=Path)
parser.add_argument("n", type=int, nargs="?")
parser.add_argument("--out", type=Path)
args = parser.parse_args()

runs = defaultdict(list)
for d in sorted(args.cmp.glob("*-s[0-9]")):
    summary = d / "summary.json"
    if not (summary.is_file() and json.loads(summary.read_text()).get("finished")):
        continue  # unfinished runs would cut every curve short
    rows = list(csv.DictReader(open(d / "metrics.csv")))
    runs[d.name.rsplit("-s", 1)[0]].append(rows)
n = args.n or min(len(r) for seeds in runs.values() for r in seeds)
order = [a for a in ("es-sac", "es-td3", "es-ddpg", "sac", "td3", "ddpg") if a in runs]
cols = ["nauc", "auc", "final_50", "best_win_50", "episodes_to_target"]
lines = [
    f"Table 1's learning columns at the first {n} generations (ES) / episodes (plain) of "
    f"each run ({args.cmp}); mean ± sample SD over seeds.",
    "",
    "| Agent | Seeds | env steps at index N | " + " | ".join(cols) + " |",
    "|---|---:|---:|" + "---:|" * len(cols),
]
for agent in order:
    seeds = [r for r in runs[agent] if len(r) >= n]
    if not seeds:
        continue
    curves = [[float(x["curve"]) for x in r[:n]] for r in seeds]
    steps = [float(r[n - 1]["env_steps"]) for r in seeds]
    summaries = metrics.summarize_method(curves)
    cells = []
    for c in cols:
        vals = [s[c] for s in summaries if s[c] is not None]
        if not vals:
            cells.append("-")
            continue
        m = metrics.mean_sd(vals)
        sd = f" ± {m['sd']:.4g}" if m["sd"] is not None else ""
        reached = f" ({len(vals)}/{len(summaries)})" if len(vals) < len(summaries) else ""
        cells.append(f"{m['mean']:.4g}{sd}{reached}")
    st = metrics.mean_sd(steps)
    st_sd = f" ± {st['sd']:.3g}" if st["sd"] is not None else ""
    lines.append(f"| {agent} | {len(seeds)} | {st['mean']:.3g}{st_sd} | " + " | ".join(cells) + " |")
lines += [
    "",
    "Episodes-to-Target: the first index whose trailing 50-value mean (of the values so far "
    "while fewer than 50) reaches 80 % of the agent's median Best-Win-50 on the cut curves; "
    "0 when the first generation already does (an ES run's generation 0 scores its "
    "warm-started policy).",
]
text = "\n".join(lines) + "\n"
if args.out:
    args.out.write_text(text)
print(text, end="")
