"""Gait-cycle metrics from Python (esrl_rs.metrics.gait_phases, step_lengths, classify_gait,
joint_motion) on synthetic contact traces with hand-computed answers, and the same rules as the
Rust crate: a walk with 20 % double support is a walk with alternation 1, a synchronous hop a
hop, an alternating run with 30 % flight a run, standing a stand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from esrl_rs import metrics as m

DT = 0.01


def foot(n: int, period: int, stance: int, offset: int) -> np.ndarray:
    """Down for the first ``stance`` samples of every ``period``, shifted by ``offset``."""
    return (np.arange(n) + offset) % period < stance


def test_walk_with_20_percent_double_support() -> None:
    left, right = foot(500, 100, 60, 0), foot(500, 100, 60, 50)
    p = m.gait_phases(left, right, DT)
    assert p["double_support"] == pytest.approx(0.2)
    assert p["single_support"] == pytest.approx(0.8)
    assert p["flight"] == 0.0
    assert p["duty_factor"] == pytest.approx((0.6, 0.6))
    # Left down from reset: touchdowns at samples 100..400; right at 50..450.
    assert p["touchdowns"] == (4, 5)
    np.testing.assert_allclose(p["touchdown_times"][0], [1.01, 2.01, 3.01, 4.01])
    assert p["cadence"] == pytest.approx(9 / 5 * 60)
    assert p["alternation"] == 1.0
    assert p["synchronous"] == 0.0
    assert p["stride_time_mean"] == pytest.approx(1.0)
    assert m.classify_gait(p) == "walk"
    # 0/1 numbers work as well as booleans.
    assert m.gait_phases(left.astype(int), right.astype(float), DT)["touchdowns"] == (4, 5)


def test_hop_run_stand_and_fall() -> None:
    both = foot(300, 50, 30, 0)
    hop = m.gait_phases(both, both, DT)
    assert (hop["landings"], hop["synchronous"], hop["alternation"]) == (5, 1.0, 0.0)
    assert hop["flight"] == pytest.approx(0.4)
    assert m.classify_gait(hop) == "hop"

    run = m.gait_phases(foot(500, 100, 35, 0), foot(500, 100, 35, 50), DT)
    assert run["flight"] == pytest.approx(0.3)
    assert run["double_support"] == 0.0
    assert m.classify_gait(run) == "run"

    down = np.ones(400, dtype=bool)
    stand = m.gait_phases(down, down, DT)
    assert stand["step_count"] == 0 and stand["alternation"] is None
    assert m.classify_gait(stand) == "stand"
    assert m.classify_gait({**stand, "foot_speed": 0.05}) == "shuffle"
    assert m.classify_gait({**stand, "fell": True}) == "fall"
    # A walk that falls after 5 s is still a walk; advancing the feet 0.07 m/s at 1.8 steps/s
    # (4 cm a step) it is stepping in place.
    walk = m.gait_phases(foot(500, 100, 60, 0), foot(500, 100, 60, 50), DT)
    assert m.classify_gait({**walk, "fell": True}) == "walk"
    assert m.classify_gait({**walk, "foot_speed": 0.07}) == "shuffle"
    assert m.classify_gait({**walk, "foot_speed": 0.7}) == "walk"
    # Thresholds can be overridden by name: at 150 steps/min minimum, 108 is not stepping.
    assert m.classify_gait(walk, {"min_cadence": 150.0}) == "stand"
    assert set(m.GAIT_CLASSES) == {"walk", "run", "hop", "shuffle", "stand", "fall"}


def test_step_lengths_and_joint_motion() -> None:
    left, right = foot(500, 100, 60, 0), foot(500, 100, 60, 50)
    # Each foot lands 0.7 m ahead of the other's last footprint.
    x = np.zeros((500, 2))
    x[:, 0] = 1.4 * (np.arange(500) // 100)
    x[:, 1] = np.where(np.arange(500) < 50, -0.7, 0.7 + 1.4 * ((np.arange(500) - 50) // 100))
    steps = m.step_lengths(left, right, x, DT)
    np.testing.assert_allclose(steps, np.full(8, 0.7))

    q = np.linspace(0.0, 1.0, 101)
    j = m.joint_motion("knee", q, (0.0, 1.0), margin=0.015)
    assert j["p5"] == pytest.approx(0.05) and j["p95"] == pytest.approx(0.95)
    assert j["range"] == pytest.approx(0.9)
    # 0, 0.01 near the lower limit; 0.99, 1.0 near the upper one (within 0.015).
    assert j["at_limit"] == pytest.approx(4 / 101)
    assert m.joint_motion("knee", q)["at_limit"] is None
    assert m.percentile([4.0, 1.0, 3.0, 2.0], 0.05) == pytest.approx(1.15)
    assert m.GAIT_THRESHOLDS["limit_margin"] == pytest.approx(math.radians(1.0))
    assert m.GAIT_THRESHOLDS["contact_force"] == 10.0


def test_gait_metrics_of_a_trace_has_the_cycle() -> None:
    left, right = foot(200, 100, 60, 0), foot(200, 100, 60, 50)
    n = len(left)
    trace = {
        "actuator_names": ["left_knee", "right_knee"], "foot_names": ["l", "r"],
        "time": list((np.arange(n) + 1) * DT), "torso_x": [0.0] * n, "torso_y": [0.0] * n,
        "torso_z_error": [0.0] * n, "forward_velocity": [0.0] * n,
        "torques": [[0.0, 0.0]] * n, "powers": [[0.0, 0.0]] * n,
        "foot_forces": np.stack([left, right], axis=1) * 300.0, "fell": False,
        "success_time": None, "joint_angles": np.full((n, 2), 0.5),
        "joint_limits": [[0.0, 0.5], None],
    }
    g = m.gait_metrics(trace)
    assert g["cycle"]["double_support"] == pytest.approx(0.2)
    assert g["cycle"]["gait_class"] == "stand", "3 touchdowns: fewer than 4, not stepping"
    assert g["joints"][0]["at_upper"] == 1.0
    # A threshold above the 300 N load: never in contact.
    g = m.gait_metrics(trace, thresholds={"contact_force": 400.0})
    assert g["cycle"]["flight"] == 1.0


def test_bad_gait_inputs_raise_value_error() -> None:
    with pytest.raises(ValueError, match=r"left_contact\[0\] = 0.5"):
        m.gait_phases([0.5, 1.0], [1, 1], DT)
    with pytest.raises(ValueError, match="right contact: length 1, expected 2"):
        m.gait_phases([1, 1], [1], DT)
    with pytest.raises(ValueError, match="dt"):
        m.gait_phases([1, 1], [1, 1], 0.0)
    with pytest.raises(ValueError, match="min_flight"):
        m.classify_gait(m.gait_phases([1, 1], [1, 1], DT), {"min_flight": 2.0})
    with pytest.raises(ValueError, match="unknown field"):
        m.classify_gait(m.gait_phases([1, 1], [1, 1], DT), {"min_fligth": 0.1})
    with pytest.raises(ValueError, match=r"joint_limits\[knee\]"):
        m.joint_motion("knee", [0.0, 1.0], (1.0, 0.0))
