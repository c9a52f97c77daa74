"""load_run / load_eval on run folders written here in the CLI's format, and bad paths."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, List

import numpy as np
import pytest

import esrl_rs
from conftest import episode, write_run


def test_load_synthetic_run(tmp_path: Path) -> None:
    q0 = [None, 0.5, 1.5]
    root = write_run(tmp_path / "r", "es-sac", 7, [1.0, 2.0, 4.0], es=True, q0=q0)
    run = esrl_rs.load_run(root)
    assert run.agent == "es-sac" and run.seed == 7 and run.env == "walk" and run.is_es
    assert run.config["es"] == {"sigma": 0.25}
    assert len(run) == 3
    assert run.columns[:3] == ["generation", "env_steps", "curve"]
    assert run.metrics["generation"].dtype == np.int64
    np.testing.assert_array_equal(run.metrics["generation"], [0, 1, 2])
    np.testing.assert_array_equal(run.curve, [1.0, 2.0, 4.0])
    assert run.metrics["q0"].dtype == np.float64
    assert np.isnan(run.metrics["q0"][0]) and run.metrics["q0"][2] == 1.5
    # an all-null column is all NaN
    assert np.isnan(run.metrics["rl_fitness"]).all()
    np.testing.assert_array_equal(run.index, [0, 1, 2])
    assert run.summary["auc"] == 7.0
    assert run.eval is None and not run.has_eval
    assert "es-sac" in repr(run)


def test_rows_with_extra_and_missing_keys(tmp_path: Path) -> None:
    root = write_run(tmp_path / "r", "sac", 0, [1.0, 2.0])
    with open(root / "metrics.jsonl", "a", encoding="utf-8") as f:
        f.write(json.dumps({"episode": 2, "curve": 3.0, "note": "late", "flag": True}) + "\n")
    run = esrl_rs.load_run(root)
    np.testing.assert_array_equal(run.curve, [1.0, 2.0, 3.0])
    assert np.isnan(run.metrics["return"][2])  # missing → NaN
    assert run.metrics["note"] == [None, None, "late"]  # a non-numeric column is a list
    # a boolean column with gaps is 0/1 with NaN; one without gaps is a bool array
    assert np.isnan(run.metrics["flag"][0]) and run.metrics["flag"][2] == 1.0
    (root / "metrics.jsonl").write_text('{"curve": 1, "ok": true}\n{"curve": 2, "ok": false}\n')
    run = esrl_rs.load_run(root)
    assert run.metrics["ok"].dtype == np.bool_ and run.metrics["ok"].tolist() == [True, False]


def test_csv_fallback_and_partial_last_line(tmp_path: Path) -> None:
    root = write_run(tmp_path / "r", "sac", 0, [1.0, 2.0], q0=[None, 2.5])
    text = (root / "metrics.jsonl").read_text()
    (root / "metrics.jsonl").write_text(text + '{"episode": 2, "cur')  # a row being written
    assert len(esrl_rs.load_run(root)) == 2
    (root / "metrics.jsonl").unlink()
    run = esrl_rs.load_run(root)
    assert run.metrics_file.name == "metrics.csv"
    np.testing.assert_array_equal(run.curve, [1.0, 2.0])
    assert np.isnan(run.metrics["q0"][0]) and run.metrics["q0"][1] == 2.5


def test_missing_summary_is_empty(tmp_path: Path) -> None:
    root = write_run(tmp_path / "r", "sac", 0, [1.0])
    (root / "summary.json").unlink()
    assert esrl_rs.load_run(root).summary == {}


def test_to_pandas(tmp_path: Path) -> None:
    pd = pytest.importorskip("pandas")
    run = esrl_rs.load_run(write_run(tmp_path / "r", "sac", 0, [1.0, 2.0], q0=[None, 1.0]))
    df = run.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == run.columns and len(df) == 2
    assert df["curve"].tolist() == [1.0, 2.0]
    assert run.dataframe.shape == df.shape


def test_load_eval(synthetic_runs: List[Path]) -> None:
    ev = esrl_rs.load_eval(synthetic_runs[0])
    by_file = esrl_rs.load_eval(synthetic_runs[0] / "eval.json")
    np.testing.assert_array_equal(by_file["episodes"][0]["trace"]["y"],
                                  ev["episodes"][0]["trace"]["y"])
    ep = ev["episodes"][0]
    assert ep["seed"] == 0 and ep["return"] == 123.5
    assert isinstance(ep["trace"]["x"], np.ndarray) and ep["trace"]["x"].shape == (40,)
    assert ep["gait"]["actuator_names"][1] == "left_knee"
    np.testing.assert_allclose(ep["gait"]["mean_abs_power"], [5, 10, 15, 20, 25, 30])
    assert ep["extra_key"] == {"kept": True} and ev["version"] == 1
    run = esrl_rs.load_run(synthetic_runs[0])
    assert run.has_eval and run.eval is not None and len(run.eval["episodes"]) == 1
    # what load_eval returns goes back into the metrics functions
    agents = [{"agent": "x", "seeds": [{"summary": esrl_rs.metrics.curve_summary(run.curve),
                                        "gait": ep["gait"], "q0_mean": None}]}]
    assert "left_knee" in esrl_rs.metrics.actuator_markdown(agents)


def test_bad_paths_raise(tmp_path: Path) -> None:
    missing = tmp_path / "nope"
    with pytest.raises(FileNotFoundError, match="nope: no such run folder"):
        esrl_rs.load_run(missing)
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    with pytest.raises(NotADirectoryError, match="not a run folder"):
        esrl_rs.load_run(a_file)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(FileNotFoundError, match="config.toml"):
        esrl_rs.load_run(empty)
    (empty / "config.toml").write_text('agent = "sac"\n')
    with pytest.raises(FileNotFoundError, match="no metrics.jsonl or metrics.csv"):
        esrl_rs.load_run(empty)
    with pytest.raises(FileNotFoundError, match="eval.json"):
        esrl_rs.load_eval(empty)
    with pytest.raises(FileNotFoundError):
        esrl_rs.load_eval(tmp_path / "nope.json")


def test_malformed_files_raise_value_error(tmp_path: Path) -> None:
    root = write_run(tmp_path / "r", "sac", 0, [1.0, 2.0])
    (root / "metrics.jsonl").write_text('{"episode": 0, "curve": 1.0}\n{oops}\n')
    with pytest.raises(ValueError, match=r"metrics.jsonl line 2"):
        esrl_rs.load_run(root)
    (root / "metrics.jsonl").write_text('[1, 2]\n')
    with pytest.raises(ValueError, match=r"line 1: expected a JSON object, got an array"):
        esrl_rs.load_run(root)
    (root / "metrics.jsonl").write_text('{"curve": 1.0}\n')
    (root / "config.toml").write_text("agent = = 1\n")
    with pytest.raises(ValueError, match="config.toml: invalid TOML"):
        esrl_rs.load_run(root)
    (root / "eval.json").write_text('{"runs": []}')
    with pytest.raises(ValueError, match="no `episodes` key"):
        esrl_rs.load_eval(root)
    (root / "eval.json").write_text('{"episodes": [1]}')
    with pytest.raises(ValueError, match=r"episodes\[0\] is a number"):
        esrl_rs.load_eval(root)
    (root / "eval.json").write_text('{"episodes": [')
    with pytest.raises(ValueError, match="eval.json"):
        esrl_rs.load_eval(root)


def test_group_by_agent(synthetic_runs: List[Path]) -> None:
    groups = esrl_rs.group_by_agent(esrl_rs.load_runs(reversed(synthetic_runs)))
    assert list(groups) == ["sac", "es-sac"]
    assert [r.seed for r in groups["es-sac"]] == [0, 1]


def test_episode_fixture_is_json() -> None:
    json.dumps(episode(0, 1.0))
