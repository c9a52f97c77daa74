"""Replays which policy a run keeps when a stopped check that ranks above the kept one runs in
full (`check.stop_early` with completion, `crates/run/src/check.rs`), from two logs of the same
run: one whose checks all ran in full, one with `stop_early` (a run learns the same whatever
its checks do, and each start's episode is deterministic, so a completed check's record is the
full log's).

    python results/speed/replay_kept.py FULL_checks.jsonl STOP_checks.jsonl
"""
import json
import sys


def score(r):
    """The rank key of `CheckResult::score`."""
    n = max(r["starts"], 1)
    return (r["at_bar"], r["finished"] / n, -r["falls"] / n,
            r["classes"].get("walk", 0) / n, r["mean_distance"])


def main(full_path, stop_path):
    full = [json.loads(line) for line in open(full_path)]
    stop = [json.loads(line) for line in open(stop_path)]
    assert len(full) == len(stop), "not the same run"
    kept = {"stop_early": None, "completion": None, "every check in full": None}
    steps = {"stop_early": 0, "completion": 0}
    completed = 0
    for i, (f, s) in enumerate(zip(full, stop)):
        assert (f["row"], f["env_steps"]) == (s["row"], s["env_steps"]), "not the same run"
        k = kept["completion"]
        if s.get("stopped") and (k is None or score(s) > score(k)):
            r, completed = f, completed + 1
        else:
            r = s
        steps["stop_early"] += s["check_steps"]
        steps["completion"] += r["check_steps"]
        for rule, rec in [("stop_early", s), ("completion", r), ("every check in full", f)]:
            if kept[rule] is None or score(rec) > score(kept[rule]):
                kept[rule] = dict(rec, index=i)
    print(f"{len(full)} checks; {completed} completed; check env steps "
          f"{steps['stop_early']:,} with stop_early, {steps['completion']:,} with completion")
    for rule, k in kept.items():
        print(f"  kept ({rule}): check {k['index']} at {k['env_steps']:,} env steps, "
              f"{k['starts']} starts, {k['finished']} finished, {k['falls']} falls, "
              f"{k['mean_distance']:.1f} m")


if __name__ == "__main__":
    main(*sys.argv[1:3])
