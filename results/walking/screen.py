"""Summarises walking-recipe runs: training curve metrics, then the gait of the final (and,
for ES runs, best) policy from `esrl eval RUN --episodes 10` (RUN/eval.json,
RUN/best/eval.json, or RUN/best-eval.json in a record copied by collect.py).

Usage: python screen.py NAME=RUN_DIR [NAME=RUN_DIR ...]   (Markdown table on stdout)
"""

import json
import statistics
import sys
from collections import Counter
from pathlib import Path


def gait_row(eval_path: Path):
    e = json.loads(eval_path.read_text())
    eps = e["episodes"]
    classes = Counter()
    alt, flight, double, at_limit, rom, dist, speed, lat = [], [], [], [], [], [], [], []
    finished = 0
    falls = 0
    times = []
    for ep in eps:
        g = ep["gait"]
        c = g.get("cycle") or {}
        classes[c.get("gait_class", "?")] += 1
        if c.get("alternation") is not None:
            alt.append(c["alternation"])
        if c:
            flight.append(c["flight"])
            double.append(c["double_support"])
        joints = g.get("joints") or []
        lim = [j.get("at_limit") or 0 for j in joints
               if "hip" in j["name"] or "knee" in j["name"]]
        if lim:
            at_limit.append(statistics.mean(lim))
        r = [j["range"] * 57.29578 for j in joints if j.get("range") is not None]
        if r:
            rom.append(statistics.mean(r))
        dist.append(g["distance"])
        speed.append(g["mean_forward_velocity"])
        lat.append(g["mean_abs_lateral"])
        falls += bool(g["fell"])
        if g.get("track_time") is not None:
            finished += 1
            times.append(g["track_time"])

    def m(v, spec=".2f"):
        return "–" if not v else format(statistics.mean(v), spec)

    cls = ", ".join(f"{k} {v}" for k, v in classes.most_common())
    return {
        "classes": cls,
        "finished": f"{finished}/{len(eps)}",
        "falls": f"{falls}/{len(eps)}",
        "distance": m(dist, ".1f"),
        "speed": m(speed),
        "lateral": m(lat, ".3f"),
        "alternation": m(alt),
        "flight": m([100 * f for f in flight], ".0f"),
        "double": m([100 * d for d in double], ".0f"),
        "at_limit": m([100 * a for a in at_limit], ".0f"),
        "rom": m(rom, ".0f"),
        "track_time": m(times, ".1f"),
    }


def main():
    head = ["run", "policy", "Best-Win-50", "env steps", "wall (s)", "gait classes (10 starts)",
            "finished 50 m", "falls", "distance (m)", "fwd v (m/s)", "track time (s)",
            "mean |lat| (m)", "alternation", "flight %", "double support %",
            "hip/knee at limit %", "mean ROM (°)"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * 2 + "---:|" * (len(head) - 2))
    for arg in sys.argv[1:]:
        name, d = arg.split("=", 1)
        run = Path(d)
        s = json.loads((run / "summary.json").read_text())
        best = run / "best" / "eval.json"
        if not best.exists():  # a run record copied into results/ (collect.py)
            best = run / "best-eval.json"
        for label, ev in (("last", run / "eval.json"), ("best", best)):
            if not ev.exists():
                continue
            g = gait_row(ev)
            print(f"| {name} | {label} | {s['best_win_50']:.1f} | {s['env_steps']} | "
                  f"{s['wall_s']:.0f} | {g['classes']} | {g['finished']} | {g['falls']} | "
                  f"{g['distance']} | {g['speed']} | {g['track_time']} | {g['lateral']} | "
                  f"{g['alternation']} | {g['flight']} | {g['double']} | {g['at_limit']} | "
                  f"{g['rom']} |")


if __name__ == "__main__":
    main()
