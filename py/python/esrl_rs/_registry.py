"""Registers the esrl environments with Gymnasium (``esrl/Walk-v0``, ``esrl/Pendulum-v0``).

Called on ``import esrl_rs`` so that ``gym.make("esrl/Walk-v0")`` works right after it; the
entry points are strings, so nothing heavy is imported until an environment is made.
"""

from __future__ import annotations

ENV_IDS = (
    ("esrl/Walk-v0", "esrl_rs.envs:WalkEnv"),
    ("esrl/Pendulum-v0", "esrl_rs.envs:Pendulum"),
)


def register() -> bool:
    """Registers every id not registered yet; returns False when gymnasium is missing."""
    try:
        import gymnasium as gym
    except ImportError:
        return False
    for env_id, entry in ENV_IDS:
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry)
    return True
