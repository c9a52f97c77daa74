"""`python -m esrl_rs.ray train` against `esrl train`: same rows and weights, whatever the
number of workers, with a worker killed mid-generation, and resumed across the two front ends.

Each test starts a local Ray cluster (`--address local`) in a subprocess, as a user would.
Ray is an optional dependency: without it these tests skip (CI installs it).
"""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path
from typing import Dict, List

import pytest

pytest.importorskip("ray", reason="Ray is optional: pip install 'esrl_rs[ray]'")

SMOKE = ("es-td3", "--preset", "smoke", "--seed", "3")


def ray_train(*args: str, env: Dict[str, str] = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "esrl_rs.ray", "train", *args]
    full_env = dict(os.environ, **(env or {}))
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=full_env)
    assert proc.returncode == 0, f"`{' '.join(cmd)}` failed:\n{proc.stderr[-3000:]}"
    return proc


def cli(esrl_bin: Path, *args: str) -> None:
    proc = subprocess.run([str(esrl_bin), *args], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]


def rows(run: Path) -> List[Dict[str, str]]:
    """metrics.csv without the wall-time column."""
    with open(run / "metrics.csv", newline="", encoding="utf-8") as f:
        table = list(csv.DictReader(f))
    assert table, f"{run}: no rows"
    for row in table:
        del row["wall_s"]
    return table


def assert_same_run(a: Path, b: Path) -> None:
    assert rows(a) == rows(b)
    # Weights byte for byte: the final actor and agent, the best policy, the replay buffer.
    files = sorted(p.relative_to(a) for p in a.rglob("*.safetensors"))
    assert Path("checkpoint/actor.safetensors") in files
    assert files == sorted(p.relative_to(b) for p in b.rglob("*.safetensors"))
    for f in files:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f"{f} differs"


@pytest.fixture(scope="module")
def reference(esrl_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Dict[int, Path]:
    """`esrl train es-td3 --preset smoke --seed 3` for 2 (the preset's) and 4 generations."""
    runs = {}
    for gens in (2, 4):
        out = tmp_path_factory.mktemp("ref") / f"g{gens}"
        cli(esrl_bin, "train", *SMOKE, "--generations", str(gens), "--out", str(out))
        runs[gens] = out
    return runs


def test_ray_equals_cli(reference: Dict[int, Path], tmp_path: Path) -> None:
    out = tmp_path / "ray"
    proc = ray_train(*SMOKE, "--address", "local", "--workers", "2", "--out", str(out))
    assert_same_run(reference[2], out)
    # The run folder holds what `esrl train` writes, and the traffic is reported.
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in reference[2].iterdir())
    assert "of genomes out" in proc.stderr


def test_killed_worker_changes_nothing(reference: Dict[int, Path], tmp_path: Path) -> None:
    out, marker = tmp_path / "ray", tmp_path / "killed"
    ray_train(*SMOKE, "--generations", "4", "--address", "local", "--workers", "2",
              "--out", str(out), env={"ESRL_RAY_KILL_ONCE": str(marker)})
    assert marker.is_file(), "no worker was killed"
    assert_same_run(reference[4], out)


def test_resume_cli_run_on_ray(esrl_bin: Path, reference: Dict[int, Path],
                               tmp_path: Path) -> None:
    out = tmp_path / "run"
    cli(esrl_bin, "train", *SMOKE, "--out", str(out))
    ray_train("es-td3", "--resume", str(out), "--generations", "4", "--address", "local",
              "--workers", "2")
    assert_same_run(reference[4], out)


def test_resume_ray_run_with_cli(esrl_bin: Path, reference: Dict[int, Path],
                                 tmp_path: Path) -> None:
    out = tmp_path / "run"
    ray_train(*SMOKE, "--address", "local", "--workers", "1", "--out", str(out))
    cli(esrl_bin, "train", "es-td3", "--resume", str(out), "--generations", "4")
    assert_same_run(reference[4], out)


def test_a_fine_tuning_run_on_ray_equals_the_cli_one(esrl_bin: Path, reference: Dict[int, Path],
                                                     tmp_path: Path) -> None:
    # Started from the weights of the 2-generation run (`--init`), on both front ends.
    ray_run, cli_run = tmp_path / "ray", tmp_path / "cli"
    init = str(reference[2])
    ray_train(*SMOKE, "--init", init, "--out", str(ray_run), "--workers", "2")
    cli(esrl_bin, "train", *SMOKE, "--init", init, "--out", str(cli_run))
    assert_same_run(ray_run, cli_run)
    assert (ray_run / "init.json").read_text() == (cli_run / "init.json").read_text()
    # Not the run of its seed from drawn weights.
    assert rows(cli_run) != rows(reference[2])


def test_resume_refuses_new_run_options(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "esrl_rs.ray", "train", "es-td3", "--resume", str(tmp_path),
           "--seed", "1"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "--seed" in proc.stderr


def test_sigint_stops_after_the_generation_with_a_checkpoint(tmp_path: Path) -> None:
    import json
    import signal
    import time

    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "esrl_rs.ray", "train", *SMOKE, "--generations", "2000",
           "--address", "local", "--workers", "1", "--out", str(out)]
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            csv_path = out / "metrics.csv"
            if csv_path.is_file() and len(csv_path.read_text().splitlines()) >= 4:
                break
            time.sleep(0.1)
        proc.send_signal(signal.SIGINT)
        _, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, stderr[-2000:]
    assert "stopped after" in stderr
    state = json.loads((out / "checkpoint" / "state.json").read_text())
    assert 3 <= state["rows"] < 2000
    assert state["rows"] == len(rows(out))


def test_an_existing_run_folder_is_an_error_not_a_traceback(tmp_path: Path) -> None:
    out = str(tmp_path / "run")
    ray_train(*SMOKE, "--out", out, "--address", "local", "--workers", "1")
    cmd = [sys.executable, "-m", "esrl_rs.ray", "train", *SMOKE, "--out", out]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "already holds a run" in proc.stderr and "--resume" in proc.stderr
    assert "Traceback" not in proc.stderr


STUDY = """
seeds = 2
[eval]
episodes = 2
[[arm]]
name = "essac"
agent = "es-sac"
preset = "smoke"
generations = 3
[[arm]]
name = "sac"
agent = "sac"
preset = "smoke"
episodes = 3
seeds = [1, 2, 3]
"""


def _records(folder: Path) -> Dict[str, str]:
    """Every record file but wall-clock times, by path."""
    out = {}
    for p in sorted((folder / "records").rglob("*")):
        if not p.is_file():
            continue
        key = str(p.relative_to(folder))
        if p.suffix == ".safetensors":
            out[key] = p.read_bytes().hex()
        elif p.name == "metrics.csv":
            out[key] = "\n".join(l.rsplit(",", 1)[0] for l in p.read_text().splitlines())
        elif p.name == "summary.json":
            import json
            s = json.loads(p.read_text())
            s.pop("wall_s")
            out[key] = json.dumps(s, sort_keys=True)
        else:
            out[key] = p.read_text()
    return out


def test_a_study_on_ray_gives_the_records_of_esrl_study_run(esrl_bin: Path,
                                                           tmp_path: Path) -> None:
    study = tmp_path / "smoke.toml"
    study.write_text(STUDY)
    local, on_ray = tmp_path / "local", tmp_path / "ray"
    proc = subprocess.run([str(esrl_bin), "study", "run", str(study), "--out", str(local),
                           "--jobs", "1", "--threads", "1"], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    cmd = [sys.executable, "-m", "esrl_rs.ray", "study", str(study), "--out", str(on_ray),
           "--esrl", str(esrl_bin), "--address", "local", "--workers", "2"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    a, b = _records(local), _records(on_ray)
    # 5 runs (2 seeds of the ES arm, the plain arm's own 3): config, eval, metrics, summary
    # and the policy's actor and config, plus the ES runs' best.json.
    assert len(a) == 5 * 6 + 2, sorted(a)
    assert a == b
