"""Trained policies from run folders: act step by step, estimate Q0, and evaluate with the
CLI's own code (``esrl eval``: same loader, episode loop and ``eval.json`` structure)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

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
    def load(cls, path: Union[str, "os.PathLike[str]"], undisturbed: bool = False,
             last: bool = False, default_starts: bool = False) -> "Policy":
        """Loads a run folder (the policy it hands over, as ``esrl eval RUN``: its kept
        policy ``RUN/best/`` when it has one, else its newest complete checkpoint; ``last``:
        the newest checkpoint, as ``esrl eval --last``), a checkpoint or ``best/`` folder,
        or a policy folder that keeps the actor alone (a study record's ``policy/``:
        ``actor.safetensors`` and its ``config.toml``; it has no critics, so :meth:`q0`
        raises ``ValueError`` there). ``undisturbed``: on the run's task without its
        training-time disturbances (``[walk.perturb]``; ``esrl eval --undisturbed``).
        ``default_starts``: from the task's standard starts (``walk.init_noise`` and
        ``walk.reset`` at their defaults; ``esrl eval --default-starts``), for a policy
        trained from other starts. Raises ``FileNotFoundError`` (no folder, no checkpoint) or ``ValueError`` (a
        config or checkpoint that cannot be used)."""
        return cls(PolicyCore.load(os.fspath(path), bool(undisturbed), bool(last),
                                   bool(default_starts)))

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
        """The critics' estimate (minimum) at ``obs`` for the deterministic action
        (``ValueError`` for a policy folder that keeps the actor alone)."""
        return self._core.q0(np.asarray(obs, dtype=np.float32).reshape(-1))

    def make_env(self) -> Any:
        """A Gymnasium environment configured like the run's (needs gymnasium)."""
        from .envs import Pendulum, WalkEnv

        if self.env == "walk":
            return WalkEnv(self._core.walk_config)
        return Pendulum()

    def evaluate(self, episodes: int = 1, seed: int = 0,
                 record: Optional[Union[str, "os.PathLike[str]"]] = None) -> Dict[str, Any]:
        """``esrl eval`` on this policy, run by the CLI's own Rust code: ``episodes``
        deterministic episodes with seeds ``seed, seed + 1, ...`` (in parallel), each also
        recorded to ``record/episode-NNN.mcap`` when ``record`` is a folder (walking runs).
        Returns what ``eval.json`` holds (``run``, ``agent``, ``episodes`` with ``return``,
        ``q0``, ``gait``, ``trace``, and ``mean``), number lists as NumPy arrays."""
        if int(episodes) < 1:
            raise ValueError(f"episodes={episodes}: evaluate at least one episode")
        if int(seed) < 0:
            raise ValueError(f"seed={seed}: must be ≥ 0")
        out = os.fspath(record) if record is not None else None
        return self._core.evaluate(int(seed), int(episodes), out)

    def rollout(self, seed: int = 0) -> Dict[str, Any]:
        """One deterministic episode from ``reset(seed)``: ``evaluate(1, seed)``'s episode."""
        episodes: List[Dict[str, Any]] = self.evaluate(1, seed)["episodes"]
        return episodes[0]


def load_policy(path: Union[str, "os.PathLike[str]"], undisturbed: bool = False,
                last: bool = False, default_starts: bool = False) -> Policy:
    """:meth:`Policy.load`."""
    return Policy.load(path, undisturbed, last, default_starts)
