"""The ES population of a hybrid agent (ES-SAC, ES-TD3, ES-DDPG) on a Ray cluster.

``python -m esrl_rs.ray train AGENT`` takes the options of ``esrl train`` plus ``--address``
and ``--workers``. What runs where:

- the **driver** (this process) runs the hybrid loop in Rust through ``esrl_rs._native``:
  asking for each generation's genomes, the ES update, elitist replacement, the inner
  gradient updates, and every file of the run folder (the same code as ``esrl train``, so
  ``esrl eval``, ``esrl record``, ``esrl compare`` and ``esrl train --resume`` work on it);
- **Ray tasks** roll genomes out: each gets the run's ``config.toml`` text (put in the object
  store once) and one genome as bytes (weights and seeds), builds the policy and a fresh
  environment in Rust (:func:`rollout`), and returns the episodes as bytes. A worker process
  keeps its built policy between tasks of the same run.

Results equal ``esrl train``'s for the same settings and seed, bit for bit, whatever the
number of workers: every genome names its random streams, and evaluations are taken in
individual order. A worker that dies has its tasks re-run by Ray (``max_retries``); the
driver dying is covered by the run's checkpoints (``--resume``).
"""

from __future__ import annotations

import os
import signal
import time
from typing import Any, Dict, List, Optional

from .. import _native

__all__ = ["RayEvaluator", "rollout", "MAX_RETRIES", "KILL_ONCE_ENV"]

#: How often Ray re-runs a genome whose worker process died.
MAX_RETRIES = 5

#: Fault injection for tests: when this environment variable names a path that does not
#: exist yet, the first rollout to create it kills its own worker process (SIGKILL) before
#: rolling out, as a crashed or preempted worker would.
KILL_ONCE_ENV = "ESRL_RAY_KILL_ONCE"

# Per worker process: the run's config.toml text -> its native worker.
_WORKERS: Dict[str, Any] = {}


def rollout(config_toml: str, genome: bytes) -> bytes:
    """Rolls one genome out in this process: the body of the Ray task.

    ``config_toml`` is the run's ``config.toml`` text and ``genome`` a genome's bytes from the
    driver; returns the evaluation's bytes. Deterministic: the same genome gives the same
    bytes on any machine of the same kind.
    """
    worker = _WORKERS.get(config_toml)
    if worker is None:
        worker = _WORKERS[config_toml] = _native.Worker(config_toml)
    _maybe_die()
    return worker.rollout(genome)


def _maybe_die() -> None:
    path = os.environ.get(KILL_ONCE_ENV)
    if not path:
        return
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return
    os.write(fd, str(os.getpid()).encode())
    os.close(fd)
    os.kill(os.getpid(), signal.SIGKILL)


class RayEvaluator:
    """The driver's side: called by the Rust hybrid loop with a list of genome bytes, it runs
    one Ray task per genome, at most ``workers`` at a time when given, and returns the
    evaluation bytes in the order of the genomes. Counts the seconds it waited."""

    def __init__(self, config_toml: str, workers: Optional[int] = None) -> None:
        import ray

        if workers is not None and workers < 1:
            raise ValueError(f"workers = {workers}: needs at least one")
        self._ray = ray
        self._config = ray.put(config_toml)
        self._task = ray.remote(num_cpus=1, max_retries=MAX_RETRIES)(rollout)
        self.workers = workers
        self.wait_s = 0.0

    def __call__(self, genomes: List[bytes]) -> List[bytes]:
        ray = self._ray
        started = time.perf_counter()
        limit = self.workers or len(genomes)
        refs: List[Any] = []
        in_flight: List[Any] = []
        for genome in genomes:
            if len(in_flight) >= limit:
                # At most `limit` tasks in flight; results are still taken in genome order.
                _, in_flight = ray.wait(in_flight, num_returns=1)
            ref = self._task.remote(self._config, genome)
            refs.append(ref)
            in_flight.append(ref)
        out = ray.get(refs)
        self.wait_s += time.perf_counter() - started
        return out
