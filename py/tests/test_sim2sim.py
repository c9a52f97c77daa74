"""Sim-to-sim: the walking task rebuilt on MuJoCo (esrl_rs.sim2sim) against esrl's own.

A zero action stands 10 s in both engines; from the same initial state the observations are
the same (but the foot forces: contact models differ), so is the actor's action to within
what those forces move it, and after one control step the pose agrees to millimetres; the
cross-check runs a committed policy in both. MuJoCo is optional: without it these tests skip
(CI installs it).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="MuJoCo is optional: pip install 'esrl_rs[mujoco]'")

import esrl_rs  # noqa: E402
from esrl_rs.sim2sim import (MujocoWalk, _past_limit_deg, cross_check, cross_checks,  # noqa: E402
                             main)

FLAGSHIP = Path(__file__).resolve().parents[2] / "results" / "walking" / "flagship"


@pytest.fixture(scope="module")
def engines():
    policy = esrl_rs.load_policy(FLAGSHIP)
    walk = policy._core.walk_config
    return policy, esrl_rs.WalkEnv(walk), MujocoWalk(walk)


def test_zero_action_stands_ten_seconds_in_both_engines(engines) -> None:
    _, rust, mj = engines
    for seed in (0, 1):
        rust.reset(seed=seed)
        mj.reset(seed)
        for _ in range(400):
            _, _, fell, _, info = rust.step(np.zeros(6, dtype=np.float32))
            _, mj_fell, _, s = mj.step(np.zeros(6))
            assert not fell and not mj_fell
        assert abs(info["gait"]["height_error"]) < 0.01 and abs(s["torso_z_error"]) < 0.01


def test_the_same_start_observes_and_acts_alike(engines) -> None:
    policy, rust, mj = engines
    names = rust.obs_names
    force = np.array([n.startswith("foot_force") for n in names])
    for seed in range(4):
        o_rust, _ = rust.reset(seed=seed)
        o_mj = mj.reset(seed)
        np.testing.assert_allclose(o_mj[~force], o_rust[~force], atol=1e-5)
        policy.reset()
        a_rust = policy.act(o_rust)
        policy.reset()
        a_mj = policy.act(o_mj)
        assert np.abs(a_rust - a_mj).max() < 0.1, f"seed {seed}"
        o_rust, *_ = rust.step(np.zeros(6, dtype=np.float32))
        o_mj, *_ = mj.step(np.zeros(6))
        pose = np.array([n.split("/")[0] in ("height_error", "lateral_offset", "orientation",
                                             "joint_angle", "passive_angle", "clock")
                         for n in names])
        # After 25 ms: the torso within a millimetre (height and lateral offset are scaled
        # ×10), the joints within 0.3°.
        np.testing.assert_allclose(o_mj[pose], o_rust[pose], atol=1e-2)


def test_the_cross_check_runs_a_policy_in_both(capsys) -> None:
    r = cross_check(str(FLAGSHIP), episodes=2, seed=0)
    for engine in ("esrl", "mujoco"):
        assert r[engine]["episodes"] == 2
        assert sum(r[engine]["classes"].values()) == 2
    assert r["esrl"]["finished"] == 2, "the flagship finishes in esrl"
    # Both engines log the torso's lean: the flagship walks leaning back a few degrees.
    for engine in ("esrl", "mujoco"):
        assert -20.0 < r[engine]["torso_pitch_deg"] < 0.0, r[engine]["torso_pitch_deg"]
    assert main([str(FLAGSHIP), "--episodes", "1"]) == 0
    assert "| MuJoCo |" in capsys.readouterr().out


@pytest.mark.parametrize("cone,servo", [("elliptic", "explicit"), ("pyramidal", "actuator"),
                                        ("elliptic", "actuator")])
def test_every_mujoco_setting_stands_and_steps_alike(engines, cone, servo) -> None:
    """The other settings: a zero action stands 10 s, and one control step from the same
    state agrees with esrl as the default setting does."""
    _, rust, _ = engines
    policy = esrl_rs.load_policy(FLAGSHIP)
    mj = MujocoWalk(policy._core.walk_config, cone=cone, servo=servo)
    assert mj.servo == servo
    mj.reset(0)
    for _ in range(400):
        _, mj_fell, _, s = mj.step(np.zeros(6))
        assert not mj_fell
    assert abs(s["torso_z_error"]) < 0.01
    # The actuators deliver the servo law's torque (within the step's change of state).
    if servo == "actuator":
        q = np.array([mj.d.qpos[i] for i in mj.act_q])
        qd = np.array([mj.d.qvel[i] for i in mj.act_v])
        kp, kd = float(mj.target["stiffness"]), float(mj.target["damping"])
        law = np.clip(kp * (mj.q_stand - q) - kd * qd, -mj.effort, mj.effort)
        np.testing.assert_allclose(s["torques"], law, atol=0.05 * mj.effort.max())
    names = rust.obs_names
    pose = np.array([n.split("/")[0] in ("height_error", "lateral_offset", "orientation",
                                         "joint_angle", "passive_angle", "clock")
                     for n in names])
    for seed in range(2):
        rust.reset(seed=seed)
        mj.reset(seed)
        o_rust, *_ = rust.step(np.zeros(6, dtype=np.float32))
        o_mj, *_ = mj.step(np.zeros(6))
        np.testing.assert_allclose(o_mj[pose], o_rust[pose], atol=1e-2)


def test_unknown_settings_are_refused() -> None:
    walk = esrl_rs.load_policy(FLAGSHIP)._core.walk_config
    with pytest.raises(ValueError, match="cone 'round'"):
        MujocoWalk(walk, cone="round")
    with pytest.raises(ValueError, match="servo 'pid'"):
        MujocoWalk(walk, servo="pid")
    with pytest.raises(ValueError, match="limits 'hard'"):
        MujocoWalk(walk, limits="hard")
    with pytest.raises(SystemExit):
        main([str(FLAGSHIP), "--cone", "round"])


def test_several_policies_under_every_setting(capsys) -> None:
    """`--cone all --servo all` with two policies: one table each, esrl's row once, then
    MuJoCo under the four settings; the JSON is a list of the four results per policy."""
    record = FLAGSHIP.parents[1] / "seeds" / "records" / "default-s2" / "policy"
    assert main([str(FLAGSHIP), str(record), "--episodes", "1", "--cone", "all",
                 "--servo", "all"]) == 0
    out = capsys.readouterr().out
    assert out.count("| esrl (Rapier) |") == 2
    for cone in ("pyramidal", "elliptic"):
        for servo in ("explicit", "actuator"):
            assert out.count(f"| MuJoCo, {cone} cone, {servo} servo |") == 2
    assert main([str(FLAGSHIP), "--episodes", "1", "--cone", "all", "--json"]) == 0
    results = json.loads(capsys.readouterr().out)
    assert [r["mujoco_settings"] for r in results] == [
        {"cone": "pyramidal", "servo": "explicit", "action": "target", "limits": "soft"},
        {"cone": "elliptic", "servo": "explicit", "action": "target", "limits": "soft"}]
    assert results[0]["esrl"] == results[1]["esrl"], "esrl's episodes are run once"


def test_a_torque_policy_runs_once_per_cone(capsys) -> None:
    """A torque policy has no servo: `--servo all` runs it once per cone (not once per cone
    and servo), in rows that say torques, not a servo."""
    torque = FLAGSHIP.parents[1] / "torque" / "records" / "torque-s0" / "policy"
    assert main([str(torque), "--episodes", "1", "--cone", "all", "--servo", "all"]) == 0
    out = capsys.readouterr().out
    for cone in ("pyramidal", "elliptic"):
        assert out.count(f"| MuJoCo, {cone} cone, torques |") == 1
    assert "servo |" not in out


def test_stiff_limits_hold_the_joints_near_the_urdfs_limits(capsys) -> None:
    """Full torque driving both ankles into their −20° stops for 0.5 s: MuJoCo's default limit
    lets them bend far past; the stiff one keeps them within 4° of the URDF's limit. `--limits
    all` runs both, the stiff rows named."""
    torque = FLAGSHIP.parents[1] / "torque" / "records" / "torque-s0" / "policy"
    walk = esrl_rs.load_policy(torque)._core.walk_config
    past = {}
    for limits in ("soft", "stiff"):
        mj = MujocoWalk(walk, limits=limits)
        ankles = [k for k, n in enumerate(mj.rust.action_names) if n.endswith("ankle")]
        action = np.zeros(6)
        action[ankles] = -1.0
        mj.reset(0)
        worst = 0.0
        for _ in range(20):
            _, _, _, s = mj.step(action)
            q = np.asarray(s["joint_angles"])[ankles]
            worst = max(worst, float(np.degrees(mj.lo[ankles] - q).max()))
        past[limits] = worst
    assert past["stiff"] < 4.0, past
    assert past["soft"] > 3 * past["stiff"], past
    assert main([str(torque), "--episodes", "1", "--cone", "elliptic", "--limits", "all"]) == 0
    out = capsys.readouterr().out
    assert out.count("| MuJoCo, elliptic cone, torques |") == 1
    assert out.count("| MuJoCo, elliptic cone, torques, stiff limits |") == 1
    assert "| past a limit (°) |" in out
    soft, stiff = cross_checks(str(torque), 1, 1000, [("elliptic", "explicit", "soft"),
                                                      ("elliptic", "explicit", "stiff")])
    assert [r["mujoco_settings"]["limits"] for r in (soft, stiff)] == ["soft", "stiff"]
    # Rapier's limit, and MuJoCo's stiff one, hold this walk's joints within a few degrees.
    assert 0.0 <= soft["esrl"]["past_limit_deg"] < 3.0, soft["esrl"]
    assert stiff["mujoco"]["past_limit_deg"] < 5.0, stiff["mujoco"]


def test_past_limit_by_hand() -> None:
    """Degrees past the nearest bound, the largest over steps and limited joints; 0 inside."""
    angles = [[0.0, 0.5, 3.0], [-0.2, 0.1, -3.0]]
    limits = [[-0.1, 0.1], [0.0, 0.4], None]
    assert _past_limit_deg(angles, limits) == pytest.approx(np.degrees(0.1))
    assert _past_limit_deg([[0.05, 0.2, 9.0]], limits) == 0.0


def test_targets_follow_the_joint_ranges() -> None:
    """`target.joint_range` widens one joint's span on MuJoCo as in esrl: q_stand + a·span,
    clamped to the limits; the other joints keep `target.range`."""
    walk = dict(esrl_rs.load_policy(FLAGSHIP)._core.walk_config)
    walk["target"] = {**walk["target"], "joint_range": {"left_knee": 0.6}}
    mj = MujocoWalk(walk)
    names = list(mj.rust.action_names)
    left, right = names.index("left_knee"), names.index("right_knee")
    for a in (1.0, 0.5, -1.0):
        t = mj._targets(np.full(len(names), a))
        assert t[left] == pytest.approx(np.clip(mj.q_stand[left] + 0.6 * a, mj.lo[left],
                                                mj.hi[left]))
        assert t[right] == pytest.approx(np.clip(
            mj.q_stand[right] + float(walk["target"]["range"]) * a, mj.lo[right], mj.hi[right]))


def test_a_policy_trained_under_disturbances_is_checked_on_the_plain_task() -> None:
    """A policy trained with `[walk.perturb]` runs in both engines without it: esrl's side
    is `esrl eval --undisturbed`'s (Policy.load(undisturbed=True)), not its own task's."""
    randomized = FLAGSHIP.parents[1] / "torque-randomized" / "records" / "randomized-s4" / "policy"
    r = cross_check(str(randomized), episodes=1, seed=1000)
    plain = esrl_rs.load_policy(randomized, undisturbed=True)
    assert not plain._core.walk_config.get("perturb")
    assert esrl_rs.load_policy(randomized)._core.walk_config.get("perturb")
    g = plain.evaluate(1, 1000)["episodes"][0]["gait"]
    assert r["esrl"]["speed"] == pytest.approx(g["mean_forward_velocity"])
    own = esrl_rs.load_policy(randomized).evaluate(1, 1000)["episodes"][0]["gait"]
    assert own["mean_forward_velocity"] != pytest.approx(g["mean_forward_velocity"])


def test_a_policy_trained_from_wider_starts_is_checked_from_the_standard_ones(capsys) -> None:
    """`--default-starts`: both engines start where `esrl eval --default-starts` does. The
    policy trained from wider starts (`results/unseen-starts/noise5.toml`); its committed
    `eval20.json` was written by `esrl eval RUN --default-starts --episodes 20 --seed 1000`."""
    wide = FLAGSHIP.parents[1] / "unseen-starts" / "noise5-s0"
    policy = wide / "policy"
    standard = esrl_rs.load_policy(policy, default_starts=True)
    assert standard._core.walk_config["init_noise"] != \
        esrl_rs.load_policy(policy)._core.walk_config["init_noise"]
    committed = json.loads((wide / "eval20.json").read_text(encoding="utf-8"))
    assert committed["default_starts"] is True
    mine = standard.evaluate(1, 1000)["episodes"][0]
    assert mine["return"] == pytest.approx(committed["episodes"][0]["return"], rel=1e-12)
    assert main([str(policy), "--episodes", "1", "--seed", "1000", "--default-starts",
                 "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["default_starts"] is True
    assert r["esrl"]["speed"] == pytest.approx(mine["gait"]["mean_forward_velocity"])
    own = cross_check(str(policy), episodes=1, seed=1000)
    assert own["default_starts"] is False
    assert own["esrl"]["speed"] != pytest.approx(r["esrl"]["speed"])


def test_a_run_folder_is_checked_on_its_kept_policy(cli_train, capsys) -> None:
    """Given a run folder, sim2sim runs the policy `esrl eval RUN` takes (`RUN/best/`);
    `--last` its newest checkpoint; the JSON names the folder the weights came from."""
    run = cli_train("es-sac", "--preset", "smoke", "--seed", "2")
    for extra, folder in (([], run / "best"), (["--last"], run / "checkpoint")):
        capsys.readouterr()
        assert main([str(run), "--episodes", "1", "--json", *extra]) == 0
        result = json.loads(capsys.readouterr().out)
        assert Path(result["checkpoint"]) == folder, extra
