"""Analyse esrl runs from Python: run folders and evaluations as NumPy arrays, the metrics of
the paper and the gait-cycle metrics (one implementation, in Rust), Fig. 5 plots, Table 1 and
pictures of the gait (``esrl_rs.gait``), MCAP recordings, and the environments as Gymnasium
``Env``\\ s.

>>> import esrl_rs
>>> run = esrl_rs.load_run("runs/sac-pendulum-s0")     # doctest: +SKIP
>>> esrl_rs.metrics.best_win_50(run.metrics["curve"])   # doctest: +SKIP
>>> env = esrl_rs.Pendulum()                            # doctest: +SKIP

The work is done by the Rust crates of the esrl workspace (``esrl-metrics``, ``esrl-record``,
``esrl-sim``) through the native module ``esrl_rs._native``; errors raised there arrive as
``ValueError``, ``FileNotFoundError`` (or another ``OSError``) or :class:`EsrlError`, with the
Rust message.
"""

from __future__ import annotations

from typing import Any

from . import gait, metrics
from ._native import (
    EsrlError,
    __version__,
    load_eval,
    read_recording,
    read_recording_table,
    recording_channels,
    write_recording,
)
from .policy import Policy, load_policy
from .run import Run, group_by_agent, load_run, load_runs
from ._registry import register as _register_envs

# `gym.make("esrl/Walk-v0")` works right after `import esrl_rs` (no-op without gymnasium).
_register_envs()

__all__ = [
    "EsrlError",
    "Pendulum",
    "Policy",
    "Run",
    "WalkEnv",
    "__version__",
    "gait",
    "group_by_agent",
    "load_eval",
    "load_policy",
    "load_run",
    "load_runs",
    "metrics",
    "read_recording",
    "read_recording_table",
    "recording_channels",
    "write_recording",
]


def __getattr__(name: str) -> Any:
    # The environments need gymnasium; import it only when they are asked for.
    if name in ("WalkEnv", "Pendulum"):
        from . import envs

        return getattr(envs, name)
    raise AttributeError(f"module 'esrl_rs' has no attribute {name!r}")
