"""Records of the equal-generations comparison taken from the 4 M-step runs, where that is exact.

The comparison at equal generations/episodes (`compare-equal-gen/`) needs, for every ES run,
the policy it keeps after N generations. A run's first N generations do not depend on its
budget (training is deterministic and nothing in it is scheduled on the budget: the N-row
retrains of compare-runs.sh repeat the first N rows of the 4 M-step runs to the last digit,
which `--check` verifies), and `RUN/best/` is a running maximum: the policy of the best row
so far, replaced only by a better row. So when a 4 M-step run's kept policy comes from a
generation below N (`best/best.json`), it is the very policy an N-generation run keeps, and
its evaluation (`best/eval.json`) is that run's evaluation. This writes such a run's record
into compare-equal-gen/<run>/ without training it again: config.toml as trained, metrics.csv
cut to the first N rows, summary.json of the cut curve (with `first_rows_of` saying where it
comes from), best/ and pictures/ as recorded. A run whose kept policy is younger than N is
refused: it has to be trained to N generations (compare-runs.sh with
TRAIN_ARGS="--generations N --episodes N --steps 1000000000").

usage: python equal-gen-records.py N RUN... [--into DIR]   (RUN = es-sac-s0, ...; reads
                 compare/RUN, writes DIR/RUN, default compare-equal-gen/RUN; with --into a
                 folder path is the record itself: runs/screen2m-base-s0, the screens' base)
       python equal-gen-records.py N --check RUN...
                 (compares compare-equal-gen/RUN/metrics.csv, a retrain to N, with the
                  first N rows of compare/RUN/metrics.csv, every column but wall_s)
"""
import argparse
import csv
import json
import shutil
import sys
from pathlib import Path

from esrl_rs import metrics

HERE = Path(__file__).resolve().parent
FULL, EQUAL = HERE / "compare", HERE / "compare-equal-gen"


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def check(n, name):
    """Whether the retrain's N rows equal the first N rows of the 4 M-step run."""
    ours, full = rows_of(EQUAL / name / "metrics.csv"), rows_of(FULL / name / "metrics.csv")
    if len(ours) != n or len(full) < n:
        print(f"{name}: {len(ours)} rows retrained, {len(full)} in the full run; need {n}")
        return False
    diff = [(i, k) for i, (a, b) in enumerate(zip(ours, full[:n]))
            for k in a if k != "wall_s" and a[k] != b.get(k)]
    if diff:
        i, k = diff[0]
        print(f"{name}: {len(diff)} cells differ, first at row {i}, column {k}: "
              f"{ours[i][k]} against {full[i][k]}")
        return False
    print(f"{name}: the {n} retrained rows equal the full run's first {n} "
          f"({len(ours[0]) - 1} columns each, wall_s aside)")
    return True


def cut(n, name, dst):
    src = FULL / name
    best = json.loads((src / "best" / "best.json").read_text())
    rows = rows_of(src / "metrics.csv")
    if best["generation"] >= n:
        sys.exit(f"{name}: its kept policy comes from generation {best['generation']} >= {n}: "
                 f"train it to {n} generations instead (compare-runs.sh)")
    if len(rows) < n:
        sys.exit(f"{name}: {len(rows)} rows, fewer than {n}")
    if dst.exists():
        shutil.rmtree(dst)
    (dst / "best").mkdir(parents=True)
    shutil.copy(src / "config.toml", dst / "config.toml")
    with open(src / "metrics.csv", newline="") as f:
        lines = f.readlines()
    (dst / "metrics.csv").write_text("".join(lines[: n + 1]))
    for f in ("best.json", "eval.json"):
        shutil.copy(src / "best" / f, dst / "best" / f)
    if (src / "pictures").is_dir():
        shutil.copytree(src / "pictures", dst / "pictures")
    curve = [float(r["curve"]) for r in rows[:n]]
    old = json.loads((src / "summary.json").read_text())
    summary = {k: old[k] for k in ("agent", "env", "seed")}
    summary.update(metrics.curve_summary(curve))
    summary.update({
        "q0_mean": metrics.q0_mean([float(r["q0"]) for r in rows[:n] if r["q0"] != ""]),
        "length": n,
        "env_steps": int(rows[n - 1]["env_steps"]),
        "best": max(curve),
        "wall_s": float(rows[n - 1]["wall_s"]),
        "finished": True,
        "first_rows_of": f"compare/{name} ({n} of {len(rows)} rows; kept policy from "
                         f"generation {best['generation']})",
    })
    (dst / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"{name}: first {n} of {len(rows)} rows, kept policy from generation "
          f"{best['generation']} -> {dst}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("n", type=int)
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--into", type=Path, help="the record's folder (one RUN)")
    parser.add_argument("runs", nargs="+")
    args = parser.parse_args()
    if args.check:
        sys.exit(0 if all([check(args.n, r) for r in args.runs]) else 1)
    if args.into and len(args.runs) != 1:
        parser.error("--into takes one RUN")
    for r in args.runs:
        cut(args.n, r, (Path.cwd() / args.into).resolve() if args.into else EQUAL / r)


if __name__ == "__main__":
    main()
