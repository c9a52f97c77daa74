"""Figures of a study folder and of a robustness card.

- :func:`study_figures`: from ``DIR/report.json`` (``esrl study report DIR``), per arm the
  rate at the walking bar and the share of runs whose policy finishes every start, each with
  its Wilson 95 % interval, the falls per episode and the IQM of Best-Win-50, each with its
  bootstrap 95 % interval (``study_intervals.png``), and the performance profiles of
  Best-Win-50: for every score τ, the share of an arm's runs that score above it
  (``study_profiles.png``; Agarwal et al. 2021, "Deep RL at the Edge of the Statistical
  Precipice", Fig. 3, whose ``rliable`` draws the same curve with bootstrap bands).
- :func:`checks_figure`: from each run's ``checks.jsonl`` (``DIR/records/<run>/``), what the
  walking checks found during training, one panel per run: the episodes of each gait class
  stacked, the starts past the 50 m line, and the first check at the walking bar
  (``study_checks.png``): whether a seed's policy walked before it learnt to finish, and
  what it turned into. With ``check.mean``, the ES mean's checks are a dashed line of their
  own (the starts it finished), beside the stacked classes of the generations' policies.
- :func:`robustness_figure`: from an ``eval.json`` with a ``robustness`` card (``esrl eval
  POLICY --robustness``), the share of episodes that stayed up against each disturbance's
  magnitude (``robustness.png``).

``python -m esrl_rs.report --study DIR --out OUT`` and ``--robustness EVAL.json --out OUT``
draw them (needs matplotlib).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Dict, List, Sequence, Tuple, Union

import numpy as np

__all__ = ["check_series", "checks_figure", "interval_panels", "performance_profile",
           "robustness_figure", "study_figures"]

PathLike = Union[str, Path]


def performance_profile(scores: List[float], taus: np.ndarray) -> np.ndarray:
    """The share of ``scores`` strictly above each τ of ``taus`` (a performance profile)."""
    s = np.asarray(scores, dtype=float)
    return np.array([(s > t).mean() if s.size else np.nan for t in taus])


#: Gait classes in the order they are stacked, with their colours.
CLASS_COLORS = {"walk": "tab:green", "shuffle": "tab:olive", "run": "tab:blue", "hop": "tab:purple",
                "stand": "tab:gray", "fall": "tab:red"}


def check_series(checks_jsonl: PathLike) -> Dict[str, Any]:
    """The checks of one run as arrays over training: ``env_steps``, ``starts``, ``finished``,
    ``at_bar`` (bool), ``stopped`` (bool: the check stopped once the bar was out of reach,
    ``check.stop_early``, so its counts are over the starts it ran), ``mean`` (bool: a check
    of the ES mean, ``check.mean``) and ``classes`` (class → episodes per check, every class
    of any check, zero where a check had none), in the order of the file."""
    rows = [json.loads(line) for line in Path(checks_jsonl).read_text(encoding="utf-8").splitlines()
            if line.strip()]
    names = sorted({c for r in rows for c in r["classes"]},
                   key=lambda c: (list(CLASS_COLORS).index(c) if c in CLASS_COLORS else 99, c))
    return {
        "env_steps": np.array([r["env_steps"] for r in rows], dtype=float),
        "starts": np.array([r["starts"] for r in rows], dtype=float),
        "finished": np.array([r["finished"] for r in rows], dtype=float),
        "at_bar": np.array([bool(r["at_bar"]) for r in rows]),
        "stopped": np.array([bool(r.get("stopped", False)) for r in rows]),
        "mean": np.array([bool(r.get("mean", False)) for r in rows]),
        "classes": {c: np.array([r["classes"].get(c, 0) for r in rows], dtype=float) for c in names},
    }


def checks_figure(study_dir: PathLike, out: PathLike, dpi: int = 150) -> Path:
    """One panel per run of the study with a ``checks.jsonl`` (module docs); raises
    ``ValueError`` when no record has one."""
    records = Path(study_dir) / "records"
    runs = sorted((d for d in records.iterdir() if (d / "checks.jsonl").is_file()),
                  key=_run_order) if records.is_dir() else []
    if not runs:
        raise ValueError(f"{records} holds no run with a checks.jsonl (a study with a [check])")
    plt = _plt()
    cols = min(5, len(runs))
    nrows = (len(runs) + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(max(2.8 * cols, 8.0), 2.2 * nrows + 0.6),
                             squeeze=False,
                             sharey=True)
    for ax, run in zip(axes.flat, runs):
        s = check_series(run / "checks.jsonl")
        # Shares of each check's starts: a confirmed check (check.confirm_starts) has more. A
        # stopped check's shares are of the few starts it ran: it is marked, not stacked. The
        # ES mean's checks (check.mean) are a line of their own.
        full = ~s["stopped"] & ~s["mean"]
        mean = ~s["stopped"] & s["mean"]
        if mean.any():
            ax.step(s["env_steps"][mean] / 1e6,
                    s["finished"][mean] / np.maximum(s["starts"][mean], 1.0), where="post",
                    color="tab:orange", ls="--", lw=1.0, label="past 50 m, ES mean")
        x = s["env_steps"][full] / 1e6
        n = np.maximum(s["starts"][full], 1.0)
        ax.stackplot(x, *(v[full] / n for v in s["classes"].values()), step="post",
                     labels=list(s["classes"]),
                     colors=[CLASS_COLORS.get(c, "black") for c in s["classes"]], alpha=0.55)
        ax.step(x, s["finished"][full] / n, where="post", color="black", lw=1.0,
                label="past 50 m")
        if s["stopped"].any():
            xs = s["env_steps"][s["stopped"]] / 1e6
            ax.plot(xs, np.full(xs.shape, 0.02), "|", color="black", ms=4,
                    label="stopped check (below the bar)")
        if s["at_bar"].any():
            ax.axvline(s["env_steps"][np.argmax(s["at_bar"])] / 1e6, color="black", ls=":",
                       lw=1.0, label="first at the bar")
        ax.set_title(run.name, fontsize=9)
        ax.set_ylim(0, 1)
        ax.set_xlabel("env steps (M)", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(runs):]:
        ax.axis("off")
    for ax in axes[:, 0]:
        ax.set_ylabel("share of a check's starts", fontsize=8)
    handles: Dict[str, Any] = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=len(handles),
               fontsize=7, frameon=False)
    fig.suptitle("walking checks during training: shares of each check's starts by gait class "
                 "(stacked) and past the 50 m line", fontsize=9)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return _save(fig, out, "study_checks.png", dpi)


def _save(fig: Any, out: PathLike, name: str, dpi: int) -> Path:
    """Writes ``fig`` to ``out/name`` (creating ``out``), closes it, returns the path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / name
    fig.savefig(path, dpi=dpi)
    _plt().close(fig)
    return path


def _run_order(run: Path) -> Any:
    """Sorts record folders ``<arm>-s<seed>`` by arm, then by seed as a number."""
    arm, _, seed = run.name.rpartition("-s")
    return (arm, int(seed)) if seed.isdigit() else (run.name, 0)


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def interval_panels(arms: Sequence[Dict[str, Any]]) -> List[Tuple[str, str, float]]:
    """The panels of ``study_intervals.png`` for the per-arm entries of a ``report.json``:
    (key, axis label, scale) of the rate at the walking bar and the IQM of Best-Win-50, and,
    when every arm has them (reports written since they were added), the share of runs whose
    policy finished every start and the falls per episode."""
    panels = [("rate", "runs at the walking bar (%), Wilson 95 % interval", 100.0)]
    if all("finished_every_episode_rate" in a for a in arms):
        panels.append(("finished_every_episode_rate",
                       "runs that finish every start (%), Wilson 95 %", 100.0))
    if all("falls_per_episode" in a for a in arms):
        panels.append(("falls_per_episode",
                       "falls per episode (%), bootstrap 95 % over runs", 100.0))
    panels.append(("best_win_50_iqm", "IQM of Best-Win-50, bootstrap 95 % interval", 1.0))
    return panels


def study_figures(study_dir: PathLike, out: PathLike, dpi: int = 150) -> List[Path]:
    """The figures of a study folder (module docs) into ``out``, the checks figure when its
    records have checks; returns their paths. A folder without ``report.json`` raises
    ``ValueError`` that says how to write it."""
    path = Path(study_dir) / "report.json"
    if not Path(study_dir).is_dir():
        raise ValueError(f"{study_dir}: no such study folder")
    if not path.is_file():
        what = "study folder" if (Path(study_dir) / "study.toml").is_file() else "folder"
        raise ValueError(f"{study_dir}: no report.json in this {what}; `esrl study report "
                         f"{study_dir}` writes it from the records")
    report = json.loads(path.read_text(encoding="utf-8"))
    arms = report["arms"]
    runs = report["runs"]
    plt = _plt()
    files = []

    panels = interval_panels(arms)
    rows = (len(panels) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(10, rows * (0.6 * len(arms) + 1.8)),
                             squeeze=False)
    y = np.arange(len(arms))
    for ax, (key, label, scale) in zip(axes.flat, panels):
        for i, a in enumerate(arms):
            v = a[key]
            ax.errorbar(scale * v["estimate"], i,
                        xerr=[[scale * (v["estimate"] - v["lo"])],
                              [scale * (v["hi"] - v["estimate"])]],
                        fmt="o", capsize=4, color=f"C{i}")
        ax.set_yticks(y, [f"{a['arm']} ({a['at_bar']}/{a['runs']})" for a in arms])
        ax.invert_yaxis()
        ax.grid(axis="x", alpha=0.3)
        ax.set_xlabel(label)
        if key == "falls_per_episode":
            ax.set_xlim(left=-0.05 * max(100.0 * a[key]["hi"] for a in arms) - 0.05)
        elif scale == 100.0:
            ax.set_xlim(-2, 102)
    fig.tight_layout()
    files.append(_save(fig, out, "study_intervals.png", dpi))

    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    all_scores = [r["best_win_50"] for r in runs]
    taus = np.linspace(min(all_scores) - 1, max(all_scores) + 1, 200)
    for i, a in enumerate(arms):
        scores = [r["best_win_50"] for r in runs if r["arm"] == a["arm"]]
        ax.step(taus, performance_profile(scores, taus), where="post", color=f"C{i}",
                label=f"{a['arm']} ({len(scores)} runs)")
    ax.set_xlabel("Best-Win-50 τ")
    ax.set_ylabel("share of runs with score > τ")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    files.append(_save(fig, out, "study_profiles.png", dpi))
    records = Path(study_dir) / "records"
    if records.is_dir() and any((d / "checks.jsonl").is_file() for d in records.iterdir()):
        files.append(checks_figure(study_dir, out, dpi=dpi))
    return files


def robustness_figure(eval_json: Union[PathLike, Sequence[PathLike]], out: PathLike,
                      dpi: int = 150) -> Path:
    """Survival against magnitude per disturbance of an evaluation's robustness card: the
    shares that stayed up, finished and did either; given several cards (one per policy),
    their shares that finished or stayed up side by side (those that stayed up, where a card
    predates that count), one line each, labelled by the card's run."""
    paths = [eval_json] if isinstance(eval_json, (str, Path)) else list(eval_json)
    if not paths:
        raise ValueError("no robustness card given")
    cards = []
    for path in paths:
        report = json.loads(Path(path).read_text(encoding="utf-8"))
        if not report.get("robustness"):
            raise ValueError(f"{path} has no robustness card (esrl eval POLICY --robustness)")
        cards.append((report.get("run") or Path(path).parent.name, report["robustness"]))
    nominal = {"push_sagittal": 0.0, "push_lateral": 0.0, "friction": 1.0, "mass": 1.0,
               "strength": 1.0, "slope": 0.0, "obs_noise": 0.0, "delay": 0.0, "contact": 60.0}
    units = {"push_sagittal": "m/s", "push_lateral": "m/s", "friction": "coefficient",
             "mass": "scale", "strength": "scale", "slope": "degrees", "obs_noise": "SD",
             "delay": "control steps", "contact": "Hz"}

    def by_kind(rows: List[Dict[str, Any]]) -> Dict[str, List[Any]]:
        base = next((r for r in rows if r["disturbance"] is None), None)
        kinds: Dict[str, List[Any]] = {}
        for r in rows:
            d = r["disturbance"]
            if d is not None:
                kinds.setdefault(d["kind"], []).append((float(d["value"]), r))
        for kind, pts in kinds.items():
            if base is not None and kind in nominal:
                pts.append((nominal[kind], base))
            pts.sort(key=lambda p: p[0])
        return kinds

    either = all("finished_or_up" in r for _, rows in cards for r in rows)
    measure, measured = (("finished_or_up", "finished or stayed up") if either
                         else ("survived", "stayed up"))

    def share(pts: List[Any], key: str) -> List[float]:
        return [p[1][key] / p[1]["episodes"] for p in pts]

    series = [(label, by_kind(rows)) for label, rows in cards]
    names = list(dict.fromkeys(k for _, kinds in series for k in kinds))
    plt = _plt()
    n = len(names)
    cols = 4
    fig, axes = plt.subplots((n + cols - 1) // cols, cols,
                             figsize=(3.0 * cols, 2.4 * ((n + cols - 1) // cols)), squeeze=False)
    for ax, kind in zip(axes.flat, names):
        for label, kinds in series:
            pts = kinds.get(kind)
            if not pts:
                continue
            x = [p[0] for p in pts]
            if len(series) == 1:
                ax.plot(x, share(pts, "survived"), "o-", label="stayed up")
                ax.plot(x, share(pts, "finished"), "s--", label="finished")
                if either:
                    ax.plot(x, share(pts, "finished_or_up"), "^:", label="finished or stayed up")
            else:
                ax.plot(x, share(pts, measure), "o-", label=label)
        ax.set_title(kind, fontsize=9)
        ax.set_xlabel(units.get(kind, ""), fontsize=8)
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    episodes = cards[0][1][0]["episodes"]
    what = (f"{cards[0][0]}: share of {episodes} episodes" if len(cards) == 1
            else f"share of {episodes} episodes that {measured}, per policy")
    fig.suptitle(f"{what}, the undisturbed task at the nominal value", fontsize=9)
    fig.tight_layout()
    return _save(fig, out, "robustness.png", dpi)
