"""Trained policies from run folders: act, estimate Q0 and roll out deterministically in Rust,
with the networks, weights and episode loop of ``esrl eval``."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Union

import numpy as np

from ._native import PolicyCore

__all__ = ["Policy", "load_policy"]


class Policy:
    """A trained agent's deterministic policy (``tanh(μ)``) with its critics' Q0.

    The actor may be recurrent: call :meth:`reset` at the start of every episode, then
    :meth:`act` once per step, in order.
    """

    def __init__(self, core: PolicyCore) -> None:
        self._core = core

    @classmethod
    def load(cls, path: Union[str, "os.PathLike[str]"]) -> "Policy":
        """Loads a run folder (its newest complete checkpoint) or a checkpoint folder inside
        one. Raises ``FileNotFoundError`` (no folder, no checkpoint) or ``ValueError`` (a
        config or checkpoint that cannot be used)."""
        return cls(PolicyCore.load(os.fspath(path)))

    def __repr__(self) -> str:
        return f"Policy(agent={self.agent!r}, env={self.env!r}, checkpoint={self.checkpoint!r})"

    @property
    def agent(self) -> str:
        """The agent (``es-sac``, ``sac``, ...)."""
        return self._core.agent

    @property
    def env(self) -> str:
        """The environment (``walk`` or ``pendulum``)."""
        return self._core.env

    @property
    def run(self) -> str:
        """The run folder."""
        return self._core.run

    @property
    def checkpoint(self) -> str:
        """The checkpoint folder the weights came from."""
        return self._core.checkpoint

    @property
    def obs_dim(self) -> int:
        """Observation length."""
        return self._core.obs_dim

    @property
    def act_dim(self) -> int:
        """Action length."""
        return self._core.act_dim

    def reset(self) -> None:
        """Zeroes the recurrent state."""
        self._core.reset()

    def act(self, obs: Any) -> np.ndarray:
        """The deterministic action (float32, in [-1, 1]) for ``obs``."""
        return self._core.act(np.asarray(obs, dtype=np.float32).reshape(-1))

    def __call__(self, obs: Any) -> np.ndarray:
        return self.act(obs)

    def q0(self, obs: Any) -> float:
        """The critics' estimate (minimum) at ``obs`` for the deterministic action."""
        return self._core.q0(np.asarray(obs, dtype=np.float32).reshape(-1))

    def make_env(self) -> Any:
        """A Gymnasium environment configured like the run's (needs gymnasium)."""
        from .envs import Pendulum, WalkEnv

        if self.env == "walk":
            return WalkEnv(self._core.walk_config)
        return Pendulum()

    def rollout(self, seed: int = 0) -> Dict[str, Any]:
        """One deterministic episode from ``reset(seed)`` in the run's environment:
        ``{"seed", "return", "length", "terminated", "truncated", "q0"}``, plus ``"trace"``
        and ``"gait"`` for walking runs (as in ``eval.json``)."""
        return self._core.rollout(int(seed))

    def evaluate(self, episodes: int = 1, seed: int = 0) -> Dict[str, Any]:
        """``episodes`` rollouts with seeds ``seed, seed + 1, ...`` (as ``esrl eval``):
        ``{"episodes": [...]}`` in the format of :func:`esrl_rs.load_eval`."""
        if episodes < 1:
            raise ValueError(f"episodes={episodes}: evaluate at least one episode")
        eps: List[Dict[str, Any]] = [self.rollout(seed + k) for k in range(episodes)]
        return {"episodes": eps}


def load_policy(path: Union[str, "os.PathLike[str]"]) -> Policy:
    """:meth:`Policy.load`."""
    return Policy.load(path)
