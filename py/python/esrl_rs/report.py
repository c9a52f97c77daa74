"""Paper Fig. 5, Table 1 and pictures of the gait from run folders.

    python -m esrl_rs.report RUN_DIR [RUN_DIR ...] --out DIR [--gif] [--episode K]
    python -m esrl_rs.report --gait RUN_DIR/best --out DIR     # gait pictures of one policy

Runs are grouped by agent (``config.toml`` key ``agent``). Writes to ``DIR``:

- ``fig5a_learning_curves.png``: learning curve per agent, mean ± SD across seeds;
- ``fig5b_q0.png``: Q0 per generation/episode, mean ± SD across seeds (needs a ``q0`` column);
- ``fig5c_lateral_deviation.png``: lateral offset y along the path x of each run's first
  evaluation episode (needs ``eval.json`` from ``esrl eval``);
- ``fig5d_power_per_actuator.png``: mean |power| per actuator, mean ± SD across seeds (needs
  ``eval.json``);
- ``fig5.png``: the four panels together;
- ``fig5a_learning_curves_env_steps.png``: the learning curves against environment steps
  instead of generations/episodes (each seed's curve averaged over 200 equal bins of env
  steps, :func:`binned_by_steps`; mean ± SD across seeds), the axis on which a comparison at
  equal env steps (``esrl compare --steps N``) is read;
- ``table1.md`` (Table 1, the per-actuator and the per-joint tables, Markdown) and
  ``table1.csv``;
- ``gait/<run>/``, for every run whose ``eval.json`` has the per-step trace of ``esrl eval``
  (:func:`render_gait`, episode ``--episode``, default 0): ``gait_diagram.png`` (left/right
  foot contact over time, as in biomechanics papers), ``joint_angles.png`` (hip, knee and
  ankle angles over time and over the gait cycle, with the joint limits),
  ``stick_filmstrip.png`` (the robot's side view every 0.3 s) and, with ``--gif``,
  ``stick.gif`` (the side view animated in real time).

A panel without data is left out with a note (printed, and listed in ``table1.md``). The
numbers come from ``esrl-metrics`` through the bindings: the per-seed summaries are computed
against each agent's own target (80% of the median Best-Win-50 over its seeds), the gait
columns from each run's ``eval.json`` (its mean over episodes, else its first episode). Colours follow the paper: ES-SAC
blue, ES-TD3 orange, ES-DDPG yellow, SAC purple, TD3 green, DDPG cyan (MATLAB's default
colour order); other agents get matplotlib's defaults.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import metrics
from ._native import EsrlError
from .gait import load_episode, render_gait
from .run import Run, group_by_agent, load_run

__all__ = [
    "AGENT_COLORS",
    "AGENT_ORDER",
    "GAIT_FIGURES",
    "Report",
    "agent_color",
    "agent_label",
    "agent_runs",
    "binned_by_steps",
    "main",
    "render_gait",
    "render_report",
]

#: The PNG files of :func:`render_gait` (``stick.gif`` comes on request).
GAIT_FIGURES: Tuple[str, ...] = ("gait_diagram.png", "joint_angles.png", "stick_filmstrip.png")

#: The paper's agent order (Table 1, Fig. 5).
AGENT_ORDER: Tuple[str, ...] = ("es-sac", "es-td3", "es-ddpg", "sac", "td3", "ddpg")

#: The paper's colours (MATLAB's default colour order, in the order of Fig. 5's legend).
AGENT_COLORS: Dict[str, Tuple[float, float, float]] = {
    "es-sac": (0.0, 0.4470, 0.7410),  # blue
    "es-td3": (0.8500, 0.3250, 0.0980),  # orange
    "es-ddpg": (0.9290, 0.6940, 0.1250),  # yellow
    "sac": (0.4940, 0.1840, 0.5560),  # purple
    "td3": (0.4660, 0.6740, 0.1880),  # green
    "ddpg": (0.3010, 0.7450, 0.9330),  # cyan
}

_LABELS = {"es-sac": "ES-SAC", "es-td3": "ES-TD3", "es-ddpg": "ES-DDPG",
           "sac": "SAC", "td3": "TD3", "ddpg": "DDPG"}


def _key(agent: str) -> str:
    return agent.strip().lower().replace("_", "-")


def agent_label(agent: str) -> str:
    """``es-sac`` → ``ES-SAC``; unknown names are kept."""
    return _LABELS.get(_key(agent), agent)


def agent_color(agent: str, fallback_index: int = 0) -> Any:
    """The paper's colour of ``agent``; matplotlib's cycle colour ``C<i>`` for others."""
    return AGENT_COLORS.get(_key(agent), f"C{fallback_index % 10}")


def _ordered(groups: Dict[str, List[Run]]) -> Dict[str, List[Run]]:
    known = sorted((a for a in groups if _key(a) in AGENT_ORDER),
                   key=lambda a: AGENT_ORDER.index(_key(a)))
    return {a: groups[a] for a in known + [a for a in groups if _key(a) not in AGENT_ORDER]}


def _q0_mean(run: Run) -> Optional[float]:
    """``summary.json``'s ``q0_mean``, or the same rule on the ``q0`` column (runs without a
    summary): ``esrl_rs.metrics.q0_mean``, one implementation with the CLI's."""
    value = run.summary.get("q0_mean")
    if isinstance(value, (int, float)) and np.isfinite(value):
        return float(value)
    q0 = run.metrics.get("q0")
    if q0 is None:
        return None
    return metrics.q0_mean(np.asarray(q0, dtype=float))


def _seed_gait(run: Run) -> Optional[Dict[str, Any]]:
    """The run's gait metrics: ``eval.json``'s mean over episodes when present (``esrl eval``
    writes it), else its first episode's."""
    ev = run.eval
    if not ev:
        return None
    mean = ev.get("mean")
    if isinstance(mean, dict):
        gait = mean.get("gait")
        if isinstance(gait, dict):
            return gait
    episodes = ev.get("episodes") or []
    gait = episodes[0].get("gait") if episodes else None
    return gait if isinstance(gait, dict) else None


def agent_runs(groups: Dict[str, List[Run]]) -> List[Dict[str, Any]]:
    """The input of the Table 1 functions of :mod:`esrl_rs.metrics`: per agent, each seed's
    curve summary (against the agent's target, by ``summarize_method``), the gait metrics of
    its evaluation (``eval.json``: the mean over episodes, else the first episode) and its
    mean Q0."""
    out = []
    for agent, runs in groups.items():
        summaries = metrics.summarize_method([r.curve for r in runs])
        seeds = [{"summary": s, "gait": _seed_gait(r), "q0_mean": _q0_mean(r)}
                 for r, s in zip(runs, summaries)]
        out.append({"agent": agent, "seeds": seeds})
    return out


def _stack(columns: Sequence[np.ndarray]) -> np.ndarray:
    """Seeds × steps, shorter seeds padded with NaN."""
    length = max(len(c) for c in columns)
    table = np.full((len(columns), length), np.nan)
    for i, c in enumerate(columns):
        table[i, : len(c)] = c
    return table


def _mean_sd(table: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    finite = np.isfinite(table)
    count = finite.sum(axis=0)
    safe = np.where(finite, table, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = safe.sum(axis=0) / count
        sq = np.where(finite, (table - mean) ** 2, 0.0).sum(axis=0)
        sd = np.sqrt(sq / (count - 1))
    mean[count == 0] = np.nan
    sd[count < 2] = np.nan
    return mean, sd


def _x_label(groups: Dict[str, List[Run]]) -> str:
    kinds = {r.is_es for runs in groups.values() for r in runs}
    if kinds == {True}:
        return "Generation"
    if kinds == {False}:
        return "Episode"
    return "Generation / episode"


def _band_plot(ax: Any, groups: Dict[str, List[Run]], column: str, ylabel: str) -> bool:
    drawn = False
    for i, (agent, runs) in enumerate(groups.items()):
        cols = [np.asarray(r.metrics[column], dtype=float) for r in runs
                if column in r.metrics]
        cols = [c for c in cols if np.isfinite(c).any()]
        if not cols:
            continue
        mean, sd = _mean_sd(_stack(cols))
        x = np.arange(1, len(mean) + 1)
        color = agent_color(agent, i)
        ax.plot(x, mean, color=color, lw=1.5, label=f"{agent_label(agent)} (n={len(cols)})")
        if np.isfinite(sd).any():
            ax.fill_between(x, mean - sd, mean + sd, color=color, alpha=0.25, lw=0)
        drawn = True
    ax.set_xlabel(_x_label(groups))
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if drawn:
        ax.legend(fontsize=8)
    return drawn


def binned_by_steps(steps: Sequence[float], values: Sequence[float],
                    edges: np.ndarray) -> np.ndarray:
    """The mean of ``values`` whose ``steps`` fall in each bin ``[edges[k], edges[k + 1])``
    (the last bin includes its right edge). A bin without a row inside the run's span takes
    the value of the bin before it (the curve as it stood); bins before the run's first row
    or after its last are NaN. Non-finite values are left out."""
    steps = np.asarray(steps, dtype=float)
    values = np.asarray(values, dtype=float)
    bins = len(edges) - 1
    k = np.searchsorted(edges, steps, side="right") - 1
    k[steps == edges[-1]] = bins - 1
    ok = (k >= 0) & (k < bins) & np.isfinite(values) & np.isfinite(steps)
    sums = np.bincount(k[ok], weights=values[ok], minlength=bins)
    counts = np.bincount(k[ok], minlength=bins)
    out = np.full(bins, np.nan)
    out[counts > 0] = sums[counts > 0] / counts[counts > 0]
    filled = np.flatnonzero(counts)
    if filled.size:
        for i in range(filled[0] + 1, filled[-1]):
            if counts[i] == 0:
                out[i] = out[i - 1]
    return out


def _panel_curves_steps(ax: Any, groups: Dict[str, List[Run]],
                        rows: List[Dict[str, Any]]) -> bool:
    ax.set_title("Learning curves against environment steps (mean ± SD)")
    runs = [r for rs in groups.values() for r in rs
            if "env_steps" in r.metrics and "curve" in r.metrics and len(r)]
    if not runs:
        return False
    top = max(float(np.nanmax(np.asarray(r.metrics["env_steps"], dtype=float))) for r in runs)
    edges = np.linspace(0.0, top, 201)
    centers = 0.5 * (edges[:-1] + edges[1:])
    drawn = False
    for i, (agent, members) in enumerate(groups.items()):
        table = [binned_by_steps(r.metrics["env_steps"], r.metrics["curve"], edges)
                 for r in members if r in runs]
        if not table:
            continue
        mean, sd = _mean_sd(np.vstack(table))
        color = agent_color(agent, i)
        ax.plot(centers, mean, color=color, lw=1.5,
                label=f"{agent_label(agent)} (n={len(table)})")
        if np.isfinite(sd).any():
            ax.fill_between(centers, mean - sd, mean + sd, color=color, alpha=0.25, lw=0)
        drawn = True
    ax.set_xlabel("Environment steps")
    ax.set_ylabel("Return (mean per bin of env steps)")
    ax.grid(True, alpha=0.3)
    if drawn:
        ax.legend(fontsize=8)
    return drawn


def _panel_curves(ax: Any, groups: Dict[str, List[Run]], rows: List[Dict[str, Any]]) -> bool:
    ax.set_title("(a) Learning curves (mean ± SD)")
    return _band_plot(ax, groups, "curve", "Return")


def _panel_q0(ax: Any, groups: Dict[str, List[Run]], rows: List[Dict[str, Any]]) -> bool:
    ax.set_title("(b) $Q_0$ per generation/episode (mean ± SD)")
    return _band_plot(ax, groups, "q0", "$Q_0$")


def _panel_lateral(ax: Any, groups: Dict[str, List[Run]], rows: List[Dict[str, Any]]) -> bool:
    ax.set_title("(c) Lateral deviation along the path")
    drawn = False
    for i, (agent, runs) in enumerate(groups.items()):
        first = True
        for r in runs:
            ev = r.eval
            if not ev or not ev.get("episodes"):
                continue
            trace = ev["episodes"][0].get("trace") or {}
            if "x" not in trace or "y" not in trace:
                continue
            ax.plot(np.asarray(trace["x"], dtype=float), np.asarray(trace["y"], dtype=float),
                    color=agent_color(agent, i), lw=1.2, alpha=0.85,
                    label=agent_label(agent) if first else None)
            first = False
            drawn = True
    if drawn:
        ax.axhline(0.0, color="0.5", ls="--", lw=1.0, label="ideal path")
        ax.legend(fontsize=8)
    ax.set_xlabel("x along the track (m)")
    ax.set_ylabel("lateral offset y (m)")
    ax.grid(True, alpha=0.3)
    return drawn


def _panel_power(ax: Any, groups: Dict[str, List[Run]], rows: List[Dict[str, Any]]) -> bool:
    ax.set_title("(d) Mean |power| per actuator (mean ± SD)")
    rows = [r for r in rows if r["actuator_names"]]
    if not rows:
        return False
    names = rows[0]["actuator_names"]
    width = 0.8 / len(rows)
    x = np.arange(len(names))
    for i, row in enumerate(rows):
        means, sds = [], []
        for name in names:
            cell = None
            if name in row["actuator_names"]:
                cell = row["mean_abs_power_per_actuator"][row["actuator_names"].index(name)]
            stat = cell["stat"] if cell else None
            means.append(stat["mean"] if stat else np.nan)
            sds.append(stat["sd"] if stat and stat["sd"] is not None else 0.0)
        agent = row["agent"]
        ax.bar(x + (i - (len(rows) - 1) / 2) * width, means, width, yerr=sds, capsize=2,
               color=agent_color(agent, list(groups).index(agent) if agent in groups else i),
               label=agent_label(agent))
    ax.set_xticks(x)
    ax.set_xticklabels([n.replace("_", "\n") for n in names], fontsize=8)
    ax.set_ylabel("mean |τ·ω| (W)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return True


_Panel = Callable[[Any, Dict[str, List[Run]], List[Dict[str, Any]]], bool]

#: (file name, panel function, why it may be missing)
_PANELS: Tuple[Tuple[str, _Panel, str], ...] = (
    ("fig5a_learning_curves.png", _panel_curves, "no run has a `curve` column"),
    ("fig5b_q0.png", _panel_q0, "no run has finite `q0` values"),
    ("fig5c_lateral_deviation.png", _panel_lateral,
     "no run has an eval.json with a trace (run `esrl eval` on the runs)"),
    ("fig5d_power_per_actuator.png", _panel_power,
     "no run has an eval.json with gait metrics (run `esrl eval` on the runs)"),
)


@dataclass
class Report:
    """What :func:`render_report` wrote."""

    out: Path
    files: List[Path] = field(default_factory=list)
    notes: List[str] = field(default_factory=list)
    agents: Dict[str, List[Path]] = field(default_factory=dict)


def _gait_dir_name(run: Run, taken: Sequence[str]) -> str:
    name = f"{run.agent}-s{run.seed}" if run.seed is not None else run.path.name
    base, k = name, 1
    while name in taken:
        k += 1
        name = f"{base}-{k}"
    return name


#: Config keys that may differ between the seeds of one agent: the seed itself, how the run
#: was executed and what it kept on disk (checkpoints, copies of ``best/``), none of which
#: changes what it learns, and the budget (a difference in budget is noted, not refused).
_FREE_KEYS = ("seed", "threads", "checkpoint_every", "best_every_steps")
_BUDGET_KEYS = ("generations", "episodes", "max_env_steps")


def _flatten(config: Dict[str, Any], prefix: str = "") -> Dict[str, Any]:
    flat: Dict[str, Any] = {}
    for key, value in config.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(_flatten(value, name + "."))
        else:
            flat[name] = value
    return flat


def config_differences(runs: Sequence[Run]) -> Tuple[List[str], List[str]]:
    """What differs between the configs of ``runs`` (seeds of one agent): the settings that
    make them different experiments, and the budget keys. Each entry reads
    ``key: value (run), value (run)``."""
    flats = [_flatten(r.config) for r in runs]
    keys = sorted(set().union(*flats)) if flats else []
    settings: List[str] = []
    budget: List[str] = []
    for key in keys:
        if key in _FREE_KEYS:
            continue
        values = [f.get(key) for f in flats]
        if all(v == values[0] for v in values):
            continue
        listed = ", ".join(f"{v!r} ({r.path.name})" for v, r in zip(values, runs))
        (budget if key in _BUDGET_KEYS else settings).append(f"{key}: {listed}")
    return settings, budget


def render_report(run_dirs: Sequence[Union[str, "os.PathLike[str]"]],
                  out: Union[str, "os.PathLike[str]"], dpi: int = 150, gait: bool = True,
                  episode: int = 0, gif: bool = False, start: float = 0.0,
                  mixed: bool = False, eval_best: bool = False) -> Report:
    """Renders Fig. 5 (a–d) and Table 1 for ``run_dirs`` into ``out`` (created if needed),
    and with ``gait`` the gait pictures (:func:`render_gait`) of episode ``episode`` of every
    run whose ``eval.json`` has the per-step trace into ``out/gait/<agent>-s<seed>/``. Raises
    the loaders' exceptions for a bad run folder and ``ValueError`` when there is nothing to
    report.

    The runs of one agent are pooled as seeds of one experiment, so their configurations
    must agree but for the seed, the threads and the budget: otherwise ``ValueError`` lists
    the differences, unless ``mixed`` (then they are pooled and the differences noted).
    Budget differences and unfinished runs are noted in ``Report.notes`` and ``table1.md``.

    With ``eval_best`` the gait columns, Fig. 5c/d and the gait pictures of ES runs come from
    their kept policy, ``RUN/best/eval.json`` (``esrl eval RUN/best`` writes it);
    plain runs keep no other policy and use ``RUN/eval.json``."""
    from matplotlib.figure import Figure  # no pyplot: no GUI backend, no global state

    if not run_dirs:
        raise ValueError("no run folders given")
    runs = [load_run(p) for p in run_dirs]
    groups = _ordered(group_by_agent(runs))
    notes: List[str] = []
    if eval_best:
        kept = [r.path.name for r in runs if r.use_best_eval()]
        notes.append("evaluations of the kept policies (best/eval.json) of "
                     + (", ".join(kept) if kept else "no run")
                     + "; the others' last checkpoints (eval.json)")
    for agent, members in groups.items():
        settings, budget = config_differences(members)
        if settings and not mixed:
            raise ValueError(
                f"the {agent_label(agent)} runs differ in configuration, so they are not seeds "
                "of one experiment: " + "; ".join(settings)
                + ". Report them separately, or pass --mixed to pool them anyway")
        if settings:
            notes.append(f"{agent_label(agent)} pools runs of different configurations: "
                         + "; ".join(settings))
        if budget:
            notes.append(f"{agent_label(agent)} pools runs of different budgets: "
                         + "; ".join(budget))
        for r in members:
            if r.summary and r.summary.get("finished") is False:
                notes.append(f"{r.path} is unfinished ({len(r)} rows so far)")
    agents = agent_runs(groups)
    rows = metrics.table1(agents)
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    report = Report(out=out_dir, agents={a: [r.path for r in rs] for a, rs in groups.items()})
    report.notes.extend(notes)
    for agent, members in groups.items():
        envs = sorted({str(r.env) for r in members})
        if len(envs) > 1:
            report.notes.append(f"{agent_label(agent)} mixes runs of different environments "
                                f"({', '.join(envs)}); its mean ± SD pools them")

    combined = Figure(figsize=(13, 9), layout="constrained")
    axes = combined.subplots(2, 2).ravel()
    for (name, panel, why), cax in zip(_PANELS, axes):
        fig = Figure(figsize=(6.5, 4.5), layout="constrained")
        ax = fig.add_subplot()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            drawn = panel(ax, groups, rows)
            panel(cax, groups, rows)
        if drawn:
            path = out_dir / name
            fig.savefig(path, dpi=dpi)
            report.files.append(path)
        else:
            report.notes.append(f"{name} skipped: {why}")
            cax.text(0.5, 0.5, f"no data:\n{why}", ha="center", va="center", wrap=True,
                     transform=cax.transAxes, fontsize=9, color="0.4")
    fig = Figure(figsize=(6.5, 4.5), layout="constrained")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        drawn = _panel_curves_steps(fig.add_subplot(), groups, rows)
    if drawn:
        path = out_dir / "fig5a_learning_curves_env_steps.png"
        fig.savefig(path, dpi=dpi)
        report.files.append(path)
    else:
        report.notes.append("fig5a_learning_curves_env_steps.png skipped: no run has "
                            "`env_steps` and `curve` columns")
    combined.suptitle("Fig. 5: " + ", ".join(agent_label(a) for a in groups))
    combined_path = out_dir / "fig5.png"
    combined.savefig(combined_path, dpi=dpi)
    report.files.append(combined_path)

    md = ["# Table 1", "",
          "Mean ± sample SD across seeds; `(k/n)`: only k of n seeds have the value; "
          "`-`: none. Episodes-to-Target is a 0-based index against each agent's own target "
          "(80% of its median Best-Win-50).", "",
          metrics.table1_markdown(agents)]
    if any(r["actuator_names"] for r in rows):
        md += ["## Mean |torque| and |power| per actuator (Fig. 5d)", "",
               metrics.actuator_markdown(agents)]
    if any(r.get("joint_names") for r in rows):
        md += ["## Range of motion (5th–95th percentile) and time within 1° of a limit", "",
               metrics.joint_markdown(agents)]
    md += ["## Runs", ""]
    for agent, runs_of in groups.items():
        for r in runs_of:
            md.append(f"- {agent_label(agent)}, seed {r.seed}: `{r.path}` ({len(r)} rows"
                      f"{', evaluated' if r.has_eval else ''})")
    if report.notes:
        md += ["", "## Notes", ""] + [f"- {n}" for n in report.notes]
    table_md = out_dir / "table1.md"
    table_md.write_text("\n".join(md) + "\n", encoding="utf-8")
    table_csv = out_dir / "table1.csv"
    table_csv.write_text(metrics.table1_csv(agents), encoding="utf-8")
    report.files += [table_md, table_csv]
    if gait:
        taken: List[str] = []
        for members in groups.values():
            for r in members:
                if not r.has_eval:
                    continue
                try:
                    load_episode(r.eval, episode)
                except ValueError as e:
                    report.notes.append(f"gait pictures of {r.path} skipped: {e}")
                    continue
                name = _gait_dir_name(r, taken)
                taken.append(name)
                report.files += render_gait(r.eval, out_dir / "gait" / name, episode=episode,
                                            dpi=min(dpi, 120), gif=gif, start=start)
        if report.notes and table_md.is_file():
            text = table_md.read_text(encoding="utf-8")
            if "## Notes" not in text:
                text += "\n## Notes\n\n"
            extra = [f"- {n}" for n in report.notes if f"- {n}" not in text]
            table_md.write_text(text + "\n".join(extra) + ("\n" if extra else ""),
                                encoding="utf-8")
    return report


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Command line entry point; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m esrl_rs.report",
        description="Paper Fig. 5 (a-d) as PNG, Table 1 as Markdown/CSV and gait pictures "
                    "(gait diagram, joint angles, side-view filmstrip) from esrl run "
                    "folders, grouped by agent.")
    parser.add_argument("runs", nargs="*", metavar="RUN_DIR", help="run folders")
    parser.add_argument("--study", metavar="DIR",
                        help="a study folder (after `esrl study report DIR`): the arms' "
                             "intervals and performance profiles")
    parser.add_argument("--robustness", metavar="EVAL_JSON", nargs="+",
                        help="an eval.json with a robustness card (`esrl eval POLICY "
                             "--robustness`): survival against each disturbance; several: "
                             "their policies side by side")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--dpi", type=int, default=150, help="PNG resolution (default 150)")
    parser.add_argument("--gait", action="append", default=[], metavar="PATH",
                        help="only the gait pictures of this run folder, RUN/best or "
                             "eval.json (repeatable), into DIR/gait/<name>/")
    parser.add_argument("--episode", type=int, default=0,
                        help="evaluation episode of the gait pictures (default 0)")
    parser.add_argument("--gif", action="store_true",
                        help="also an animated side view, stick.gif (first 10 s)")
    parser.add_argument("--start", type=float, default=0.0, metavar="S",
                        help="gait pictures from this time (s) of the episode (default 0)")
    parser.add_argument("--eval-best", action="store_true",
                        help="take ES runs' evaluations from their kept policy, "
                             "RUN/best/eval.json (`esrl eval RUN/best`), instead of "
                             "RUN/eval.json")
    parser.add_argument("--mixed", action="store_true",
                        help="pool runs of one agent even when their configurations differ "
                             "(by default that is refused, listing the differences)")
    args = parser.parse_args(argv)
    if not args.runs and not args.gait and not args.study and not args.robustness:
        parser.error("give run folders, --gait PATH, --study DIR or --robustness EVAL_JSON")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        parser.error(f"--out {args.out}: exists and is not a folder (the report is a folder "
                     "of figures and tables)")
    try:
        if args.study or args.robustness:
            from .study import robustness_figure, study_figures

            written = []
            if args.study:
                written += study_figures(args.study, args.out, dpi=args.dpi)
            if args.robustness:
                written.append(robustness_figure(args.robustness, args.out, dpi=args.dpi))
            for path in written:
                print(f"wrote {path}")
            if not args.runs and not args.gait:
                return 0
        if args.runs:
            report = render_report(args.runs, args.out, dpi=args.dpi, episode=args.episode,
                                   gif=args.gif, start=args.start, mixed=args.mixed,
                                   eval_best=args.eval_best)
        else:
            report = Report(out=Path(args.out))
        for path in args.gait:
            p = Path(path)
            name = p.parent.name + "-best" if p.name == "best" else (
                p.parent.name if p.is_file() else p.name)
            report.files += render_gait(p, Path(args.out) / "gait" / name,
                                        episode=args.episode, dpi=min(args.dpi, 120),
                                        gif=args.gif, start=args.start)
    except (EsrlError, OSError, ValueError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    for agent, paths in report.agents.items():
        print(f"{agent_label(agent)}: {len(paths)} run(s)")
    for note in report.notes:
        print(f"note: {note}")
    for path in report.files:
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
