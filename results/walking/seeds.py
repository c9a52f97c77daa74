"""The seeds tables of README.md: the gait of each seed's kept policy against the issue's goals,
for today's `--preset walking` and for the preset before it.

Usage: python seeds.py   (reads the eval reports in this folder)
"""

import json
import statistics
from collections import Counter

ROWS = [
    ("0", "`best/` at the end (gen 323, 1.47 M steps)", "runs/walking-chatter-clip-cap-s0/best-eval.json"),
    ("1", "`best/` at the end (gen 410, 4.00 M steps) = `flagship/`", "flagship-eval10.json"),
    ("1", "`best/` at 2.30 M steps (gen 324)", "runs/walking-chatter-clip-cap-s1/best-2.30M-eval.json"),
    ("2", "`best/` at the end (gen 473, 3.97 M steps)", "runs/walking-chatter-clip-cap-s2/best-eval.json"),
    ("2", "`best/` at 2.91 M steps (gen 422)", "runs/walking-chatter-clip-cap-s2/best-2.91M-eval.json"),
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


def main():
    table(ROWS)
    print()
    table(PREVIOUS)


if __name__ == "__main__":
    main()
