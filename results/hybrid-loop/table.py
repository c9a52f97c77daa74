"""Builds results/hybrid-loop/table.md from compare folders: one row per run, then the mean
over seeds per (setting, agent).

Usage: python table.py SETTING=DIR [SETTING=DIR ...] > table.md
Each DIR is an `esrl compare` output folder (runs in DIR/<agent>-s<seed>).
"""

import csv
import json
import statistics
import sys
from pathlib import Path


def run_row(setting, run):
    s = json.loads((run / "summary.json").read_text())
    e = json.loads((run / "eval.json").read_text())
    rows = list(csv.DictReader(open(run / "metrics.csv")))
    last = rows[-10:]
    eps = e["episodes"]
    return {
        "setting": setting,
        "run": run.name,
        "agent": s["agent"],
        "best_win_50": s["best_win_50"],
        "final_50": s["final_50"],
        "len_end": sum(float(r["mean_length"]) for r in last) / len(last),
        "survived": sum(1 for ep in eps if not ep["gait"]["fell"]),
        "n_eval": len(eps),
        "distance": statistics.mean(ep["gait"]["distance"] for ep in eps),
        "best_share": s.get("rl_trained_best_share"),
        "elite_share": s.get("rl_trained_elite_share"),
        "replaced_share": s.get("rl_replaced_share"),
        "env_steps": s["env_steps"],
        "wall_s": s["wall_s"],
    }


def fmt(x, spec=".1f"):
    return "–" if x is None else format(x, spec)


def main():
    rows = []
    for arg in sys.argv[1:]:
        setting, d = arg.split("=", 1)
        for run in sorted(Path(d).glob("*-s[0-9]*")):
            if (run / "eval.json").exists():
                rows.append(run_row(setting, run))
    head = ("| setting | run | Best-Win-50 | Final-50 | ep. length, last 10 gens | "
            "eval: up 60 s | eval: distance (m) | trained actor best | trained actor elite | "
            "RL actor replaced | env steps | wall (s) |")
    print(head)
    print("|" + "---|" * 2 + "---:|" * 10)
    for r in rows:
        print(f"| {r['setting']} | {r['run']} | {fmt(r['best_win_50'])} | {fmt(r['final_50'])} | "
              f"{fmt(r['len_end'])} | {r['survived']}/{r['n_eval']} | {fmt(r['distance'], '.2f')} | "
              f"{fmt(r['best_share'], '.0%')} | {fmt(r['elite_share'], '.0%')} | "
              f"{fmt(r['replaced_share'], '.0%')} | {r['env_steps']} | {fmt(r['wall_s'], '.0f')} |")
    print()
    print("Mean ± sample SD over seeds:")
    print()
    print("| setting | agent | seeds | Best-Win-50 | Final-50 | ep. length, last 10 gens | "
          "eval: up 60 s | eval: distance (m) | trained actor best |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    groups = {}
    for r in rows:
        groups.setdefault((r["setting"], r["agent"]), []).append(r)

    def ms(vals, spec=".1f"):
        vals = [v for v in vals if v is not None]
        if not vals:
            return "–"
        if len(vals) == 1:
            return format(vals[0], spec)
        return f"{format(statistics.mean(vals), spec)} ± {format(statistics.stdev(vals), spec)}"

    for (setting, agent), g in groups.items():
        print(f"| {setting} | {agent} | {len(g)} | {ms([r['best_win_50'] for r in g])} | "
              f"{ms([r['final_50'] for r in g])} | {ms([r['len_end'] for r in g])} | "
              f"{sum(r['survived'] for r in g)}/{sum(r['n_eval'] for r in g)} | "
              f"{ms([r['distance'] for r in g], '.2f')} | "
              f"{ms([r['best_share'] for r in g], '.2f')} |")


if __name__ == "__main__":
    main()
