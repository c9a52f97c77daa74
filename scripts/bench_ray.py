#!/usr/bin/env python3
"""Per-generation cost of rolling the population out on Ray (`python -m esrl_rs.ray train`)
against the local rayon evaluator (`esrl train`), on this machine.

For each preset given, trains the same agent, seed and generations with both front ends and
prints one JSON line: seconds per generation of each (from metrics.csv's wall_s, generation 0
left out: it holds the warm start), the overhead, the seconds the driver waited on Ray per
generation, bytes per generation each way, and whether the rows agreed.

    .venv/bin/python scripts/bench_ray.py --preset smoke --preset quick --generations 8
    .venv/bin/python scripts/bench_ray.py --preset paper --generations 3

Needs the esrl binary (ESRL_BIN, default target/release/esrl) and esrl_rs with Ray installed.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def per_generation(run: Path) -> float:
    with open(run / "metrics.csv", newline="") as f:
        wall = [float(r["wall_s"]) for r in csv.DictReader(f)]
    return (wall[-1] - wall[0]) / (len(wall) - 1)


def rows(run: Path) -> list:
    with open(run / "metrics.csv", newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(f)]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", action="append", required=True)
    ap.add_argument("--agent", default="es-sac")
    ap.add_argument("--generations", type=int, default=8)
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                    help="local: rollout and update threads; Ray: workers and driver threads")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    esrl = os.environ.get("ESRL_BIN", str(REPO / "target" / "release" / "esrl"))
    for preset in args.preset:
        with tempfile.TemporaryDirectory() as tmp:
            local, remote = Path(tmp) / "local", Path(tmp) / "ray"
            common = [args.agent, "--preset", preset, "--seed", str(args.seed),
                      "--generations", str(args.generations), "--threads", str(args.threads)]
            subprocess.run([esrl, "train", *common, "--no-progress", "--out", str(local)],
                           check=True, capture_output=True)
            proc = subprocess.run(
                [sys.executable, "-m", "esrl_rs.ray", "train", *common, "--address", "local",
                 "--workers", str(args.threads), "--out", str(remote)],
                check=True, capture_output=True, text=True)
            m = re.search(r"per generation: ([\d.]+ \w+) of genomes out, ([\d.]+ \w+) of "
                          r"episodes back, ([\d.]+) s waiting", proc.stderr)
            t_local, t_ray = per_generation(local), per_generation(remote)
            print(json.dumps({
                "preset": preset,
                "agent": args.agent,
                "generations": args.generations,
                "threads": args.threads,
                "local_s_per_generation": round(t_local, 3),
                "ray_s_per_generation": round(t_ray, 3),
                "overhead_s": round(t_ray - t_local, 3),
                "ratio": round(t_ray / t_local, 3),
                "ray_wait_s_per_generation": float(m.group(3)) if m else None,
                "genomes_out_per_generation": m.group(1) if m else None,
                "episodes_back_per_generation": m.group(2) if m else None,
                "rows_equal": rows(local) == rows(remote),
            }), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
