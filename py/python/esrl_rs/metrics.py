"""The metrics of SPEC §6 (paper §5, Table 1), computed by the Rust crate ``esrl-metrics``.

Curves are 1-D array-likes of finite numbers (one value per generation or episode); NaN, inf
and empty input raise ``ValueError`` rather than returning a silent NaN. Conventions (all from
the Rust crate): a curve shorter than the window uses all its values for Final-50 and
Best-Win-50; trailing means average the values available so far; Episodes-to-Target is a
0-based index, ``None`` when never reached; the SD of a single value is ``None``.

Gait cycle (the Rust module ``esrl_metrics::cycle`` documents every rule and the source of every
threshold): :func:`gait_phases` turns two contact traces into support phases, touchdowns,
alternation, cadence and stride-time variability; :func:`step_lengths` adds the distance between
successive footprints; :func:`classify_gait` names the gait (``walk``, ``run``, ``hop``,
``shuffle``, ``stand`` or ``fall``); :func:`joint_motion` gives a joint's range of motion
(5th–95th percentile) and time at a limit. :data:`GAIT_THRESHOLDS` holds the defaults; every
function that uses thresholds takes a dict overriding some of them.

>>> import numpy as np
>>> left = np.arange(400) % 100 < 60            # down 60 % of a 1 s cycle
>>> right = (np.arange(400) + 50) % 100 < 60     # the same, half a cycle later
>>> p = gait_phases(left, right, dt=0.01)
>>> round(p["double_support"], 3), p["alternation"], classify_gait(p)
(0.2, 1.0, 'walk')

Table functions take ``agents``: a list of ``{"agent": str, "seeds": [{"summary": {...},
"gait": {...} | None, "q0_mean": float | None}, ...]}`` (the serde form of
``esrl_metrics::AgentRuns``); :func:`esrl_rs.report.agent_runs` builds it from run folders.
"""

from __future__ import annotations

from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._native import metrics as _m

ArrayLike = Union[npt.ArrayLike, Sequence[float]]

#: Window of Final-50, Best-Win-50 and Episodes-to-Target.
WINDOW: int = _m.WINDOW
#: Fraction of the median Best-Win-50 that defines a method's target (0.8).
TARGET_FRACTION: float = _m.TARGET_FRACTION

#: The default thresholds of the gait-cycle metrics and the gait class (keys of
#: ``esrl_metrics::GaitThresholds``: ``contact_force`` N, ``sync_window`` s, ``min_touchdowns``,
#: ``min_duration`` s, ``min_cadence`` steps/min, ``min_synchronous``, ``min_alternation``,
#: ``min_flight``, ``min_advance`` m, ``still_speed`` m/s, ``limit_margin`` rad).
GAIT_THRESHOLDS: Dict[str, Any] = dict(_m.gait_thresholds())

#: The gait classes, from the least to the most locomotive.
GAIT_CLASSES: Tuple[str, ...] = ("fall", "stand", "shuffle", "hop", "run", "walk")

__all__ = [
    "GAIT_CLASSES",
    "GAIT_THRESHOLDS",
    "TARGET_FRACTION",
    "WINDOW",
    "actuator_markdown",
    "auc",
    "best_win_50",
    "best_window_mean",
    "classify_gait",
    "curve_summary",
    "episodes_to_target",
    "final_50",
    "final_mean",
    "format_number",
    "gait_metrics",
    "gait_phases",
    "joint_markdown",
    "joint_motion",
    "mean_sd",
    "median",
    "method_target",
    "nauc",
    "percentile",
    "q0_mean",
    "step_lengths",
    "summarize_method",
    "table1",
    "table1_csv",
    "table1_markdown",
    "trailing_means",
]


def auc(curve: ArrayLike) -> float:
    """AUC: the sum of the curve."""
    return _m.auc(curve)


def nauc(curve: ArrayLike) -> float:
    """nAUC: AUC divided by the curve's length (average return per generation/episode)."""
    return _m.nauc(curve)


def q0_mean(q0: ArrayLike) -> Optional[float]:
    """Mean Q0 of a run: the mean of the finite values of its ``q0`` column, ``None`` when
    there are none (the rule of ``summary.json`` and ``esrl compare``)."""
    return _m.q0_mean(q0)


def final_50(curve: ArrayLike) -> float:
    """Final-50: mean of the last 50 values (all values if fewer)."""
    return _m.final_50(curve)


def final_mean(curve: ArrayLike, window: int) -> float:
    """Mean of the last ``window`` values (all values if fewer)."""
    return _m.final_mean(curve, window)


def best_win_50(curve: ArrayLike) -> float:
    """Best-Win-50: best mean of 50 consecutive values (mean of all values if fewer)."""
    return _m.best_win_50(curve)


def best_window_mean(curve: ArrayLike, window: int) -> float:
    """Best mean of ``window`` consecutive values (mean of all values if fewer)."""
    return _m.best_window_mean(curve, window)


def trailing_means(curve: ArrayLike, window: int = WINDOW) -> np.ndarray:
    """Trailing means ``m[i] = mean(c[max(0, i+1-window) : i+1])`` (MATLAB ``movmean(c,
    [w-1 0])``), one per value."""
    return _m.trailing_means(curve, window)


def episodes_to_target(curve: ArrayLike, target: float, window: int = WINDOW) -> Optional[int]:
    """First 0-based index whose trailing ``window``-value mean is ≥ ``target``; ``None`` if
    the curve never gets there."""
    return _m.episodes_to_target(curve, target, window)


def median(values: ArrayLike) -> float:
    """Median (mean of the two middle values for an even count)."""
    return _m.median(values)


def method_target(
    curves: Iterable[ArrayLike], window: int = WINDOW, fraction: float = TARGET_FRACTION
) -> float:
    """A method's target: ``fraction`` × the median over its seeds' curves of the best
    ``window``-value mean (paper: 80% of the median Best-Win-50)."""
    return _m.method_target(list(curves), window, fraction)


def curve_summary(curve: ArrayLike, target: Optional[float] = None) -> Dict[str, Any]:
    """``{"auc", "nauc", "final_50", "best_win_50", "episodes_to_target"}`` of one curve (the
    keys of ``summary.json``); Episodes-to-Target is ``None`` without a ``target``."""
    return _m.curve_summary(curve, target)


def summarize_method(curves: Iterable[ArrayLike]) -> List[Dict[str, Any]]:
    """:func:`curve_summary` of every seed of one method against the method's target, in the
    order of ``curves``."""
    return _m.summarize_method(list(curves))


def mean_sd(values: ArrayLike) -> Dict[str, Any]:
    """``{"mean": float, "sd": float | None, "n": int}``: mean ± sample SD (n − 1)."""
    return _m.mean_sd(values)


def gait_metrics(
    trace: Mapping[str, Any],
    track_length: float = 50.0,
    left_knee: str = "left_knee",
    right_knee: str = "right_knee",
    thresholds: Optional[Mapping[str, Any]] = None,
) -> Dict[str, Any]:
    """Gait metrics of one rollout. ``trace`` has the fields of ``esrl_metrics::GaitTrace``:
    ``actuator_names``, ``foot_names``, ``time``, ``torso_x``, ``torso_y``, ``torso_z_error``,
    ``forward_velocity`` (per step), ``torques``, ``powers`` (steps × actuators),
    ``foot_forces`` (steps × feet, N), ``fell`` and ``success_time`` (``None`` if none), and
    optionally ``joint_angles`` (steps × actuators, rad), ``joint_limits`` (``[lower, upper]``
    or ``None`` per actuator), ``foot_positions`` (steps × feet × ``[x, y]``, m) and
    ``torso_pitch`` (per step, rad, forward lean positive: ``atan2(u_x, u_z)`` of the torso's
    up axis ``u`` in the world).

    With two feet the result has ``cycle`` (:func:`gait_phases` of the forces above
    ``thresholds["contact_force"]``, step lengths, foot speed, ``gait_class``); with joint
    angles, ``joints`` (:func:`joint_motion` of each actuator); with the torso pitch,
    ``torso_pitch`` (its ``mean``, ``p5`` and ``p95``)."""
    return _m.gait_metrics(trace, track_length, left_knee, right_knee, _thresholds(thresholds))


def _thresholds(overrides: Optional[Mapping[str, Any]]) -> Optional[Dict[str, Any]]:
    """The defaults updated with ``overrides`` (unknown keys are refused by the Rust side)."""
    if overrides is None:
        return None
    return {**GAIT_THRESHOLDS, **dict(overrides)}


def gait_phases(
    left_contact: ArrayLike,
    right_contact: ArrayLike,
    dt: float,
    sync_window: Optional[float] = None,
) -> Dict[str, Any]:
    """Support phases and touchdowns of two contact traces sampled every ``dt`` seconds
    (booleans or 0/1; threshold forces first, e.g. ``force > GAIT_THRESHOLDS["contact_force"]``).
    Sample ``i`` is the state at ``(i + 1)·dt``; a foot down at the first sample has not
    touched down.

    Returns ``samples``, ``dt``, ``duration``; ``double_support``, ``single_support``,
    ``flight`` (fractions of the time, summing to 1), ``duty_factor`` (left, right);
    ``touchdowns`` (left, right), ``touchdown_times`` (two arrays, s), ``step_count`` (all
    touchdowns), ``cadence`` (steps/min), ``landings`` (two-footed landings: opposite
    touchdowns at most ``sync_window`` apart, default ``GAIT_THRESHOLDS["sync_window"]``),
    ``alternation`` (share of successive beats that switch foot), ``synchronous`` (share of
    touchdowns in landings), ``stride_time_mean``, ``stride_time_sd``, ``stride_time_cv``
    (``None`` where undefined)."""
    out = _m.gait_phases(left_contact, right_contact, dt, sync_window)
    times = out["touchdown_times"]
    out["touchdown_times"] = tuple(np.asarray(t, dtype=float).reshape(-1) for t in times)
    out["touchdowns"] = tuple(int(n) for n in out["touchdowns"])
    out["duty_factor"] = tuple(float(d) for d in out["duty_factor"])
    return out


def step_lengths(
    left_contact: ArrayLike,
    right_contact: ArrayLike,
    foot_x: ArrayLike,
    dt: float,
    sync_window: Optional[float] = None,
) -> np.ndarray:
    """Step lengths (m): for successive one-footed touchdowns of different feet, the forward
    position of the new foot at its touchdown minus the other foot's at its own.
    ``foot_x`` is samples × 2 (left x, right x)."""
    return _m.step_lengths(left_contact, right_contact, np.asarray(foot_x, dtype=float), dt,
                           sync_window)


def classify_gait(inputs: Mapping[str, Any],
                  thresholds: Optional[Mapping[str, Any]] = None) -> str:
    """The gait class: ``"walk"``, ``"run"``, ``"hop"``, ``"shuffle"``, ``"stand"`` or
    ``"fall"``. ``inputs`` is a :func:`gait_phases` result, optionally with ``fell`` (bool)
    and ``foot_speed`` (m/s, the feet's net horizontal travel / duration); without foot speed,
    not stepping reads as ``"stand"`` and the advance per step is not checked. Rules, in
    order: fall (fell before ``min_touchdowns`` or within ``min_duration``); stand/shuffle (too
    few steps or a cadence under ``min_cadence``; shuffle when the feet slide); hop (landings
    together, or no alternation with flight); shuffle (no alternation, or the feet advance
    less than ``min_advance`` per step); run (flight ≥ ``min_flight``); walk."""
    keys = ("fell", "step_count", "cadence", "duration", "synchronous", "alternation",
            "double_support", "flight", "foot_speed")
    return _m.classify_gait({k: inputs[k] for k in keys if k in inputs},
                            _thresholds(thresholds))


def joint_motion(name: str, angles: ArrayLike,
                 limits: Optional[Tuple[float, float]] = None,
                 margin: Optional[float] = None) -> Dict[str, Any]:
    """Range of motion of one joint (rad): ``p5``, ``p95``, ``range = p95 − p5``; with
    ``limits = (lower, upper)`` also ``at_lower``, ``at_upper``, ``at_limit``: shares of the
    samples within ``margin`` (default 1°) of a limit."""
    return _m.joint_motion(name, angles, limits, margin)


def percentile(values: ArrayLike, p: float) -> float:
    """The ``p``-quantile, ``p`` in [0, 1], interpolating linearly (NumPy's default)."""
    return _m.percentile(values, p)


def table1(agents: Sequence[Mapping[str, Any]]) -> List[Dict[str, Any]]:
    """Table 1 rows, one dict per agent (cells are ``{"stat": {"mean", "sd", "n"} | None,
    "seeds": int}``)."""
    return _m.table1(list(agents))


def table1_markdown(agents: Sequence[Mapping[str, Any]]) -> str:
    """Table 1 as a GitHub-flavoured Markdown table."""
    return _m.table1_markdown(list(agents))


def table1_csv(agents: Sequence[Mapping[str, Any]]) -> str:
    """Table 1 as CSV (``<key>_mean, <key>_sd, <key>_n`` per metric)."""
    return _m.table1_csv(list(agents))


def actuator_markdown(agents: Sequence[Mapping[str, Any]]) -> str:
    """Mean |torque| and mean |power| per actuator (paper Fig. 5d) as Markdown."""
    return _m.actuator_markdown(list(agents))


def joint_markdown(agents: Sequence[Mapping[str, Any]]) -> str:
    """Range of motion (5th–95th percentile, degrees) and time at a limit per joint as
    Markdown."""
    return _m.joint_markdown(list(agents))


def format_number(x: float) -> str:
    """The number format of Table 1 cells."""
    return _m.format_number(x)
