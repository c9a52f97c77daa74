"""Learning curves of the ES-SAC experiments in this folder (results/README.md, section 2).

Usage: python plot_curves.py [OUT.png]   (needs matplotlib; reads */metrics.csv here)
"""

import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "curves.png"
fig, (ax_r, ax_l) = plt.subplots(1, 2, figsize=(12, 4.2))
for run in sorted(p.parent for p in here.glob("*/metrics.csv")):
    rows = list(csv.DictReader(open(run / "metrics.csv")))
    steps = [int(r["env_steps"]) / 1e6 for r in rows]
    curve = [float(r["curve"]) for r in rows]
    length = [float(r["mean_length"]) * 0.025 for r in rows]
    ax_r.plot(steps, curve, lw=0.8, label=run.name)
    ax_l.plot(steps, length, lw=0.8, label=run.name)
ax_r.set(xlabel="environment steps (millions)", ylabel="return of the kept policy",
         title="ES-SAC learning curves (16 solver iterations)")
ax_l.set(xlabel="environment steps (millions)", ylabel="mean episode length (s)",
         title="Mean population episode length")
for ax in (ax_r, ax_l):
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=100)
print(f"wrote {out}")
