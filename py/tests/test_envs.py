"""The Gymnasium environments: check_env, determinism, reward terms, the pendulum's
dynamics against Gymnasium's formulas, and errors."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import esrl_rs


def _check(env: gym.Env) -> None:
    with warnings.catch_warnings():
        # -inf/inf observation bounds (as Gymnasium's own MuJoCo humanoid)
        warnings.simplefilter("ignore", UserWarning)
        check_env(env, skip_render_check=True)


def test_check_env_pendulum() -> None:
    _check(esrl_rs.Pendulum())
    _check(gym.make("esrl/Pendulum-v0").unwrapped)


def test_check_env_walk() -> None:
    _check(esrl_rs.WalkEnv())
    _check(gym.make("esrl/Walk-v0", config={"episode_seconds": 2.0}).unwrapped)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        check_env(esrl_rs.WalkEnv({"episode_seconds": 2.0}, render_mode="rgb_array"))


def test_spaces() -> None:
    walk = esrl_rs.WalkEnv()
    assert walk.observation_space.shape == (43,)
    assert walk.observation_space.dtype == np.float32
    assert walk.action_space.shape == (6,) and walk.action_space.dtype == np.float32
    np.testing.assert_array_equal(walk.action_space.low, -1.0)
    np.testing.assert_array_equal(walk.action_space.high, 1.0)
    assert len(walk.obs_names) == 43 and walk.obs_names[0] == "height_error"
    assert walk.action_names == ["left_hip", "left_knee", "left_ankle",
                                 "right_hip", "right_knee", "right_ankle"]
    assert walk.max_episode_steps == 2400
    assert walk.control_period == pytest.approx(0.025)
    assert walk.config["track_length"] == 50.0
    pend = esrl_rs.Pendulum()
    assert pend.observation_space.shape == (3,) and pend.action_space.shape == (1,)
    np.testing.assert_array_equal(pend.observation_space.high, [1.0, 1.0, 8.0])
    assert pend.max_episode_steps == 200


def _rollout(env: gym.Env, seed: int, steps: int) -> list:
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(0)
    out = [obs]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(
            rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        out.append((obs, reward, terminated, truncated))
        if terminated or truncated:
            break
    return out


@pytest.mark.parametrize("make", [esrl_rs.WalkEnv, esrl_rs.Pendulum])
def test_deterministic_for_a_seed(make: type) -> None:
    a = _rollout(make(), 5, 30)
    b = _rollout(make(), 5, 30)
    np.testing.assert_array_equal(a[0], b[0])
    for x, y in zip(a[1:], b[1:]):
        np.testing.assert_array_equal(x[0], y[0])
        assert x[1:] == y[1:]
    c = _rollout(make(), 6, 1)
    assert not np.array_equal(a[0], c[0])
    # reset() without a seed draws from np_random, so it follows the last seeded reset
    env = make()
    env.reset(seed=9)
    o1, i1 = env.reset()
    env.reset(seed=9)
    o2, i2 = env.reset()
    np.testing.assert_array_equal(o1, o2)
    assert i1["seed"] == i2["seed"]


def test_walk_reward_terms_and_gait() -> None:
    # raw observations, so index 1 is the lateral offset in metres (unscaled)
    env = esrl_rs.WalkEnv({"normalize_obs": False})
    env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(np.zeros(6, dtype=np.float32))
    terms = info["reward_terms"]
    assert set(terms) == {"forward", "lateral", "height", "power", "alive"}
    assert sum(terms.values()) == pytest.approx(reward, abs=1e-5)
    assert terms["alive"] == pytest.approx(0.025)
    g = info["gait"]
    assert g["joint_torque"].shape == (6,) and g["torso_position"].shape == (3,)
    # zero action: zero torque; the logged lateral offset is raw observation index 1
    np.testing.assert_allclose(g["joint_torque"], 0.0, atol=1e-6)
    assert g["lateral_offset"] == pytest.approx(float(obs[1]), abs=1e-6)
    assert g["time"] == pytest.approx(0.025)


def test_walk_falls_without_control() -> None:
    env = esrl_rs.WalkEnv()
    env.reset(seed=0)
    steps = 0
    terminated = truncated = False
    while not (terminated or truncated) and steps < env.max_episode_steps:
        _, _, terminated, truncated, info = env.step(-np.ones(6, dtype=np.float32))
        steps += 1
    assert terminated and info["gait"]["fell"], f"no fall after {steps} steps at full torque"


def test_pendulum_matches_gymnasium_formulas() -> None:
    env = esrl_rs.Pendulum()
    obs, _ = env.reset(seed=3)
    for a in (0.5, -1.0, 0.25, 1.0):
        theta = math.atan2(float(obs[1]), float(obs[0]))
        thdot = float(obs[2])
        u = 2.0 * a
        new_thdot = min(8.0, max(-8.0, thdot + (15.0 * math.sin(theta) + 3.0 * u) * 0.05))
        new_theta = theta + new_thdot * 0.05
        norm = ((theta + math.pi) % (2 * math.pi)) - math.pi
        expected_r = -(norm**2 + 0.1 * thdot**2 + 0.001 * u**2)
        obs, r, terminated, truncated, info = env.step(np.array([a], dtype=np.float32))
        assert r == pytest.approx(expected_r, abs=1e-4)
        np.testing.assert_allclose(obs, [math.cos(new_theta), math.sin(new_theta), new_thdot],
                                   atol=1e-4)
        assert not terminated and not truncated
        assert sum(info["reward_terms"].values()) == pytest.approx(r, abs=1e-5)
    # truncation after 200 steps
    env.reset(seed=0)
    for k in range(200):
        _, _, terminated, truncated, _ = env.step(np.zeros(1, dtype=np.float32))
        assert truncated == (k == 199) and not terminated


def test_env_errors() -> None:
    env = esrl_rs.Pendulum()
    with pytest.raises(esrl_rs.EsrlError, match="call reset"):
        env.step(np.zeros(1, dtype=np.float32))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action: length 2, expected 1"):
        env.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=-1)
    # NaN actions are treated as 0 by the core, never a crash
    obs, *_ = env.step(np.array([np.nan], dtype=np.float32))
    assert np.isfinite(obs).all()
    with pytest.raises(ValueError, match="control_period"):
        esrl_rs.WalkEnv({"control_period": -1.0})
    with pytest.raises(ValueError, match="unknown field `bogus`"):
        esrl_rs.WalkEnv({"bogus": 1})
    with pytest.raises(ValueError, match="no joint `elbow`"):
        esrl_rs.WalkEnv({"actuated_joints": ["elbow"]})
    with pytest.raises(FileNotFoundError, match="missing.urdf"):
        esrl_rs.WalkEnv({"urdf": "/nonexistent/missing.urdf"})
    with pytest.raises(ValueError, match="render_mode"):
        esrl_rs.Pendulum(render_mode="human")
    with pytest.raises(ValueError, match="render_mode"):
        esrl_rs.WalkEnv(render_mode="human")


def test_step_after_the_episode_ended_raises() -> None:
    env = esrl_rs.Pendulum()
    env.reset(seed=0)
    for _ in range(200):
        *_, truncated, _ = env.step(np.zeros(1, dtype=np.float32))
    assert truncated
    with pytest.raises(esrl_rs.EsrlError, match="episode ended"):
        env.step(np.zeros(1, dtype=np.float32))
    env.reset(seed=1)
    env.step(np.zeros(1, dtype=np.float32))  # a reset starts the next episode
    walk = esrl_rs.WalkEnv({"episode_seconds": 5.0})
    walk.reset(seed=0)
    terminated = False
    while not terminated:
        _, _, terminated, truncated, _ = walk.step(-np.ones(6, dtype=np.float32))
        assert not truncated
    with pytest.raises(esrl_rs.EsrlError, match="episode ended"):
        walk.step(np.zeros(6, dtype=np.float32))


def test_a_deeply_nested_urdf_is_an_error_not_a_crash(tmp_path) -> None:
    deep = tmp_path / "deep.urdf"
    deep.write_text('<robot name="r">' + "<link>" * 20000 + "</link>" * 20000 + "</robot>")
    with pytest.raises(ValueError, match="nested 20001 deep"):
        esrl_rs.WalkEnv({"urdf": str(deep)})


def test_walk_renders_the_side_view() -> None:
    env = esrl_rs.WalkEnv({"episode_seconds": 3.0}, render_mode="rgb_array")
    assert env.metadata["render_modes"] == ["rgb_array"] and env.metadata["render_fps"] == 40
    env.reset(seed=0)
    first = env.render()
    assert first.shape == (360, 480, 3) and first.dtype == np.uint8
    coloured = (first != 255).any(axis=2)
    assert 500 < coloured.sum() < 0.5 * coloured.size, "a robot and a ground line on white"
    terminated = False
    while not terminated:
        *_, terminated, truncated, _ = env.step(-np.ones(6, dtype=np.float32))
        if truncated:
            break
    fallen = env.render()
    assert (fallen != first).any(), "the picture follows the robot"
    # The robot's pixels sit lower once it has fallen.
    rows = lambda img: np.nonzero((img != 255).any(axis=2) & ~(img == 120).all(axis=2))[0]
    assert rows(fallen).min() > rows(first).min()
    assert esrl_rs.WalkEnv().render() is None, "no render_mode: nothing"


def test_record_video_films_the_walk(tmp_path) -> None:
    pytest.importorskip("moviepy")
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(gym.make("esrl/Walk-v0", config={"episode_seconds": 1.0},
                               render_mode="rgb_array"),
                      video_folder=str(tmp_path), episode_trigger=lambda e: True,
                      disable_logger=True)
    env.reset(seed=0)
    done = False
    while not done:
        *_, terminated, truncated, _ = env.step(np.zeros(6, dtype=np.float32))
        done = terminated or truncated
    env.close()
    videos = list(tmp_path.glob("*.mp4"))
    assert videos and videos[0].stat().st_size > 1000


def test_threads_give_the_sequential_results() -> None:
    from concurrent.futures import ThreadPoolExecutor

    def run(seed: int) -> list:
        return _rollout(esrl_rs.WalkEnv(), seed, 40)

    sequential = [run(s) for s in (1, 2, 3)]
    with ThreadPoolExecutor(3) as pool:
        parallel = list(pool.map(run, (1, 2, 3)))
    for a, b in zip(sequential, parallel):
        np.testing.assert_array_equal(a[-1][0], b[-1][0])
    # one environment shared by threads: steps are serialised, never a deadlock or a crash
    # (joint-angle targets: a zero action holds the standing pose, so no step ends it)
    env = esrl_rs.WalkEnv({"action": "target"})
    env.reset(seed=0)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda _: env.step(np.zeros(6, dtype=np.float32)), range(40)))
    assert len(results) == 40


def test_make_right_after_import() -> None:
    # A fresh interpreter: nothing but `import esrl_rs` before gym.make.
    import subprocess
    import sys

    code = (
        "import gymnasium as gym, esrl_rs\n"
        "env = gym.make('esrl/Walk-v0', config={'episode_seconds': 1.0})\n"
        "obs, _ = env.reset(seed=0)\n"
        "print(obs.shape)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "(43,)"
