"""The esrl environments as Gymnasium ``Env``\\ s, stepping in Rust (``esrl-sim``).

- :class:`WalkEnv`: the humanoid on the 50 m track (43 observations, 6 torques in [-1, 1]);
  registered as ``esrl/Walk-v0``.
- :class:`Pendulum`: Gymnasium's ``Pendulum-v1`` dynamics with the action in [-1, 1]
  (scaled to ±2 N·m); registered as ``esrl/Pendulum-v0``.

``reset(seed=s)`` gives the same initial state as the Rust ``Env::reset(s)`` (so a seed from
``eval.json`` replays in Python); ``reset()`` without a seed draws one from ``self.np_random``.
``step`` returns ``info["reward_terms"]`` (name → value; they sum to the reward) and, for the
walk task, ``info["gait"]`` (torso position, joint torques and power, foot forces, ...). The
environments truncate episodes themselves (``max_episode_steps``), so they are registered
without a ``TimeLimit`` wrapper. Once a step has ended the episode (``terminated`` or
``truncated``), ``step`` raises ``EsrlError`` until the next ``reset``.

``WalkEnv(render_mode="rgb_array")``: ``render()`` returns the robot seen from the side as an
``(H, W, 3)`` uint8 image (the camera follows the torso; left links blue, right ones orange,
a ground tick every metre), so Gymnasium's ``RecordVideo`` wrapper films it.
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional, Tuple

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from . import _registry
from ._native import EnvCore

__all__ = ["Pendulum", "WalkEnv"]

_SEED_BOUND = 2**63 - 1


class _RustEnv(gym.Env[np.ndarray, np.ndarray]):
    """A Gymnasium ``Env`` around an ``EnvCore``."""

    metadata: Dict[str, Any] = {"render_modes": []}
    _render_modes: List[str] = []

    def __init__(self, core: EnvCore, obs_low: np.ndarray, obs_high: np.ndarray,
                 render_mode: Optional[str] = None) -> None:
        if render_mode is not None and render_mode not in self._render_modes:
            raise ValueError(f"render_mode={render_mode!r}: {type(self).__name__} renders "
                             f"{self._render_modes or 'nothing'} (record a rollout with "
                             "`esrl record RUN --out walk.svg` or `walk.mcap` instead)")
        self.render_mode = render_mode
        self._core = core
        self.observation_space = spaces.Box(obs_low, obs_high, dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(core.act_dim,), dtype=np.float32)
        self.metadata = {"render_modes": list(self._render_modes),
                         "render_fps": round(1.0 / core.control_period)}

    def render(self) -> Optional[np.ndarray]:
        """With ``render_mode="rgb_array"``: the side view now, ``(H, W, 3)`` uint8."""
        if self.render_mode == "rgb_array":
            return self._core.render()
        return None

    @property
    def obs_names(self) -> List[str]:
        """A name per observation index."""
        return self._core.obs_names

    @property
    def action_names(self) -> List[str]:
        """A name per action index."""
        return self._core.action_names

    @property
    def effort_limits(self) -> np.ndarray:
        """Torque at action ±1 per actuator, N·m."""
        return np.asarray(self._core.effort_limits, dtype=np.float32)

    @property
    def control_period(self) -> float:
        """Control period, s."""
        return self._core.control_period

    @property
    def max_episode_steps(self) -> int:
        """Steps after which an episode is truncated."""
        return self._core.max_episode_steps

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        """Resets to a seeded initial state; ``info["seed"]`` is the seed the Rust core used.
        ``options`` is accepted for API compatibility and ignored."""
        if seed is not None and not 0 <= int(seed) < 2**64:
            raise ValueError(f"seed={seed}: must be an integer in [0, 2**64)")
        super().reset(seed=seed)
        if seed is None:
            seed = int(self.np_random.integers(0, _SEED_BOUND))
        obs = self._core.reset(int(seed))
        return obs, {"seed": int(seed)}

    def step(self, action: Any) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        """One control step. Actions are clipped to [-1, 1] (NaN → 0) by the core."""
        a = np.asarray(action, dtype=np.float32).reshape(-1)
        return self._core.step(a)


class WalkEnv(_RustEnv):
    """The humanoid walking task (SPEC §2). ``config``: any subset of ``WalkConfig``'s fields,
    e.g. ``{"episode_seconds": 10, "reward": {"lateral": 2.0}}``; unknown keys raise
    ``ValueError``. ``render_mode="rgb_array"`` renders the side view (module docs)."""

    _render_modes = ["rgb_array"]

    def __init__(self, config: Optional[Mapping[str, Any]] = None,
                 render_mode: Optional[str] = None) -> None:
        core = EnvCore.walk(dict(config) if config is not None else None)
        inf = np.full(core.obs_dim, np.inf, dtype=np.float32)
        super().__init__(core, -inf, inf, render_mode)

    @property
    def config(self) -> Dict[str, Any]:
        """The resolved configuration (every ``WalkConfig`` field)."""
        return self._core.config


class Pendulum(_RustEnv):
    """Gymnasium ``Pendulum-v1`` in Rust, action in [-1, 1] (×2 N·m)."""

    def __init__(self, render_mode: Optional[str] = None) -> None:
        core = EnvCore.pendulum()
        # The pendulum renders nothing (`_render_modes` is empty).
        high = np.array([1.0, 1.0, 8.0], dtype=np.float32)
        super().__init__(core, -high, high, render_mode)


_registry.register()
