"""``python -m esrl_rs.ray train AGENT``: ``esrl train`` with the population on a Ray cluster;
``python -m esrl_rs.ray study STUDY.toml``: ``esrl study run`` with one Ray task per run.

Options are ``esrl train``'s, plus ``--address`` (``local`` starts a cluster in this process;
``auto`` joins the one ``ray start`` runs on this machine; ``HOST:PORT`` or ``ray://HOST:PORT``
joins a remote one) and ``--workers`` (local: the CPUs of the cluster it starts; otherwise the
most rollouts in flight at once). The run folder is the one ``esrl train`` writes.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from typing import Any, Callable, Dict, List, Optional, TypeVar

T = TypeVar("T")

AGENTS = ["es-sac", "es-td3", "es-ddpg", "sac", "td3", "ddpg"]
PRESETS = ["paper", "quick", "long", "walking", "walking-torque", "walker", "walker-fast",
           "walker-mirror", "walker-even", "walker-robust", "smoke"]
ENVS = ["walk", "pendulum"]


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m esrl_rs.ray",
        description="Train with the ES population rolled out on a Ray cluster; results equal "
        "`esrl train`'s for the same settings and seed.",
    )
    sub = p.add_subparsers(dest="command", required=True)
    t = sub.add_parser(
        "train",
        help="train an agent (the run folder of `esrl train`)",
        description="Train an agent; hybrid agents roll their populations out on Ray tasks, "
        "the driver runs the ES update and the gradient updates. Same files, checkpoints and "
        "results as `esrl train`.",
    )
    t.add_argument("agent", choices=AGENTS)
    t.add_argument("--seed", type=int, help="seed of every random stream in the run")
    t.add_argument("--out", metavar="DIR", help="run folder [default: runs/<agent>-s<seed>, "
                   "runs/<agent>-<preset>-s<seed> for a preset other than walker-even]")
    t.add_argument(
        "--resume",
        metavar="DIR",
        help="continue the run in DIR from its last checkpoint (a run of either front end); "
        "--generations, --episodes, --steps and --threads may change",
    )
    t.add_argument("--preset", choices=PRESETS,
                   help="named settings [default: walker-even, the recipe that walks; "
                   "paper: the paper's literal protocol]")
    t.add_argument("--config", metavar="FILE.toml", help="TOML file overriding the preset")
    t.add_argument("--env", choices=ENVS, help="environment [default: walk]")
    t.add_argument("--urdf", metavar="PATH", help="a URDF instead of the embedded humanoid "
                   "(workers must be able to read it at the same path)")
    t.add_argument("--threads", type=int,
                   help="driver threads for the gradient updates [default: all cores]")
    t.add_argument("--generations", type=int, help="generations for ES agents")
    t.add_argument("--episodes", type=int, help="episodes for plain agents")
    t.add_argument("--steps", type=int, help="environment-step budget (any agent)")
    t.add_argument("--init", metavar="DIR",
                   help="start from a trained policy's weights (fine-tuning): a run folder, "
                   "its best/ or checkpoint/, or a study record's policy/")
    t.add_argument("--until", choices=["walk", "budget"],
                   help="walk: stop at the first policy at the walking bar; budget: run the "
                   "whole budget [default: the config's]")
    t.add_argument("--no-progress", action="store_true",
                   help="accepted for parity with `esrl train`; progress is logged every 10 s")
    t.add_argument(
        "--address",
        default="local",
        help="Ray cluster: `local` starts one in this process (default), `auto` joins the "
        "local `ray start` cluster, HOST:PORT or ray://HOST:PORT a remote one",
    )
    t.add_argument(
        "--workers",
        type=int,
        help="local: CPUs of the cluster started [default: all cores]; otherwise the most "
        "rollouts in flight [default: as many as the generation has]",
    )
    st = sub.add_parser(
        "study",
        help="run a study file with one Ray task per run (the folder of `esrl study run`)",
        description="Each run of the study is one Ray task that runs `esrl study run STUDY "
        "--shard k/n --jobs 1` for its index k (n = the study's runs) into the study folder, "
        "which the workers must share; the records are those of `esrl study run`.",
    )
    st.add_argument("study", help="the study file")
    st.add_argument("--out", metavar="DIR", help="the study folder [default: "
                    "studies/<file stem>]; every worker must see it at the same path")
    st.add_argument("--threads", type=int, default=1, help="threads per run [default: 1]")
    st.add_argument("--esrl", metavar="PATH", help="the esrl binary on the workers [default: "
                    "$ESRL_BIN, else `esrl` on the PATH]")
    st.add_argument("--address", default="local", help="Ray cluster, as for `train`")
    st.add_argument("--workers", type=int,
                    help="local: CPUs of the cluster started [default: all cores]")
    return p


def _study_runs(path: str) -> int:
    """How many runs a study file has (each arm's seeds: its own, else the study's), as
    `esrl study` counts them."""
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        import tomli as tomllib  # type: ignore[no-redef]

    with open(path, "rb") as f:
        study = tomllib.load(f)
    def count(seeds: Any) -> int:
        return seeds if isinstance(seeds, int) else len(seeds)

    default = study.get("seeds", 0)
    return sum(count(arm.get("seeds", default)) for arm in study.get("arm", []))


def study(argv: List[str]) -> int:
    """`esrl study run` with one Ray task per run (`--shard k/n`)."""
    import shutil
    import subprocess

    args = _parser().parse_args(argv)
    esrl = args.esrl or os.environ.get("ESRL_BIN") or shutil.which("esrl")
    if not esrl:
        print("error: no esrl binary: pass --esrl PATH, set ESRL_BIN or put esrl on the PATH",
              file=sys.stderr)
        return 2
    try:
        n = _study_runs(args.study)
    except (OSError, ValueError) as e:
        print(f"error: {args.study}: {e}", file=sys.stderr)
        return 2
    if n == 0:
        print(f"error: {args.study} has no runs", file=sys.stderr)
        return 2
    out = os.path.abspath(args.out or os.path.join(
        "studies", os.path.splitext(os.path.basename(args.study))[0]))
    study_file = os.path.abspath(args.study)
    try:
        import ray
    except ImportError:
        print('error: Ray is not installed: pip install "esrl_rs[ray]" (or pip install ray)',
              file=sys.stderr)
        return 1
    # The study folder's study.toml, written once here so that the tasks, which all check it,
    # never write it at the same time.
    os.makedirs(out, exist_ok=True)
    held = os.path.join(out, "study.toml")
    with open(study_file, "rb") as f:
        text = f.read()
    if not os.path.exists(held):
        with open(held + ".tmp", "wb") as f:
            f.write(text)
        os.replace(held + ".tmp", held)
    _start_ray(args.address, args.workers)

    @ray.remote(num_cpus=args.threads)
    def one_run(k: int) -> Dict[str, Any]:
        cmd = [esrl, "study", "run", study_file, "--out", out, "--shard", f"{k}/{n}",
               "--jobs", "1", "--threads", str(args.threads), "--no-progress"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        return {"k": k, "status": proc.returncode, "stderr": proc.stderr[-2000:]}

    print(f"study {args.study}: {n} run(s) as Ray tasks at {args.address} → {out}",
          file=sys.stderr, flush=True)
    results = ray.get([one_run.remote(k) for k in range(n)])
    ray.shutdown()
    failed = [r for r in results if r["status"] != 0]
    for r in failed:
        print(f"run {r['k']} failed ({r['status']}):\n{r['stderr']}", file=sys.stderr)
    if failed:
        return 1
    print(f"done; `esrl study report {out}` tabulates the records", file=sys.stderr)
    return 0


def _human(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def _bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB"):
        if n < 1024:
            return f"{n:.0f} B" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GiB"


def _start_ray(address: str, workers: Optional[int]) -> None:
    import ray

    if address == "local":
        ray.init(
            num_cpus=workers or os.cpu_count() or 1,
            include_dashboard=False,
            log_to_driver=True,
            configure_logging=False,
        )
    else:
        ray.init(address=address, log_to_driver=True, configure_logging=False)


class _StopSignals:
    """Ctrl-C (SIGINT) and SIGTERM as `esrl train` treats them: the first finishes the row in
    progress, writes a checkpoint and exits with 128 + the signal; a second exits at once."""

    def __init__(self, unit: str) -> None:
        self.requested = 0
        self.unit = unit
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, self._on_signal)

    def _on_signal(self, signum: int, _frame: object) -> None:
        name = signal.Signals(signum).name
        if self.requested:
            print(f"{name} again: exiting now; the rows since the last checkpoint are lost",
                  file=sys.stderr, flush=True)
            os._exit(128 + signum)
        self.requested = signum
        print(f"{name}: stopping after the current {self.unit} with a checkpoint (send it "
              "again to exit at once)", file=sys.stderr, flush=True)


def _off_main_thread(call: Callable[[], T]) -> T:
    """Runs `call` on another thread and waits, so that the main thread keeps handling
    signals while the Rust core trains (it releases the interpreter)."""
    box: Dict[str, Any] = {}

    def run() -> None:
        try:
            box["value"] = call()
        except BaseException as e:  # handed to the main thread
            box["error"] = e

    worker = threading.Thread(target=run, name="esrl-driver-step", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(0.2)
    if "error" in box:
        raise box["error"]
    return box["value"]


def train(argv: List[str]) -> int:
    args = _parser().parse_args(argv)
    if args.resume is not None:
        clash = [f"--{n}" for n in ("out", "config", "preset", "seed", "env", "urdf", "init")
                 if getattr(args, n) is not None]
        if clash:
            print(f"error: --resume cannot be used with {', '.join(clash)} (the run's "
                  "config.toml is used)", file=sys.stderr)
            return 2
    if args.workers is not None and args.workers < 1:
        print("error: --workers must be at least 1", file=sys.stderr)
        return 2
    try:
        import ray  # noqa: F401
    except ImportError:
        print('error: Ray is not installed: pip install "esrl_rs[ray]" (or pip install ray)',
              file=sys.stderr)
        return 1

    from .. import _native
    from . import RayEvaluator

    try:
        plan = _native.plan_train(
            args.agent, seed=args.seed, out=args.out, resume=args.resume, preset=args.preset,
            config=args.config, env=args.env, urdf=args.urdf, threads=args.threads,
            generations=args.generations, episodes=args.episodes, steps=args.steps,
            until=args.until, init=args.init,
        )
    except (_native.EsrlError, ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for note in plan.notes:
        print(note, file=sys.stderr)
    if not plan.hybrid:
        print(f"{plan.agent} has no population: it trains on the driver alone, as `esrl train` "
              "would", file=sys.stderr)
    _start_ray(args.address, args.workers)
    import ray

    evaluator = RayEvaluator(plan.config_toml, None if args.address == "local" else args.workers)
    cpus = int(ray.cluster_resources().get("CPU", 0))
    driver = _native.Driver(plan, evaluator)
    opening = driver.opening
    if opening["kind"] == "resumed":
        print(f"resuming {plan.root} from {opening['checkpoint']} ({opening['rows']} rows, "
              f"{opening['env_steps']} env steps)", file=sys.stderr)
    unit = "generation" if plan.hybrid else "episode"
    print(f"training {plan.agent} (seed {plan.seed}, {driver.total} {unit}s) into {plan.root}; "
          f"rollouts on Ray at {args.address} ({cpus} CPUs), updates on the driver; Ctrl-C "
          f"stops after the current {unit} with a checkpoint", file=sys.stderr, flush=True)

    stop = _StopSignals(unit)
    # Rows run in this session (a restart starts the run's row count over).
    rows, t0, last = 0, time.perf_counter(), 0.0
    while not stop.requested and not driver.done():
        row = _off_main_thread(driver.step)
        rows += 1
        if row["restart"]:
            print(row["restart"], file=sys.stderr, flush=True)
        if row["estimate"]:
            print(row["estimate"], file=sys.stderr, flush=True)
        now = time.perf_counter() - t0
        if now - last > 10.0:
            last = now
            print(f"[{row['rows']}/{driver.total}] {row['summary']} | best so far "
                  f"{row['best']:.1f} | {_human(driver.wall_s)}", file=sys.stderr, flush=True)
    finished = driver.done()
    driver.finish(finished)
    traffic = driver.traffic
    if plan.hybrid and rows > 0:
        print(f"ray: {rows} {unit}s in {_human(time.perf_counter() - t0)}; per {unit}: "
              f"{_bytes(traffic['bytes_out'] / rows)} of genomes out, "
              f"{_bytes(traffic['bytes_in'] / rows)} of episodes back, "
              f"{evaluator.wait_s / rows:.2f} s waiting on rollouts", file=sys.stderr)
    if finished:
        print(f"done: {driver.rows} rows, {driver.env_steps} env steps, "
              f"{_human(driver.wall_s)} -> {plan.root}", file=sys.stderr)
    else:
        print(f"stopped after {driver.rows} rows; checkpoint written. Continue with: python -m "
              f"esrl_rs.ray train {plan.agent} --resume {plan.root} (or esrl train)",
              file=sys.stderr)
    ray.shutdown()
    return 0 if finished else 128 + stop.requested


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "study":
        return study(argv)
    return train(argv)


if __name__ == "__main__":
    sys.exit(main())
