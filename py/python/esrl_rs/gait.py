"""Pictures of one evaluated episode's gait, from the per-step trace ``esrl eval`` writes to
``eval.json``:

- :func:`gait_diagram`: left and right foot contact as bars over time (the "gait diagram" of
  biomechanics papers; Alexander 1984), flight shaded, with the gait metrics in the title;
- :func:`joint_angle_cycles`: hip, knee and ankle angles over time and over the gait cycle
  (each stride of a foot, from its touchdown to its next, rescaled to 0–100 %), with the joint
  limits;
- :func:`stick_filmstrip`: the robot's side view (every collision primitive projected on the
  x–z plane) every ``interval`` seconds (default 0.3), one panel per frame, following the
  robot;
- :func:`stick_animation`: the side view as an animated GIF (needs Pillow, which matplotlib
  depends on).

:func:`render_gait` writes all of them for one run folder, ``RUN/best`` or ``eval.json``.
The touchdowns come from :func:`esrl_rs.metrics.gait_phases` on the trace's contact flags, so
the pictures and the numbers use the same events. Figures are built without pyplot (no GUI
backend, no global state).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native, metrics

__all__ = [
    "gait_diagram",
    "joint_angle_cycles",
    "load_episode",
    "render_gait",
    "stick_animation",
    "stick_filmstrip",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Colours of the left and right side (matplotlib's first two cycle colours).
SIDE_COLORS = {"left": "C0", "right": "C3"}
_BODY = "0.25"


def load_episode(source: Union[PathLike, Dict[str, Any]], episode: int = 0) -> Dict[str, Any]:
    """Episode ``episode`` of an ``eval.json`` (a run folder, ``RUN/best``, the file itself, or
    a dict already loaded with :func:`esrl_rs.load_eval`), with ``"label"`` added. Raises
    ``ValueError`` when the episode has no gait trace (a pendulum run, or an ``eval.json``
    written before the gait-cycle metrics: run ``esrl eval`` again)."""
    if isinstance(source, dict):
        ev, label = source, str(source.get("run", "eval"))
    else:
        path = Path(source)
        ev = _native.load_eval(os.fspath(path))
        label = path.name if path.is_dir() else path.parent.name
        if label == "best":
            label = f"{path.parent.name if path.is_dir() else path.parent.parent.name}/best"
    episodes = ev.get("episodes") or []
    if not 0 <= episode < len(episodes):
        raise ValueError(f"{label}: episode {episode} not in eval.json "
                         f"({len(episodes)} episode(s))")
    ep = dict(episodes[episode])
    trace = ep.get("trace") or {}
    if len(trace.get("contact", [])) == 0 or len(trace.get("joint_angle", [])) == 0:
        raise ValueError(f"{label}: episode {episode} has no contact/joint-angle trace; "
                         "evaluate it again with this version of `esrl eval`")
    ep["label"] = f"{ev.get('agent', '?')} {label}, episode {episode} (reset seed "\
                  f"{ep.get('seed', '?')})"
    return ep


def _contact(trace: Dict[str, Any]) -> np.ndarray:
    return np.asarray(trace["contact"], dtype=float).reshape(-1, 2) > 0.5


def _dt(trace: Dict[str, Any]) -> float:
    time = np.asarray(trace["time"], dtype=float)
    return float(time[-1] / len(time))


def _runs(mask: np.ndarray) -> List[Tuple[int, int]]:
    """(start, length) of each run of True samples."""
    padded = np.concatenate(([False], mask, [False])).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b - a)) for a, b in zip(edges[::2], edges[1::2])]


def _cycle_text(ep: Dict[str, Any]) -> str:
    c = (ep.get("gait") or {}).get("cycle") or {}
    if not c:
        return ""

    def pct(key: str) -> str:
        return f"{100 * c[key]:.0f} %"

    parts = [f"gait: {c.get('gait_class', '?')}",
             f"double support {pct('double_support')}", f"single {pct('single_support')}",
             f"flight {pct('flight')}"]
    if c.get("alternation") is not None:
        parts.append(f"alternation {c['alternation']:.2f}")
    parts.append(f"cadence {c['cadence']:.0f}/min")
    if c.get("step_length_mean") is not None:
        parts.append(f"step {c['step_length_mean']:.2f} m")
    return ", ".join(parts)


def _span(n: int, dt: float, window: Optional[float], start: float) -> Tuple[int, int]:
    """Sample range [i0, i1) of the time window ``start`` .. ``start + window``."""
    i0 = min(max(0, int(round(start / dt))), n - 1)
    i1 = n if window is None else min(n, i0 + max(1, int(round(window / dt))))
    return i0, i1


def gait_diagram(ep: Dict[str, Any], ax: Any = None, window: Optional[float] = 10.0,
                 start: float = 0.0) -> Any:
    """Left/right contact bars over ``window`` seconds from ``start`` (all of it for
    ``window=None``); flight (no foot down) shaded. Returns the figure."""
    from matplotlib.figure import Figure

    trace = ep["trace"]
    contact = _contact(trace)
    dt = _dt(trace)
    i0, i1 = _span(len(contact), dt, window, start)
    fig = None
    if ax is None:
        fig = Figure(figsize=(10, 2.8), layout="constrained")
        ax = fig.add_subplot()
    # Sample i is the state after step i + 1, held over ((i)·dt, (i + 1)·dt].
    for row, (side, col) in enumerate((("left", 0), ("right", 1))):
        bars = [((i0 + a) * dt, k * dt) for a, k in _runs(contact[i0:i1, col])]
        ax.broken_barh(bars, (1 - row - 0.35, 0.7), facecolors=SIDE_COLORS[side])
    flight = [((i0 + a) * dt, k * dt) for a, k in _runs(~contact[i0:i1].any(axis=1))]
    ax.broken_barh(flight, (-0.5, 2.0), facecolors="0.85", zorder=0, label="flight")
    ax.set_yticks([1, 0])
    ax.set_yticklabels(["left", "right"])
    ax.set_ylim(-0.5, 1.5)
    ax.set_xlim(i0 * dt, i1 * dt)
    ax.set_xlabel("time since reset (s)")
    ends = " (fell)" if (ep.get("gait") or {}).get("fell") else ""
    ax.set_title(f"Gait diagram: {ep.get('label', '')}{ends}\n{_cycle_text(ep)}", fontsize=9)
    if flight:
        ax.legend(loc="upper right", fontsize=8)
    return fig if fig is not None else ax.figure


def _joint_rows(names: Sequence[str]) -> List[Tuple[str, Dict[str, int]]]:
    """Joints grouped by kind (``hip``, ``knee``, …) with the column of each side."""
    rows: Dict[str, Dict[str, int]] = {}
    for j, name in enumerate(names):
        side = next((s for s in ("left", "right") if s in name), "")
        kind = name.replace(f"{side}_", "").replace(f"_{side}", "") if side else name
        rows.setdefault(kind, {})[side or name] = j
    return list(rows.items())


def joint_angle_cycles(ep: Dict[str, Any], window: Optional[float] = 10.0,
                       start: float = 0.0, thin: int = 20) -> Any:
    """Per joint kind (hip, knee, ankle): the angle over ``window`` seconds from ``start``
    (left), and over the gait cycle of its own foot (right): the mean over every stride of
    the episode thick, the first ``thin`` strides from ``start`` on thin; dashed lines at the
    joint limits. Returns the figure."""
    from matplotlib.figure import Figure

    trace = ep["trace"]
    names = list(trace["joint_names"])
    q = np.degrees(np.asarray(trace["joint_angle"], dtype=float).reshape(-1, len(names)))
    limits = trace.get("joint_limits")
    dt = _dt(trace)
    t = np.asarray(trace["time"], dtype=float)
    contact = _contact(trace)
    phases = metrics.gait_phases(contact[:, 0], contact[:, 1], dt)
    # Touchdown sample indices per side (time = (i + 1)·dt).
    downs = {side: np.rint(np.asarray(phases["touchdown_times"][k]) / dt).astype(int) - 1
             for k, side in enumerate(("left", "right"))}
    i0, i1 = _span(len(t), dt, window, start)
    rows = _joint_rows(names)
    fig = Figure(figsize=(11, 2.4 * len(rows) + 0.6), layout="constrained")
    axes = np.asarray(fig.subplots(len(rows), 2, squeeze=False))
    grid = np.linspace(0.0, 100.0, 101)
    for (kind, sides), (ax_t, ax_c) in zip(rows, axes):
        strides_drawn = False
        for side, j in sides.items():
            color = SIDE_COLORS.get(side, _BODY)
            ax_t.plot(t[i0:i1], q[i0:i1, j], color=color, lw=1.1, label=side)
            d = downs.get(side, np.array([], dtype=int))
            curves = []
            drawn = 0
            for a, b in zip(d[:-1], d[1:]):
                if b - a < 2:
                    continue
                x = np.linspace(0.0, 100.0, b - a + 1)
                curves.append(np.interp(grid, x, q[a:b + 1, j]))
                if a >= i0 and drawn < thin:
                    ax_c.plot(grid, curves[-1], color=color, lw=0.5, alpha=0.3)
                    drawn += 1
            if curves:
                ax_c.plot(grid, np.mean(curves, axis=0), color=color, lw=2.0,
                          label=f"{side} (mean of {len(curves)} strides)")
                strides_drawn = True
            if limits is not None and j < len(limits) and limits[j] is not None:
                for lim in np.degrees(np.asarray(limits[j], dtype=float)):
                    for ax in (ax_t, ax_c):
                        ax.axhline(lim, color="0.5", ls="--", lw=0.8)
        ax_t.set_ylabel(f"{kind} (°)")
        ax_t.grid(True, alpha=0.3)
        ax_t.legend(fontsize=7, loc="upper right")
        ax_c.grid(True, alpha=0.3)
        if strides_drawn:
            ax_c.legend(fontsize=7, loc="upper right")
        else:
            ax_c.text(0.5, 0.5, "fewer than two touchdowns of a foot:\nno complete stride",
                      ha="center", va="center", transform=ax_c.transAxes, color="0.4",
                      fontsize=8)
    axes[-1][0].set_xlabel("time since reset (s)")
    axes[-1][1].set_xlabel("gait cycle (% of the stride, from touchdown to touchdown)")
    axes[0][0].set_title("over time (dashed: joint limits)", fontsize=9)
    axes[0][1].set_title("over the gait cycle of the same side's foot", fontsize=9)
    fig.suptitle(f"Joint angles: {ep.get('label', '')}", fontsize=10)
    return fig


def _side_color(link: str) -> str:
    for side, color in SIDE_COLORS.items():
        if side in link:
            return color
    return _BODY


def _draw_stick(ax: Any, parts: Sequence[Dict[str, Any]], frame: Sequence[Any]) -> Tuple[
        float, float]:
    """Draws one frame; returns its x extent (min, max)."""
    from matplotlib.patches import Circle, Polygon

    xs: List[float] = []
    # Right-side parts first and lighter: they are behind the left ones from this side.
    order = sorted(range(len(parts)), key=lambda k: 0 if "right" in parts[k]["link"] else 1)
    for k in order:
        part, c = parts[k], np.asarray(frame[k], dtype=float)
        color = _side_color(part["link"])
        alpha = 0.6 if "right" in part["link"] else 1.0
        kind = part["kind"]
        if kind == "line":
            width = max(1.5, 40.0 * float(part.get("radius", 0.03)))
            ax.plot(c[[0, 2]], c[[1, 3]], color=color, lw=width, alpha=alpha,
                    solid_capstyle="round")
            xs += [c[0], c[2]]
        elif kind == "box":
            ax.add_patch(Polygon(c.reshape(4, 2), closed=True, facecolor=color,
                                 edgecolor=color, alpha=0.5 * alpha))
            xs += list(c[0::2])
        elif kind == "circle":
            r = float(part.get("radius", 0.1))
            ax.add_patch(Circle((c[0], c[1]), r, facecolor=color, edgecolor=color,
                                alpha=0.6 * alpha))
            xs += [c[0] - r, c[0] + r]
    return (min(xs), max(xs)) if xs else (0.0, 0.0)


def _stick(ep: Dict[str, Any]) -> Dict[str, Any]:
    stick = ep["trace"].get("stick")
    if not stick or len(stick.get("frames", [])) == 0:
        raise ValueError(f"{ep.get('label', 'episode')}: no side view (stick) frames in the "
                         "trace; evaluate it again with this version of `esrl eval`")
    return stick


def stick_filmstrip(ep: Dict[str, Any], interval: float = 0.3, frames: int = 12,
                    start: float = 0.0) -> Any:
    """The side view every ``interval`` seconds (0.2–0.5 s reads well; rounded to a multiple
    of the trace's 0.1 s frames) from ``start``, ``frames`` panels, each centred on the robot
    with the same scale (1 m grid). Returns the figure."""
    from matplotlib.figure import Figure

    stick = _stick(ep)
    times = np.asarray(stick["time"], dtype=float)
    step = float(stick["interval"])
    interval = step * max(1, int(np.floor(interval / step + 0.5)))
    wanted = start + interval * np.arange(max(1, frames))
    picks: List[int] = []
    for w in wanted:
        k = int(np.argmin(np.abs(times - w)))
        if abs(times[k] - w) <= 0.51 * step and k not in picks:
            picks.append(k)
    if not picks:
        picks = [0]
    cols = min(len(picks), 6)
    rows = (len(picks) + cols - 1) // cols
    fig = Figure(figsize=(1.9 * cols, 3.3 * rows + 0.5), layout="constrained")
    axes = np.asarray(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, k in zip(axes, picks):
        lo, hi = _draw_stick(ax, stick["parts"], stick["frames"][k])
        centre = 0.5 * (lo + hi)
        ax.axhline(0.0, color="0.3", lw=1.0)
        ax.set_xlim(centre - 0.6, centre + 0.6)
        ax.set_ylim(-0.05, 1.9)
        ax.set_aspect("equal")
        ax.set_xticks(np.arange(np.ceil(centre - 0.6), centre + 0.6, 1.0))
        ax.tick_params(labelsize=7)
        ax.set_title(f"t = {times[k]:.2f} s\nx = {centre:.2f} m", fontsize=8)
        ax.grid(True, alpha=0.2)
    for ax in axes[len(picks):]:
        ax.set_axis_off()
    fig.suptitle(f"Side view every {interval:g} s (x forward, z up; left side blue, right "
                 f"red): {ep.get('label', '')}\n{_cycle_text(ep)}", fontsize=9)
    return fig


def stick_animation(ep: Dict[str, Any], path: PathLike, seconds: Optional[float] = 10.0,
                    dpi: int = 80, start: float = 0.0) -> Path:
    """Writes the side view as an animated GIF at the trace's frame rate (real time),
    ``seconds`` from ``start`` (to the end for ``None``), the camera following the robot.
    Returns the path."""
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    stick = _stick(ep)
    times = np.asarray(stick["time"], dtype=float)
    end = np.inf if seconds is None else start + seconds + 1e-9
    shown = np.flatnonzero((times >= start - 1e-9) & (times <= end))
    if shown.size == 0:
        shown = np.array([0])
    fig = Figure(figsize=(4.0, 3.2))
    ax = fig.add_subplot()

    def draw(i: int) -> List[Any]:
        k = int(shown[i])
        ax.clear()
        lo, hi = _draw_stick(ax, stick["parts"], stick["frames"][k])
        centre = 0.5 * (lo + hi)
        ax.axhline(0.0, color="0.3", lw=1.0)
        ax.set_xlim(centre - 1.2, centre + 1.2)
        ax.set_ylim(-0.05, 1.9)
        ax.set_aspect("equal")
        ax.set_title(f"t = {times[k]:.1f} s, x = {centre:.2f} m", fontsize=9)
        ax.tick_params(labelsize=7)
        return []

    anim = FuncAnimation(fig, draw, frames=len(shown), blit=False)
    out = Path(path)
    fps = max(1, int(round(1.0 / float(stick["interval"]))))
    anim.save(os.fspath(out), writer=PillowWriter(fps=fps), dpi=dpi)
    return out


def render_gait(source: Union[PathLike, Dict[str, Any]], out: PathLike, episode: int = 0,
                dpi: int = 120, gif: bool = False, window: Optional[float] = 10.0,
                interval: float = 0.3, frames: int = 12, start: float = 0.0) -> List[Path]:
    """Writes :data:`esrl_rs.report.GAIT_FIGURES` (and ``stick.gif`` with ``gif``) for episode
    ``episode`` of a run folder, ``RUN/best``, an ``eval.json`` or a loaded eval dict into
    ``out`` (created if needed): the gait diagram and the joint angles over ``window`` seconds
    from ``start``, the filmstrip's ``frames`` every ``interval`` seconds from ``start``.
    Returns the files written."""
    ep = load_episode(source, episode)
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in (("gait_diagram.png", gait_diagram(ep, window=window, start=start)),
                      ("joint_angles.png", joint_angle_cycles(ep, window=window, start=start)),
                      ("stick_filmstrip.png", stick_filmstrip(ep, interval, frames, start))):
        path = out_dir / name
        fig.savefig(path, dpi=dpi)
        written.append(path)
    if gif:
        written.append(stick_animation(ep, out_dir / "stick.gif", start=start))
    return written
