"""The metrics of SPEC §6 (paper §5, Table 1), computed by the Rust crate ``esrl-metrics``.

Curves are 1-D array-likes of finite numbers (one value per generation or episode); NaN, inf
and empty input raise ``ValueError`` rather than returning a silent NaN. Conventions (all from
the Rust crate): a curve shorter than the window uses all its values for Final-50 and
Best-Win-50; trailing means average the values available so far; Episodes-to-Target is a
0-based index, ``None`` when never reached; the SD of a single value is ``None``.

Table functions take ``agents``: a list of ``{"agent": str, "seeds": [{"summary": {...},
"gait": {...} | None, "q0_mean": float | None}, ...]}`` (the serde form of
``esrl_metrics::AgentRuns``); :func:`esrl_rs.report.agent_runs` builds it from run folders.
"""

from __future__ import annotations

from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._native import metrics as _m

ArrayLike = Union[npt.ArrayLike, Sequence[float]]

#: Window of Final-50, Best-Win-50 and Episodes-to-Target.
WINDOW: int = _m.WINDOW
#: Fraction of the median Best-Win-50 that defines a method's target (0.8).
TARGET_FRACTION: float = _m.TARGET_FRACTION

__all__ = [
    "TARGET_FRACTION",
    "WINDOW",
    "actuator_markdown",
    "auc",
    "best_win_50",
    "best_window_mean",
    "curve_summary",
    "episodes_to_target",
    "final_50",
    "final_mean",
    "format_number",
    "gait_metrics",
    "mean_sd",
    "median",
    "method_target",
    "nauc",
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
) -> Dict[str, Any]:
    """Gait metrics of one rollout. ``trace`` has the fields of ``esrl_metrics::GaitTrace``:
    ``actuator_names``, ``foot_names``, ``time``, ``torso_x``, ``torso_y``, ``torso_z_error``,
    ``forward_velocity`` (per step), ``torques``, ``powers`` (steps × actuators),
    ``foot_forces`` (steps × feet), ``fell`` and ``success_time`` (``None`` if none)."""
    return _m.gait_metrics(trace, track_length, left_knee, right_knee)


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


def format_number(x: float) -> str:
    """The number format of Table 1 cells."""
    return _m.format_number(x)
