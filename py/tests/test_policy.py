"""Trained policies from CLI runs: loading, deterministic acting, rollouts that agree with a
Python loop over the Gymnasium env and with `esrl eval`'s eval.json."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import esrl_rs

PENDULUM = ("--env", "pendulum", "--preset", "smoke", "--episodes", "60", "--seed", "3")
WALK = ("--preset", "smoke", "--seed", "2")


def test_policy_rollout_matches_a_python_loop(cli_train: Callable[..., Path]) -> None:
    policy = esrl_rs.load_policy(cli_train("sac", *PENDULUM))
    assert policy.agent == "sac" and policy.env == "pendulum"
    assert policy.obs_dim == 3 and policy.act_dim == 1
    env = policy.make_env()
    for seed in (0, 5):
        r = policy.rollout(seed)
        obs, _ = env.reset(seed=seed)
        policy.reset()
        q0 = policy.q0(obs)
        ret, length, done = 0.0, 0, False
        while not done:
            a = policy.act(obs)
            assert a.dtype == np.float32 and np.all(np.abs(a) <= 1.0)
            obs, reward, terminated, truncated, _ = env.step(a)
            ret += reward
            length += 1
            done = terminated or truncated
        assert r["return"] == ret and r["length"] == length == 200
        assert r["q0"] == q0 and r["truncated"] and not r["terminated"]
    # deterministic
    assert policy.rollout(0) == policy.rollout(0)


def test_policy_matches_esrl_eval(cli_train: Callable[..., Path],
                                  cli_eval: Callable[..., dict], tmp_path: Path) -> None:
    import shutil
    for args, last in ((PENDULUM, False), (WALK, False), (WALK, True)):
        run = shutil.copytree(cli_train("sac" if args is PENDULUM else "es-sac", *args),
                              tmp_path / f"run-{len(args)}-{last}")
        ev = cli_eval(run, 2, last)
        mine = esrl_rs.load_policy(run, last=last).evaluate(episodes=2, seed=0)
        written = run / "best" if args is WALK and not last else run
        loaded = esrl_rs.load_eval(written)
        assert mine["agent"] == ev["agent"] and mine["seed"] == ev["seed"] == 0
        assert mine["mean"]["return"] == ev["mean"]["return"]
        for theirs, ours, typed in zip(ev["episodes"], mine["episodes"], loaded["episodes"]):
            assert ours["seed"] == theirs["seed"]
            assert ours["return"] == theirs["return"]
            assert ours["length"] == theirs["length"]
            assert ours["q0"] == pytest.approx(theirs["q0"], rel=1e-12)
            if theirs.get("trace"):
                np.testing.assert_array_equal(ours["trace"]["x"], theirs["trace"]["x"])
                np.testing.assert_array_equal(ours["trace"]["y"], typed["trace"]["y"])
                np.testing.assert_allclose(ours["gait"]["mean_abs_power"],
                                           theirs["gait"]["mean_abs_power"], rtol=1e-12)


def test_policy_folder_with_the_actor_alone(cli_train: Callable[..., Path],
                                           tmp_path: Path) -> None:
    """A study record's `policy/` (actor.safetensors and config.toml, no critics) loads and
    acts as the checkpoint it came from; it has no Q0 to give."""
    import shutil
    full = esrl_rs.load_policy(cli_train("es-sac", *WALK))
    folder = tmp_path / "policy"
    folder.mkdir()
    for name in ("actor.safetensors", "config.toml"):
        shutil.copy(Path(full.checkpoint) / name, folder / name)
    alone = esrl_rs.load_policy(folder)
    assert Path(alone.checkpoint) == folder
    env = full.make_env()
    obs, _ = env.reset(seed=1)
    full.reset()
    alone.reset()
    for _ in range(20):
        action = full.act(obs)
        np.testing.assert_array_equal(alone.act(obs), action)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    with pytest.raises(ValueError, match="actor alone"):
        alone.q0(obs)
    assert full.q0(obs) == full.q0(obs)
    ours, theirs = alone.rollout(3), full.rollout(3)
    assert ours["return"] == theirs["return"] and ours["length"] == theirs["length"]
    assert ours["q0"] is None and theirs["q0"] is not None


def test_a_run_folder_means_its_kept_policy(cli_train: Callable[..., Path]) -> None:
    """Given a run folder, `load_policy` takes the policy the run hands over, `RUN/best/`,
    as `esrl eval RUN` does; `last=True` its newest checkpoint, as `esrl eval --last`."""
    run = cli_train("es-sac", *WALK)
    kept, last = esrl_rs.load_policy(run), esrl_rs.load_policy(run, last=True)
    assert Path(kept.checkpoint) == run / "best"
    assert Path(last.checkpoint).name == "checkpoint"
    ours, best = kept.rollout(1), esrl_rs.load_policy(run / "best").rollout(1)
    assert ours["return"] == best["return"] and ours["length"] == best["length"]
    np.testing.assert_array_equal(ours["trace"]["x"], best["trace"]["x"])


def test_walk_policy(cli_train: Callable[..., Path]) -> None:
    policy = esrl_rs.load_policy(cli_train("es-sac", *WALK) / "checkpoint")
    assert policy.agent == "es-sac" and policy.env == "walk"
    assert (policy.obs_dim, policy.act_dim) == (43, 6)
    r = policy.rollout(1)
    n = r["length"]
    assert r["trace"]["x"].shape == (n,) and r["gait"]["steps"] == n
    assert r["gait"]["actuator_names"][1] == "left_knee"
    env = policy.make_env()
    assert env.max_episode_steps == n or r["terminated"]
    assert env.config == policy._core.walk_config


def test_policy_evaluation_records_mcap(cli_train: Callable[..., Path], tmp_path: Path) -> None:
    policy = esrl_rs.load_policy(cli_train("es-sac", *WALK))
    ev = policy.evaluate(episodes=1, seed=4, record=tmp_path / "rec")
    mcap = tmp_path / "rec" / "episode-000.mcap"
    assert mcap.is_file()
    n = ev["episodes"][0]["length"]
    torque = esrl_rs.read_recording(mcap, "/esrl/joints/torque")
    assert torque["time"].shape == (n,)
    assert "left_knee" in torque and torque["left_knee"].shape == (n,)
    np.testing.assert_allclose(torque["time"], ev["episodes"][0]["trace"]["time"], atol=1e-6)
    topics = {c["topic"] for c in esrl_rs.recording_channels(mcap)}
    assert {"/scene", "/tf", "/esrl/reward"} <= topics
    with pytest.raises(ValueError, match="episodes=0"):
        policy.evaluate(episodes=0)


def test_policy_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="no such run or checkpoint folder"):
        esrl_rs.load_policy(tmp_path / "none")
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "config.toml").write_text('agent = "sac"\n')
    with pytest.raises(FileNotFoundError, match="no complete checkpoint"):
        esrl_rs.load_policy(tmp_path / "run")
    with pytest.raises(ValueError, match="neither a run folder"):
        esrl_rs.load_policy(tmp_path)
    a_file = tmp_path / "file"
    a_file.write_text("x")
    with pytest.raises(ValueError, match="is a file"):
        esrl_rs.load_policy(a_file)


def test_policy_bad_config_and_obs(cli_train: Callable[..., Path], tmp_path: Path) -> None:
    import shutil
    run = shutil.copytree(cli_train("sac", *PENDULUM), tmp_path / "run")
    policy = esrl_rs.load_policy(run)
    with pytest.raises(ValueError, match="obs: length 2, expected 3"):
        policy.act([0.0, 1.0])
    text = (run / "config.toml").read_text()
    (run / "config.toml").write_text(text.replace('agent = "sac"', 'agent = "nope"'))
    with pytest.raises(ValueError, match="config.toml"):
        esrl_rs.load_policy(run)


def test_policy_shared_by_threads(cli_train: Callable[..., Path]) -> None:
    from concurrent.futures import ThreadPoolExecutor

    policy = esrl_rs.load_policy(cli_train("sac", *PENDULUM))
    expected = policy.rollout(0)
    obs = np.zeros(3, dtype=np.float32)
    with ThreadPoolExecutor(4) as pool:
        jobs = [pool.submit(policy.rollout, 0) for _ in range(3)]
        jobs += [pool.submit(policy.act, obs) for _ in range(20)]
        done = [j.result(timeout=120) for j in jobs]
    assert all(d == expected for d in done[:3])
