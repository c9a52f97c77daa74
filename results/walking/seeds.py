"""The seeds tables of README.md: the gait of each seed's kept policy against the issue's goals,
for today's `--preset walking` and for the preset before it; with `--compare`, the same for
every run of the six-agent comparison (the policy each run hands over: ES runs' `best/`,
plain runs' last checkpoint, from the records in compare/), and per agent the seeds whose
policy meets the bar (classified `walk` in most episodes, finishing from >= 8 of 10 starts);
`--compare compare-equal-gen` does it for the comparison at equal generations/episodes.

Usage: python seeds.py [--compare [RECORDS]]   (reads the eval reports in this folder)
"""

import json
import statistics
import sys
from collections import Counter
from pathlib import Path

AGENTS = ["es-sac", "es-td3", "es-ddpg", "sac", "td3", "ddpg"]

ROWS = [
    ("0", "`best/` at the end (gen 323, 1.47 M steps)", "runs/walking-chatter-clip-cap-s0/best-eval.json"),
    ("1", "`best/` at the end (gen 410, 4.00 M steps) = `flagship/`", "flagship-eval10.json"),
    ("1", "`best/` at 2.30 M steps (gen 324)", "runs/walking-chatter-clip-cap-s1/best-2.30M-eval.json"),
    ("2", "`best/` at the end (gen 473, 3.97 M steps)", "runs/walking-chatter-clip-cap-s2/best-eval.json"),
    ("2", "`best/` at 2.91 M steps (gen 422)", "runs/walking-chatter-clip-cap-s2/best-2.91M-eval.json"),
    ("3", "`best/` at the end (gen 415, 2.13 M steps)", "runs/preset-walking-s3/best-eval.json"),
    ("4", "`best/` at the end (gen 434, 3.59 M steps)", "runs/preset-walking-s4/best-eval.json"),
]

# The preset before the chatter price, clipped targets and the open, capped track (commit
# 4786e09): the previous flagship (seed 0) and plain SAC on the same preset.
PREVIOUS = [
    ("0", "`best/` at the end (gen 346, 2.90 M steps), the previous flagship", "runs/long-clock-s0/best-eval.json"),
    ("1", "`best/` at the end (gen 369, 3.62 M steps)", "runs/walking-s1/best-eval.json"),
    ("1", "`best/` at 2.56 M steps (gen 315)", "runs/walking-s1/best-2.56M-eval.json"),
    ("2", "`best/` at the end (gen 304, 2.56 M steps)", "runs/walking-s2/best-eval.json"),
    ("0 (plain SAC)", "the last policy (4 M steps)", "runs/walking-sac-s0/eval.json"),
    ("1 (plain SAC)", "the last policy (4 M steps)", "runs/walking-sac-s1/eval.json"),
    ("2 (plain SAC)", "the last policy (4 M steps)", "runs/walking-sac-s2/eval.json"),
]


def table(rows):
    print("| seed | policy | gait classes | finished 50 m | falls | track time (s) | fwd v (m/s) "
          "| mean \\|lat\\| (m) | knee asym. | alternation | flight % | double support % |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for seed, label, path in rows:
        eps = json.load(open(path))["episodes"]
        g = [ep["gait"] for ep in eps]
        cls = Counter(x["cycle"]["gait_class"] for x in g)
        times = [x["track_time"] for x in g if x["track_time"] is not None]
        mean = lambda k: statistics.mean(x[k] for x in g)  # noqa: E731
        cyc = lambda k: statistics.mean(x["cycle"][k] for x in g if x["cycle"][k] is not None)  # noqa: E731
        print(f"| {seed} | {label} | {', '.join(f'{k} {v}' for k, v in cls.most_common())} "
              f"| {len(times)}/10 | {sum(x['fell'] for x in g)}/10 "
              f"| {f'{statistics.mean(times):.1f}' if times else '–'} | {mean('mean_forward_velocity'):.2f} "
              f"| {mean('mean_abs_lateral'):.3f} | {100 * mean('knee_torque_asymmetry'):.1f} % "
              f"| {cyc('alternation'):.2f} | {100 * cyc('flight'):.1f} | {100 * cyc('double_support'):.1f} |")


def meets_bar(path):
    """Classified `walk` in most of the episodes and finishing from at least 8 of them."""
    g = [ep["gait"] for ep in json.load(open(path))["episodes"]]
    walks = sum(x["cycle"]["gait_class"] == "walk" for x in g)
    return 2 * walks > len(g) and sum(x["track_time"] is not None for x in g) >= 8


def compare(records="compare"):
    rows, seeds_in, bar = [], {}, {}
    for agent in AGENTS:
        for seed in range(3):
            run = Path(records) / f"{agent}-s{seed}"
            path = run / "best" / "eval.json" if agent.startswith("es-") else run / "eval.json"
            if not path.is_file():
                continue
            label = f"{agent} `best/`" if agent.startswith("es-") else f"{agent}, last"
            rows.append((str(seed), label, str(path)))
            seeds_in.setdefault(agent, []).append(seed)
            if meets_bar(path):
                bar.setdefault(agent, []).append(seed)
    table(rows)
    print()
    print("| agent | seeds with a record | seeds meeting the bar |")
    print("|---|---|---|")
    for agent, seeds in seeds_in.items():
        met = bar.get(agent, [])
        print(f"| {agent} | {', '.join(map(str, seeds))} "
              f"| {len(met)} ({', '.join(map(str, met)) or 'none'}) |")


def main():
    args = sys.argv[1:]
    if args and args[0] == "--compare":
        compare(*args[1:2])
        return
    table(ROWS)
    print()
    table(PREVIOUS)


if __name__ == "__main__":
    main()
