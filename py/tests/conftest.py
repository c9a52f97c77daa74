"""Fixtures: synthetic run folders (written here, in the CLI's format) and CLI-made runs."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

import pytest

REPO = Path(__file__).resolve().parents[2]
ACTUATORS = ["left_hip", "left_knee", "left_ankle", "right_hip", "right_knee", "right_ankle"]


def allow_no_cli() -> bool:
    return os.environ.get("ESRL_ALLOW_NO_CLI", "0") == "1"


def no_cli(reason: str) -> None:
    """Fails (CI) or skips (ESRL_ALLOW_NO_CLI=1 while the CLI is being written)."""
    if allow_no_cli():
        pytest.skip(f"{reason} (ESRL_ALLOW_NO_CLI=1)")
    pytest.fail(f"{reason}; build it (cargo build --release -p esrl), point ESRL_BIN at it, or "
                "set ESRL_ALLOW_NO_CLI=1 while developing", pytrace=False)


@pytest.fixture(scope="session")
def esrl_bin() -> Path:
    """The esrl CLI: $ESRL_BIN, else target/release/esrl of this checkout."""
    env = os.environ.get("ESRL_BIN")
    path = Path(env) if env else REPO / "target" / "release" / "esrl"
    if not (path.is_file() and os.access(path, os.X_OK)):
        no_cli(f"the esrl CLI binary was not found at {path}")
    return path


@pytest.fixture(scope="session")
def cli_train(esrl_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Callable[..., Path]:
    """Trains with the CLI into a fresh folder and returns it (cached per argument list)."""
    cache: Dict[tuple, Path] = {}

    def train(agent: str, *args: str) -> Path:
        key = (agent,) + args
        if key in cache:
            return cache[key]
        out = tmp_path_factory.mktemp(f"cli-{agent}") / "run"
        cmd = [str(esrl_bin), "train", agent, *args, "--out", str(out)]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        if proc.returncode != 0 or not (out / "summary.json").is_file():
            no_cli(f"`{' '.join(cmd)}` did not produce a run (exit {proc.returncode}): "
                   f"{proc.stderr.strip()[-500:]}")
        cache[key] = out
        return out

    return train


@pytest.fixture(scope="session")
def cli_eval(esrl_bin: Path) -> Callable[..., Dict[str, Any]]:
    """Runs `esrl eval RUN --last --episodes K` (the run's last checkpoint, the policy
    `esrl_rs.load_policy(RUN, last=True)` loads) and returns the RUN/eval.json it wrote;
    `last=False`: `esrl eval RUN` (the kept policy, `load_policy(RUN)`'s), whose eval.json is
    RUN/best/'s when the run keeps one."""

    def evaluate(run: Path, episodes: int = 1, last: bool = True) -> Dict[str, Any]:
        cmd = [str(esrl_bin), "eval", str(run), "--episodes", str(episodes)]
        cmd += ["--last"] if last else []
        kept = not last and (run / "best").is_dir()
        path = run / "best" / "eval.json" if kept else run / "eval.json"
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        if proc.returncode != 0 or not path.is_file():
            no_cli(f"`{' '.join(cmd)}` did not write {path} (exit {proc.returncode}): "
                   f"{proc.stderr.strip()[-500:]}")
        return json.loads(path.read_text(encoding="utf-8"))

    return evaluate


def write_run(
    root: Path,
    agent: str,
    seed: int,
    curve: List[float],
    es: bool = False,
    q0: Optional[List[Optional[float]]] = None,
    eval_episodes: Optional[List[Dict[str, Any]]] = None,
    summary: Optional[Dict[str, Any]] = None,
) -> Path:
    """A run folder in the CLI's format (crates/cli/src/run_dir.rs)."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "config.toml").write_text(
        f'agent = "{agent}"\nenv = "walk"\npreset = "smoke"\nseed = {seed}\n\n'
        "[es]\nsigma = 0.25\n", encoding="utf-8")
    rows = []
    for i, c in enumerate(curve):
        row: Dict[str, Any] = {"generation" if es else "episode": i,
                               "env_steps": 100 * (i + 1), "curve": c}
        if es:
            row.update(best_fitness=c + 1.0, mean_fitness=c - 1.0, rl_fitness=None, sigma=0.25)
        else:
            row.update({"return": c, "length": 100})
        row["q0"] = None if q0 is None else q0[i]
        row["critic_loss"] = None
        row["wall_s"] = 0.01 * i
        rows.append(row)
    with open(root / "metrics.jsonl", "w", encoding="utf-8") as f:
        for row in rows:
            f.write(json.dumps(row) + "\n")
    cols = list(rows[0])
    with open(root / "metrics.csv", "w", encoding="utf-8") as f:
        f.write(",".join(cols) + "\n")
        for row in rows:
            f.write(",".join("" if row[c] is None else str(row[c]) for c in cols) + "\n")
    if summary is None:
        n = len(curve)
        summary = {"agent": agent, "seed": seed, "auc": sum(curve), "nauc": sum(curve) / n,
                   "final_50": sum(curve[-50:]) / len(curve[-50:]), "best_win_50": None,
                   "episodes_to_target": None}
    (root / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    if eval_episodes is not None:
        (root / "eval.json").write_text(json.dumps({"episodes": eval_episodes, "version": 1}),
                                        encoding="utf-8")
    return root


def gait(power_scale: float, fell: bool = False) -> Dict[str, Any]:
    """A GaitMetrics object as esrl-metrics serialises it."""
    torque = [10.0 * power_scale * (k + 1) for k in range(6)]
    power = [5.0 * power_scale * (k + 1) for k in range(6)]
    return {
        "track_length": 50.0, "track_time": None if fell else 40.0 / power_scale,
        "mean_forward_velocity": 1.0 * power_scale, "mean_abs_lateral": 0.05,
        "mean_vertical": -0.01, "mean_abs_vertical": 0.02, "actuator_names": ACTUATORS,
        "mean_abs_torque": torque, "mean_abs_power": power,
        "mean_abs_torque_overall": sum(torque) / 6, "mean_abs_power_overall": sum(power) / 6,
        "knee_torque_asymmetry": 0.1, "foot_names": ["left_foot", "right_foot"],
        "mean_foot_force": [300.0, 310.0], "distance": 50.0, "fell": fell, "steps": 4,
        "duration": 0.1,
    }


def stick(times: List[float], x0: float) -> Dict[str, Any]:
    """A side view in `esrl eval`'s format: a leg (line), a foot (box), a head (circle)."""
    parts = [{"link": "left_shank", "kind": "line", "radius": 0.045},
             {"link": "right_foot", "kind": "box", "radius": 0.0},
             {"link": "torso", "kind": "circle", "radius": 0.1}]
    frames = []
    for t in times:
        x = x0 + t
        frames.append([[x, 0.5, x, 0.1], [x, 0.0, x + 0.2, 0.0, x + 0.2, 0.05, x, 0.05],
                       [x, 1.6]])
    return {"interval": 0.1, "parts": parts, "time": times, "frames": frames}


def episode(seed: int, power_scale: float) -> Dict[str, Any]:
    t = [0.025 * (k + 1) for k in range(40)]
    # Alternating feet, 0.5 s cycle: left down 0..11, right 10..21 (mod 20).
    contact = [[int(k % 20 < 12), int((k + 10) % 20 < 12)] for k in range(40)]
    angles = [[0.1 * math.sin(k / 3 + j) for j in range(6)] for k in range(40)]
    return {
        "seed": seed, "return": 123.5, "gait": gait(power_scale),
        "trace": {"time": t, "x": [1.25 * v * power_scale for v in t],
                  "y": [0.05 * math.sin(3 * v) for v in t],
                  "z_error": [-0.01] * 40, "forward_velocity": [1.25 * power_scale] * 40,
                  "contact": contact, "joint_names": ACTUATORS,
                  "joint_limits": [[-1.5708, 0.5236], [0.0873, 1.5708], [-0.349, 0.349]] * 2,
                  "joint_angle": angles, "stick": stick([0.1 * k for k in range(1, 11)], 0.0)},
        "extra_key": {"kept": True},
    }


@pytest.fixture
def synthetic_runs(tmp_path: Path) -> List[Path]:
    """Two agents × two seeds, 60 generations/episodes, all evaluated."""
    runs = []
    for agent, es, scale in (("es-sac", True, 1.0), ("sac", False, 0.5)):
        for seed in (0, 1):
            curve = [scale * (i + seed) for i in range(60)]
            q0 = [0.1 * i for i in range(60)]
            runs.append(write_run(tmp_path / f"{agent}-s{seed}", agent, seed, curve, es=es,
                                  q0=q0, eval_episodes=[episode(seed, scale + 0.1 * seed)]))
    return runs


@pytest.fixture
def copy_tree() -> Callable[[Path, Path], Path]:
    def copy(src: Path, dst: Path) -> Path:
        shutil.copytree(src, dst)
        return dst
    return copy
