"""esrl_rs.metrics against hand-computed values; errors arrive as ValueError."""

from __future__ import annotations

import math

import numpy as np
import pytest

import esrl_rs
from esrl_rs import metrics as m


def test_curve_metrics_by_hand() -> None:
    c = np.array([1.0, 2.0, 3.0, 4.0])
    assert m.auc(c) == 10.0
    assert m.nauc(c) == 2.5
    # shorter than 50: all values
    assert m.final_50(c) == 2.5
    assert m.best_win_50(c) == 2.5
    assert m.final_mean(c, 2) == 3.5
    assert m.best_window_mean([5.0, 1.0, 1.0, 4.0], 2) == 3.0
    # lists and integer arrays are accepted
    assert m.auc([1, 2, 3]) == 6.0
    assert m.auc(np.arange(4, dtype=np.int32)) == 6.0


def test_windows_of_50() -> None:
    c = np.arange(100, dtype=float)  # last 50: 50..99, mean 74.5; best window is the last
    assert m.final_50(c) == 74.5
    assert m.best_win_50(c) == 74.5
    peak = np.concatenate([np.zeros(10), np.full(50, 7.0), np.zeros(40)])
    assert m.best_win_50(peak) == 7.0
    assert m.final_50(peak) == pytest.approx(7.0 * 10 / 50)


def test_trailing_means_and_episodes_to_target() -> None:
    np.testing.assert_allclose(m.trailing_means([0.0, 10.0, 10.0]), [0.0, 5.0, 20.0 / 3.0])
    np.testing.assert_allclose(m.trailing_means([1.0, 3.0, 5.0, 7.0], window=2),
                               [1.0, 2.0, 4.0, 6.0])
    assert m.episodes_to_target([0.0, 10.0, 10.0], 5.0) == 1
    assert m.episodes_to_target([0.0, 10.0, 10.0], 50.0) is None
    assert m.episodes_to_target([1.0, 3.0, 5.0, 7.0], 4.0, window=2) == 2


def test_method_target_and_summaries() -> None:
    a = np.arange(60, dtype=float)
    b = 2.0 * a
    # Best-Win-50: 34.5 and 69 -> median 51.75 -> 80% = 41.4
    assert m.method_target([a, b]) == pytest.approx(41.4)
    assert m.method_target(np.vstack([a, b])) == pytest.approx(41.4)
    assert m.method_target([[1.0], [2.0], [4.0]]) == pytest.approx(1.6)
    assert m.method_target([[1.0], [3.0]], window=1, fraction=0.5) == pytest.approx(1.0)
    s = m.summarize_method([a, b])
    assert s[0]["auc"] == 1770.0 and s[0]["final_50"] == 34.5
    assert s[0]["episodes_to_target"] is None  # a's trailing mean peaks at 34.5 < 41.4
    assert s[1]["episodes_to_target"] == 42  # mean of 0, 2, ..., 84 = 42 >= 41.4
    one = m.curve_summary([1.0, 2.0, 3.0])
    assert one == {"auc": 6.0, "nauc": 2.0, "final_50": 2.0, "best_win_50": 2.0,
                   "episodes_to_target": None}
    assert m.curve_summary([1.0, 2.0, 3.0], target=1.5)["episodes_to_target"] == 1
    assert m.median([3.0, 1.0, 2.0, 10.0]) == 2.5


def test_mean_sd() -> None:
    s = m.mean_sd([1.0, 2.0, 3.0, 4.0])
    assert s["mean"] == 2.5 and s["n"] == 4
    assert s["sd"] == pytest.approx(math.sqrt(5.0 / 3.0))
    assert m.mean_sd([7.0]) == {"mean": 7.0, "sd": None, "n": 1}
    assert m.WINDOW == 50 and m.TARGET_FRACTION == 0.8


def test_gait_metrics_by_hand() -> None:
    names = ["left_knee", "right_knee"]
    trace = {
        "actuator_names": names, "foot_names": [],
        "time": [0.5, 1.0, 1.5], "torso_x": [10.0, 30.0, 60.0], "torso_y": [0.1, -0.3, 0.2],
        "torso_z_error": [-0.1, 0.1, -0.2], "forward_velocity": [1.0, 2.0, 3.0],
        "torques": np.array([[1.0, -3.0], [-1.0, 3.0], [1.0, 3.0]]),
        "powers": [[2.0, 0.0], [-4.0, 0.0], [0.0, 6.0]],
        "foot_forces": [], "fell": False, "success_time": None,
    }
    g = m.gait_metrics(trace)
    assert g["track_time"] == 1.5  # first x >= 50
    assert g["mean_forward_velocity"] == pytest.approx(2.0)
    assert g["mean_abs_lateral"] == pytest.approx(0.2)
    assert g["mean_vertical"] == pytest.approx(-0.2 / 3)
    assert g["mean_abs_vertical"] == pytest.approx(0.4 / 3)
    np.testing.assert_allclose(g["mean_abs_torque"], [1.0, 3.0])
    np.testing.assert_allclose(g["mean_abs_power"], [2.0, 2.0])
    assert g["knee_torque_asymmetry"] == pytest.approx(2.0 / 2.0)  # |1-3| / 2
    assert g["distance"] == 50.0 and g["steps"] == 3 and g["duration"] == 1.5
    assert m.gait_metrics(trace, track_length=100.0)["track_time"] is None
    assert "torso_pitch" not in g  # not logged
    p = m.gait_metrics(dict(trace, torso_pitch=[0.3, -0.1, 0.1]))["torso_pitch"]
    # sorted -0.1, 0.1, 0.3: h = 2 * 0.05 = 0.1 and 2 * 0.95 = 1.9
    assert p["mean"] == pytest.approx(0.1)
    assert p["p5"] == pytest.approx(-0.1 + 0.1 * 0.2) and p["p95"] == pytest.approx(0.1 + 0.9 * 0.2)
    with pytest.raises(ValueError, match="actuator `left_hip` not found"):
        m.gait_metrics(trace, left_knee="left_hip")
    bad = dict(trace, torso_y=[0.1, 0.2])
    with pytest.raises(ValueError, match="torso_y: length 2, expected 3"):
        m.gait_metrics(bad)
    with pytest.raises(ValueError, match="trace: missing field `time`"):
        m.gait_metrics({k: v for k, v in trace.items() if k != "time"})


def test_table1_through_the_bindings() -> None:
    summary = {"auc": 10.0, "nauc": 1.0, "final_50": 2.0, "best_win_50": 3.0,
               "episodes_to_target": 4}
    agents = [{"agent": "es-sac", "seeds": [
        {"summary": summary, "gait": None, "q0_mean": 1.0},
        {"summary": dict(summary, nauc=3.0, episodes_to_target=None), "gait": None,
         "q0_mean": None},
    ]}]
    md = m.table1_markdown(agents)
    lines = md.splitlines()
    assert lines[0].startswith("| Agent | Seeds | nAUC | AUC |")
    # nAUC 1 and 3: mean 2, SD sqrt(2); Episodes-to-Target from one of two seeds
    assert "| es-sac | 2 | 2.00 ± 1.41 |" in lines[2]
    assert "4.00 (1/2)" in lines[2]
    rows = m.table1(agents)
    assert rows[0]["nauc"]["stat"]["mean"] == 2.0
    assert rows[0]["nauc"]["stat"]["sd"] == pytest.approx(math.sqrt(2.0))
    csv = m.table1_csv(agents)
    assert csv.splitlines()[0].startswith("agent,seeds,nauc_mean,nauc_sd,nauc_n")
    assert m.format_number(1234.5678) == "1234.57"
    with pytest.raises(ValueError, match="agents"):
        m.table1_markdown([{"agent": "x"}])
    with pytest.raises(ValueError, match="agent `x`: seeds"):
        m.table1_markdown([{"agent": "x", "seeds": []}])


@pytest.mark.parametrize("bad, message", [
    ([], "curve: empty input"),
    ([1.0, float("nan")], "curve: non-finite value NaN at index 1"),
    ([1.0, float("inf")], "curve: non-finite value inf at index 1"),
])
def test_bad_curves_raise_value_error(bad: list, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        m.auc(bad)


def test_bad_parameters() -> None:
    with pytest.raises(ValueError, match="window: invalid value 0"):
        m.final_mean([1.0], 0)
    with pytest.raises(ValueError, match="target: invalid value NaN"):
        m.episodes_to_target([1.0], float("nan"))
    with pytest.raises(ValueError, match="no seeds"):
        m.method_target([])
    with pytest.raises(ValueError, match=r"curves\[1\]"):
        m.method_target([[1.0], "abc"])
    with pytest.raises(TypeError):
        m.auc([[1.0, 2.0]])  # 2-D is not a curve
    assert issubclass(esrl_rs.EsrlError, Exception)
