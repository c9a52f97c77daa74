"""Parity with the Rust CLI: runs trained by `esrl train` load in Python, and the Python
metrics (through the bindings) reproduce the CLI's summary.json."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import esrl_rs
from esrl_rs import metrics as m


@pytest.mark.parametrize("agent, args", [
    ("sac", ("--env", "pendulum", "--preset", "smoke", "--episodes", "60", "--seed", "3")),
    ("es-sac", ("--env", "pendulum", "--preset", "smoke", "--generations", "3", "--seed", "1")),
])
def test_summary_parity(cli_train: Callable[..., Path], agent: str, args: tuple) -> None:
    root = cli_train(agent, *args)
    run = esrl_rs.load_run(root)
    assert run.agent == agent
    assert run.env == "pendulum"
    summary = json.loads((root / "summary.json").read_text())
    curve = run.curve
    # the curve is the logged column, row for row
    rows = [json.loads(line) for line in (root / "metrics.jsonl").read_text().splitlines()]
    np.testing.assert_array_equal(curve, [r["curve"] for r in rows])
    assert len(curve) == (60 if agent == "sac" else 3)
    for key, fn in (("auc", m.auc), ("nauc", m.nauc), ("final_50", m.final_50),
                    ("best_win_50", m.best_win_50)):
        assert fn(curve) == pytest.approx(summary[key], rel=1e-12, abs=1e-12), key
    assert m.curve_summary(curve)["auc"] == pytest.approx(summary["auc"], rel=1e-12)
    if summary.get("q0_mean") is not None:
        q0 = run.metrics["q0"]
        assert np.nanmean(q0) == pytest.approx(summary["q0_mean"], rel=1e-9)
    # one seed's target is 80% of its own Best-Win-50
    target = m.method_target([curve])
    assert target == pytest.approx(0.8 * summary["best_win_50"], rel=1e-12)


def test_cli_run_csv_matches_jsonl(cli_train: Callable[..., Path], tmp_path: Path) -> None:
    root = cli_train("sac", "--env", "pendulum", "--preset", "smoke", "--episodes", "60",
                     "--seed", "3")
    from_jsonl = esrl_rs.load_run(root)
    copy = tmp_path / "csv-only"
    copy.mkdir()
    for name in ("config.toml", "metrics.csv", "summary.json"):
        (copy / name).write_bytes((root / name).read_bytes())
    from_csv = esrl_rs.load_run(copy)
    for column in ("curve", "q0", "env_steps"):
        np.testing.assert_allclose(from_csv.metrics[column], from_jsonl.metrics[column],
                                   rtol=1e-15)
