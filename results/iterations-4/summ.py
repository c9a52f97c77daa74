import csv, sys
for run in sys.argv[1:]:
    try:
        rows = list(csv.DictReader(open(f"{run}/metrics.csv")))
    except Exception as e:
        print(run, e); continue
    if not rows: continue
    f = lambda k: [float(r[k]) for r in rows]
    c = f("curve"); L = f("mean_length"); bf=f("best_fitness")
    last = rows[-1]
    n=min(10,len(c))
    print(f"{run.split('/')[-1]:28s} gens={len(rows):3d} steps={last['env_steps']:>7s} wall={float(last['wall_s']):6.0f}s "
          f"best_curve={max(c):6.1f} best_indiv={max(bf):6.1f} final10={sum(c[-n:])/n:6.1f} "
          f"len_last10={sum(L[-n:])/n:5.1f} len_max={max(L):5.1f} alpha={float(last['alpha'] or 0):.3f} closs={float(last['critic_loss'] or 0):.3g} q0={float(last['q0'] or 0):.3g}")
