"""`python -m esrl_rs.report`: Fig. 5 panels and Table 1 from run folders."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Callable, List

import numpy as np
import pytest

import esrl_rs
from esrl_rs import report

PNG = b"\x89PNG\r\n\x1a\n"
ALL_PANELS = ["fig5.png", "fig5a_learning_curves.png", "fig5a_learning_curves_env_steps.png",
              "fig5b_q0.png", "fig5c_lateral_deviation.png", "fig5d_power_per_actuator.png"]
CURVE_PNGS = ["fig5.png", "fig5a_learning_curves.png", "fig5a_learning_curves_env_steps.png",
              "fig5b_q0.png"]
GAIT_PNGS = ["gait_diagram.png", "joint_angles.png", "stick_filmstrip.png"]


def _files(out: Path) -> List[str]:
    return sorted(p.name for p in out.iterdir())


def _check_pngs(out: Path, names: List[str]) -> None:
    for name in names:
        data = (out / name).read_bytes()
        assert data[:8] == PNG and len(data) > 5000, name


def test_report_from_evaluated_runs(synthetic_runs: List[Path], tmp_path: Path) -> None:
    out = tmp_path / "report"
    r = report.render_report(synthetic_runs, out, dpi=60)
    assert _files(out) == sorted(ALL_PANELS + ["gait", "table1.csv", "table1.md"])
    assert r.notes == []
    _check_pngs(out, ALL_PANELS)
    # One gait folder per evaluated run, named agent-s<seed>.
    assert _files(out / "gait") == ["es-sac-s0", "es-sac-s1", "sac-s0", "sac-s1"]
    for run in ("es-sac-s0", "sac-s1"):
        assert _files(out / "gait" / run) == GAIT_PNGS
        _check_pngs(out / "gait" / run, GAIT_PNGS)
    md = (out / "table1.md").read_text(encoding="utf-8")
    # paper order: ES-SAC before SAC; both with 2 seeds
    assert md.index("| es-sac | 2 |") < md.index("| sac | 2 |")
    assert "Mean |torque| and |power| per actuator" in md
    csv = (out / "table1.csv").read_text(encoding="utf-8").splitlines()
    assert len(csv) == 3 and csv[1].startswith("es-sac,2,")
    # Table 1 comes from the Rust implementation over the same inputs
    groups = report._ordered(esrl_rs.group_by_agent(esrl_rs.load_runs(synthetic_runs)))
    assert esrl_rs.metrics.table1_markdown(report.agent_runs(groups)) in md


def test_report_cli_with_two_runs_without_eval(tmp_path: Path) -> None:
    from conftest import write_run
    runs = [write_run(tmp_path / f"td3-s{s}", "td3", s, [float(s + i) for i in range(10)],
                      q0=[0.5] * 10) for s in (0, 1)]
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "esrl_rs.report", *map(str, runs),
                           "--out", str(out), "--dpi", "60"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "TD3: 2 run(s)" in proc.stdout
    assert "fig5c_lateral_deviation.png skipped" in proc.stdout
    assert _files(out) == CURVE_PNGS + ["table1.csv", "table1.md"]
    _check_pngs(out, CURVE_PNGS)
    assert "## Notes" in (out / "table1.md").read_text(encoding="utf-8")


def test_report_from_two_cli_runs(cli_train: Callable[..., Path], tmp_path: Path) -> None:
    a = cli_train("sac", "--env", "pendulum", "--preset", "smoke", "--episodes", "60",
                  "--seed", "3")
    b = cli_train("es-sac", "--env", "pendulum", "--preset", "smoke", "--generations", "3",
                  "--seed", "1")
    out = tmp_path / "cli-report"
    r = report.render_report([a, b], out, dpi=60)
    assert set(r.agents) == {"sac", "es-sac"}
    pngs = [p.name for p in r.files if p.suffix == ".png"]
    # no eval.json from the CLI here: (a), (a) against env steps, (b) and the combined figure
    assert sorted(pngs) == CURVE_PNGS
    _check_pngs(out, pngs)
    md = (out / "table1.md").read_text(encoding="utf-8")
    assert "| es-sac | 1 |" in md and "| sac | 1 |" in md


def test_report_from_two_evaluated_cli_runs(cli_train: Callable[..., Path],
                                            cli_eval: Callable[..., dict],
                                            tmp_path: Path) -> None:
    import shutil
    runs = []
    for seed in ("0", "1"):
        run = shutil.copytree(cli_train("es-sac", "--preset", "smoke", "--seed", seed),
                              tmp_path / f"es-sac-{seed}")
        cli_eval(run, 2)
        runs.append(run)
    out = tmp_path / "walk-report"
    r = report.render_report(runs, out, dpi=60, episode=1)
    assert r.notes == []
    assert _files(out) == sorted(ALL_PANELS + ["gait", "table1.csv", "table1.md"])
    _check_pngs(out, ALL_PANELS)
    md = (out / "table1.md").read_text(encoding="utf-8")
    assert "| es-sac | 2 |" in md and "left_knee" in md
    assert "Gait (episodes)" in md and "left_knee ROM (°)" in md
    # Every new figure, from the smoke runs' own eval.json.
    for seed in ("0", "1"):
        folder = out / "gait" / f"es-sac-s{seed}"
        assert _files(folder) == GAIT_PNGS
        _check_pngs(folder, GAIT_PNGS)


def test_eval_best_reports_the_kept_policy_of_es_runs(cli_train: Callable[..., Path],
                                                      cli_eval: Callable[..., dict],
                                                      tmp_path: Path) -> None:
    import shutil
    run = shutil.copytree(cli_train("es-sac", "--preset", "smoke", "--seed", "0"),
                          tmp_path / "es-sac-s0")
    last = cli_eval(run, 1)
    kept = cli_eval(run / "best", 2)
    # Two different policies (the last RL actor, the kept individual) evaluated differently.
    assert kept["mean"]["gait"]["mean_forward_velocity"] != \
        last["mean"]["gait"]["mean_forward_velocity"]

    def velocity_cell(out: Path) -> float:
        header, row = (out / "table1.csv").read_text(encoding="utf-8").splitlines()[:2]
        return float(row.split(",")[header.split(",").index("mean_forward_velocity_mean")])

    r = report.render_report([run], tmp_path / "kept", dpi=60, eval_best=True)
    assert r.notes == ["evaluations of the kept policies (best/eval.json) of es-sac-s0; "
                       "the others' last checkpoints (eval.json)"]
    assert velocity_cell(tmp_path / "kept") == pytest.approx(
        kept["mean"]["gait"]["mean_forward_velocity"], rel=1e-12)
    report.render_report([run], tmp_path / "last", dpi=60)
    assert velocity_cell(tmp_path / "last") == pytest.approx(
        last["mean"]["gait"]["mean_forward_velocity"], rel=1e-12)
    # A run without best/ (plain agents keep none) stays on eval.json.
    one = esrl_rs.load_run(run)
    shutil.rmtree(run / "best")
    assert not one.use_best_eval() and one.eval_path == run / "eval.json"


def test_gait_pictures_of_one_run(cli_train: Callable[..., Path],
                                  cli_eval: Callable[..., dict], tmp_path: Path) -> None:
    import shutil
    from esrl_rs import gait
    run = shutil.copytree(cli_train("es-sac", "--preset", "smoke", "--seed", "0"),
                          tmp_path / "one")
    ev = cli_eval(run, 1)
    trace = ev["episodes"][0]["trace"]
    assert len(trace["contact"]) == len(trace["time"]) == len(trace["joint_angle"])
    files = gait.render_gait(run, tmp_path / "pics", dpi=60, gif=True)
    assert [f.name for f in files] == GAIT_PNGS + ["stick.gif"]
    _check_pngs(tmp_path / "pics", GAIT_PNGS)
    assert (tmp_path / "pics" / "stick.gif").read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    # The command line takes a single policy with --gait (here the run folder).
    out = tmp_path / "cli"
    proc = subprocess.run([sys.executable, "-m", "esrl_rs.report", "--gait", str(run),
                           "--out", str(out), "--dpi", "60"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert _files(out / "gait" / "one") == GAIT_PNGS
    with pytest.raises(ValueError, match="episode 3 not in eval.json"):
        gait.render_gait(run, tmp_path / "none", episode=3)


def test_binned_by_steps_averages_each_bin_and_carries_the_curve_over_empty_ones() -> None:
    edges = np.array([0.0, 25.0, 50.0, 75.0, 100.0, 125.0])
    # bins: [0, 25) holds 1 and 3; [25, 50) holds 5; [50, 75) is empty inside the run's span
    # (carries 5 over); [75, 100) holds 7 (NaN left out); [100, 125] is after the last row.
    got = report.binned_by_steps([10, 20, 35, 90, 95], [1.0, 3.0, 5.0, 7.0, np.nan], edges)
    np.testing.assert_array_equal(got[:4], [2.0, 5.0, 5.0, 7.0])
    assert np.isnan(got[4])
    # a row on the last edge belongs to the last bin; rows before the first are NaN
    got = report.binned_by_steps([125, 130], [4.0, 9.0], edges)
    assert np.isnan(got[:4]).all() and got[4] == 4.0


def test_report_bad_path(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        report.render_report([tmp_path / "missing"], tmp_path / "out")
    proc = subprocess.run([sys.executable, "-m", "esrl_rs.report", str(tmp_path / "missing"),
                           "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert "error:" in proc.stderr and "missing: no such run folder" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_colours_follow_the_paper() -> None:
    assert report.agent_color("es-sac") == (0.0, 0.4470, 0.7410)
    assert report.agent_color("ES_TD3") == (0.8500, 0.3250, 0.0980)
    assert report.agent_color("mystery", 3) == "C3"
    assert report.agent_label("es-ddpg") == "ES-DDPG"


def test_report_pools_seeds_that_differ_only_in_how_they_ran(tmp_path: Path) -> None:
    from conftest import write_run
    runs = [write_run(tmp_path / f"es-sac-s{s}", "es-sac", s, [float(s + i) for i in range(10)],
                      es=True) for s in (0, 1, 2)]
    # seed 1 kept copies of best/ every 1 M steps and checkpointed more often, seed 2 ran on
    # 4 threads: what they learn is the same experiment's
    cfg = runs[1] / "config.toml"
    cfg.write_text("best_every_steps = 1000000\ncheckpoint_every = 5\n"
                   + cfg.read_text(encoding="utf-8"), encoding="utf-8")
    cfg = runs[2] / "config.toml"
    cfg.write_text("threads = 4\n" + cfg.read_text(encoding="utf-8"), encoding="utf-8")
    rep = report.render_report(runs, tmp_path / "out", dpi=60, gait=False)
    assert not [n for n in rep.notes if "pools" in n], rep.notes
    assert report.config_differences([esrl_rs.load_run(r) for r in runs]) == ([], [])


def test_report_refuses_to_pool_different_configurations(tmp_path: Path) -> None:
    from conftest import write_run
    runs = [write_run(tmp_path / f"td3-s{s}", "td3", s, [float(s + i) for i in range(10)])
            for s in (0, 1)]
    cfg = runs[1] / "config.toml"
    cfg.write_text(cfg.read_text(encoding="utf-8").replace("sigma = 0.25", "sigma = 0.01")
                   .replace('preset = "smoke"', 'preset = "quick"'), encoding="utf-8")
    summary = json.loads((runs[1] / "summary.json").read_text(encoding="utf-8"))
    summary["finished"] = False
    (runs[1] / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    args = [sys.executable, "-m", "esrl_rs.report", *map(str, runs), "--out",
            str(tmp_path / "out"), "--dpi", "60"]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    assert "differ in configuration" in proc.stderr, proc.stderr
    assert "es.sigma: 0.25 (td3-s0), 0.01 (td3-s1)" in proc.stderr, proc.stderr
    assert "preset" in proc.stderr
    proc = subprocess.run(args + ["--mixed"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "pools runs of different configurations" in proc.stdout
    assert "td3-s1 is unfinished" in proc.stdout


def test_study_and_robustness_figures(tmp_path) -> None:
    """The study figures from a report.json and the robustness figure from a card."""
    pytest.importorskip("matplotlib")
    from esrl_rs.study import (check_series, checks_figure, interval_panels,
                               performance_profile, robustness_figure, study_figures)

    np.testing.assert_array_equal(performance_profile([1.0, 2.0, 3.0], np.array([0.0, 1.5, 3.0])),
                                  [1.0, 2 / 3, 0.0])
    study = tmp_path / "study"
    study.mkdir()
    with pytest.raises(ValueError, match="no report.json in this folder; `esrl study report"):
        study_figures(study, tmp_path / "out")
    with pytest.raises(ValueError, match="none: no such study folder"):
        study_figures(tmp_path / "none", tmp_path / "out")
    interval = {"estimate": 0.5, "lo": 0.2, "hi": 0.8}
    (study / "report.json").write_text(json.dumps({
        "arms": [{"arm": "a", "runs": 2, "at_bar": 1, "rate": interval,
                  "best_win_50_iqm": {"estimate": 10.0, "lo": 5.0, "hi": 12.0}}],
        "runs": [{"arm": "a", "best_win_50": 8.0}, {"arm": "a", "best_win_50": 12.0}],
    }))
    files = study_figures(study, tmp_path / "out", dpi=40)
    assert [f.name for f in files] == ["study_intervals.png", "study_profiles.png"]
    # A report written before the reliability columns: two panels; with them, four.
    arm = json.loads((study / "report.json").read_text())["arms"][0]
    assert [p[0] for p in interval_panels([arm])] == ["rate", "best_win_50_iqm"]
    arm.update(finished_every_episode=1, finished_every_episode_rate=interval,
               falls_per_episode={"estimate": 0.02, "lo": 0.0, "hi": 0.05})
    assert [p[0] for p in interval_panels([arm])] == [
        "rate", "finished_every_episode_rate", "falls_per_episode", "best_win_50_iqm"]
    (study / "report.json").write_text(json.dumps({
        "arms": [arm], "runs": [{"arm": "a", "best_win_50": 8.0}]}))
    assert study_figures(study, tmp_path / "four", dpi=40)[0].is_file()
    with pytest.raises(ValueError, match="no run with a checks.jsonl"):
        checks_figure(study, tmp_path / "out")
    # Two checks of one run: the classes of both, zero where a check had none.
    run = study / "records" / "a-s1"
    run.mkdir(parents=True)
    check = {"starts": 4, "at_bar": False}
    (run / "checks.jsonl").write_text("\n".join(json.dumps(c) for c in [
        {**check, "env_steps": 1000, "finished": 0, "classes": {"fall": 3, "walk": 1}},
        {**check, "env_steps": 3000, "starts": 1, "finished": 0, "stopped": True,
         "classes": {"walk": 1}},
        {**check, "env_steps": 5000, "finished": 4, "at_bar": True,
         "classes": {"walk": 3, "shuffle": 1}}]) + "\n")
    s = check_series(run / "checks.jsonl")
    np.testing.assert_array_equal(s["env_steps"], [1000, 3000, 5000])
    np.testing.assert_array_equal(s["finished"], [0, 0, 4])
    np.testing.assert_array_equal(s["at_bar"], [False, False, True])
    np.testing.assert_array_equal(s["stopped"], [False, True, False])
    np.testing.assert_array_equal(s["mean"], [False, False, False])
    assert list(s["classes"]) == ["walk", "shuffle", "fall"]
    np.testing.assert_array_equal(s["classes"]["shuffle"], [0, 0, 1])
    np.testing.assert_array_equal(s["classes"]["fall"], [3, 0, 0])
    files = study_figures(study, tmp_path / "out", dpi=40)
    assert [f.name for f in files] == ["study_intervals.png", "study_profiles.png",
                                       "study_checks.png"]
    # A run with check.mean: the ES mean's check beside each generation's, marked.
    with (run / "checks.jsonl").open("a") as f:
        f.write(json.dumps({**check, "env_steps": 7000, "finished": 2, "mean": True,
                            "classes": {"walk": 4}}) + "\n")
    s = check_series(run / "checks.jsonl")
    np.testing.assert_array_equal(s["mean"], [False, False, False, True])
    np.testing.assert_array_equal(s["classes"]["walk"], [1, 1, 3, 4])
    assert checks_figure(study, tmp_path / "mean", dpi=40).is_file()
    card = tmp_path / "eval.json"
    row = {"episodes": 4, "survived": 2, "finished": 1, "speed": 1.0, "classes": {}}
    (card).write_text(json.dumps({"run": "r", "robustness": [
        {**row, "disturbance": None},
        {**row, "disturbance": {"kind": "friction", "value": 0.4}},
        {**row, "disturbance": {"kind": "delay", "value": 1}}]}))
    assert robustness_figure(card, tmp_path / "out", dpi=40).is_file()
    # Two cards: one line per policy; a card without a robustness section is named.
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"run": "s", "robustness": [
        {**row, "disturbance": None}, {**row, "disturbance": {"kind": "contact", "value": 20}}]}))
    assert robustness_figure([card, other], tmp_path / "both", dpi=40).is_file()
    # Cards that count the episodes that finished or stayed up are drawn by that count.
    row["finished_or_up"] = 3
    other.write_text(json.dumps({"run": "s", "robustness": [
        {**row, "disturbance": None}, {**row, "disturbance": {"kind": "slope", "value": -5}}]}))
    assert robustness_figure(other, tmp_path / "either", dpi=40).is_file()
    assert robustness_figure([card, other], tmp_path / "mixed", dpi=40).is_file()
    with pytest.raises(ValueError, match="plain.json has no robustness card"):
        (tmp_path / "plain.json").write_text(json.dumps({"run": "r"}))
        robustness_figure([card, tmp_path / "plain.json"], tmp_path / "both")
    (tmp_path / "plain.json").write_text(json.dumps({"run": "r"}))
    with pytest.raises(ValueError, match="no robustness card"):
        robustness_figure(tmp_path / "plain.json", tmp_path / "out")


def test_an_out_that_is_a_file_is_refused_by_name(tmp_path: Path) -> None:
    # It used to end with "[Errno 17] File exists".
    taken = tmp_path / "taken.txt"
    taken.write_text("keep me")
    with pytest.raises(SystemExit) as e:
        report.main([str(tmp_path), "--out", str(taken)])
    assert e.value.code == 2
    assert taken.read_text() == "keep me"
