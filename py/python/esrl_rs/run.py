"""Run folders written by ``esrl train`` (``config.toml``, ``metrics.jsonl``/``metrics.csv``,
``summary.json``, optionally ``eval.json`` from ``esrl eval``)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Union

import numpy as np

from . import _native

PathLike = Union[str, "os.PathLike[str]"]

__all__ = ["Run", "group_by_agent", "load_run", "load_runs"]


class Run:
    """One run folder, loaded by the Rust core.

    Attributes:
        path: the folder.
        config: the resolved configuration (``config.toml``) as a dict.
        metrics: column name → NumPy array, one entry per generation (ES agents) or episode
            (plain agents); integer columns without gaps are ``int64``, other numeric columns
            ``float64`` with NaN for null/missing; non-numeric columns are lists.
        columns: the column names in file order.
        summary: ``summary.json`` as a dict (empty if the run has not written it yet).
        eval_path: the evaluation report :attr:`eval` reads: ``eval.json`` (``esrl eval
            RUN``, the last checkpoint) unless :meth:`use_best_eval` chose
            ``best/eval.json`` (``esrl eval RUN/best``, an ES run's kept policy).
    """

    def __init__(self, data: Dict[str, Any]) -> None:
        self.path: Path = Path(data["path"])
        self.config: Dict[str, Any] = data["config"]
        self.metrics: Dict[str, Any] = data["metrics"]
        self.columns: List[str] = list(data["columns"])
        self.summary: Dict[str, Any] = data["summary"]
        self.metrics_file: Path = Path(data["metrics_file"])
        self._rows: int = int(data["rows"])
        self._eval: Optional[Dict[str, Any]] = None
        self.eval_path: Path = self.path / "eval.json"

    def __len__(self) -> int:
        return self._rows

    def __repr__(self) -> str:
        return (
            f"Run(path={str(self.path)!r}, agent={self.agent!r}, seed={self.seed!r}, "
            f"rows={self._rows})"
        )

    @property
    def agent(self) -> str:
        """The agent (``config["agent"]``), else the folder name."""
        agent = self.config.get("agent")
        return str(agent) if agent is not None else self.path.name

    @property
    def env(self) -> Optional[str]:
        """The environment (``config["env"]``), if recorded."""
        env = self.config.get("env")
        return None if env is None else str(env)

    @property
    def seed(self) -> Optional[int]:
        """The seed (``config["seed"]``), if recorded."""
        seed = self.config.get("seed")
        return None if seed is None else int(seed)

    @property
    def is_es(self) -> bool:
        """Whether rows are generations (ES-X) rather than episodes."""
        return "generation" in self.metrics

    @property
    def index(self) -> np.ndarray:
        """The generation or episode number of each row (0, 1, … if the log has neither)."""
        for key in ("generation", "episode"):
            if key in self.metrics:
                return np.asarray(self.metrics[key])
        return np.arange(self._rows)

    @property
    def curve(self) -> np.ndarray:
        """The learning curve (column ``curve``)."""
        if "curve" not in self.metrics:
            raise KeyError(f"{self.metrics_file}: no `curve` column (columns: {self.columns})")
        return np.asarray(self.metrics["curve"], dtype=float)

    @property
    def has_eval(self) -> bool:
        """Whether the evaluation report :attr:`eval_path` exists."""
        return self.eval_path.is_file()

    @property
    def eval(self) -> Optional[Dict[str, Any]]:
        """The evaluation report at :attr:`eval_path` (see :func:`esrl_rs.load_eval`), or
        ``None`` if there is none. Loaded on first use."""
        if self._eval is None and self.has_eval:
            self._eval = _native.load_eval(str(self.eval_path))
        return self._eval

    def use_best_eval(self) -> bool:
        """Reads the evaluation of the run's kept policy, ``best/eval.json`` (``esrl eval
        RUN/best``), from now on, if the run keeps one (ES runs
        do; plain runs keep no other policy and stay on ``eval.json``). Returns whether it
        switched."""
        best = self.path / "best"
        if not (best / "best.json").is_file():
            return False
        self.eval_path = best / "eval.json"
        self._eval = None
        return True

    def to_pandas(self) -> Any:
        """The metrics as a ``pandas.DataFrame`` (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Run.to_pandas() needs pandas: pip install pandas") from e
        return pd.DataFrame({c: self.metrics[c] for c in self.columns})

    @property
    def dataframe(self) -> Any:
        """:meth:`to_pandas`."""
        return self.to_pandas()


def load_run(path: PathLike) -> Run:
    """Loads a run folder. Raises ``FileNotFoundError`` for a missing folder or file,
    ``NotADirectoryError`` for a file, ``ValueError`` for malformed contents."""
    return Run(_native.load_run(os.fspath(path)))


def load_runs(paths: Iterable[PathLike]) -> List[Run]:
    """:func:`load_run` on each path, in order."""
    return [load_run(p) for p in paths]


def group_by_agent(runs: Iterable[Run]) -> Dict[str, List[Run]]:
    """Runs grouped by :attr:`Run.agent`, agents in order of first appearance, runs sorted
    by seed within an agent."""
    groups: Dict[str, List[Run]] = {}
    for run in runs:
        groups.setdefault(run.agent, []).append(run)
    for agent, members in groups.items():
        groups[agent] = sorted(
            members, key=lambda r: (r.seed is None, r.seed if r.seed is not None else 0)
        )
    return groups
