import csv, json, sys, os
# usage: table.py label=run ...  -> markdown table
print("| run | what differs from `--preset quick` | gens | env steps | wall (s) | best curve | final (mean last 10) | mean ep. length, last 10 (steps) | eval: return | eval: steps (s) | eval: distance (m) | eval: fwd v (m/s) | eval: mean abs lateral (m) | eval: mean abs torque (N·m) | eval: knee asym | fell |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for arg in sys.argv[1:]:
    run, label = arg.split("=", 1)
    rows = list(csv.DictReader(open(f"{run}/metrics.csv")))
    c = [float(r["curve"]) for r in rows]; L = [float(r["mean_length"]) for r in rows]
    n = min(10, len(c)); last = rows[-1]
    ev = "| – " * 8 + "|"
    p = f"{run}/eval.json"
    if os.path.exists(p):
        e = json.load(open(p)); top = e["mean"]; m = dict(top["gait"]); m["return"] = top["return"]
        def g(*ks):
            for k in ks:
                if k in m and m[k] is not None: return m[k]
            return float("nan")
        steps = top["length"]
        ev = (f"| {g('return'):.2f} | {steps:.1f} ({steps*0.025:.2f}) | {g('distance'):.3f} | {g('mean_forward_velocity','forward_velocity'):.2f} | "
              f"{g('mean_abs_lateral','abs_lateral'):.3f} | {g('mean_abs_torque_overall'):.1f} | {g('knee_torque_asymmetry','knee_asymmetry'):.2f} | {top['falls']}/{top['episodes']} |")
    print(f"| `{os.path.basename(run)}` | {label} | {len(rows)} | {last['env_steps']} | {float(last['wall_s']):.0f} | {max(c):.1f} | {sum(c[-n:])/n:.1f} | {sum(L[-n:])/n:.1f} " + ev)
