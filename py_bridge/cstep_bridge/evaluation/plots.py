"""Figures of training and evaluation (matplotlib, written as PNG without a display)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display needed, none opened
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle

from ..training.training_log import read_monitor
from .comparison import Interval

Rect = tuple[float, float, float, float]  # x0, y0, x1, y1


def _smooth(values: np.ndarray, window: int) -> np.ndarray:
    window = max(1, min(window, len(values)))
    kernel = np.ones(window) / window
    return np.convolve(values, kernel, mode="valid")


SEED_WINDOW = 100
"""Episodes in the moving average of a seed's training success in :func:`training_curves`."""


def _band(ax, x: np.ndarray, curves: np.ndarray, color: str, label: str) -> None:
    """The mean of ``curves`` (seeds × points) as a line and their range as a band."""
    ax.plot(x, curves.mean(axis=0), color=color, label=label)
    if len(curves) > 1:
        ax.fill_between(x, curves.min(axis=0), curves.max(axis=0), color=color, alpha=0.2)


def training_curves(
    agents: Mapping[str, Sequence[tuple[np.ndarray | None, np.ndarray | None]]],
    png: Path,
    title: str = "",
) -> None:
    """Training across seeds, per agent: its seeds' training success rate (moving average of
    :data:`SEED_WINDOW` episodes, :func:`~cstep_bridge.training.training_log.read_monitor`'s rows) and
    validation success rate (``validation.csv`` rows) over training steps — the mean over seeds as
    a line, their range as a band. Each agent maps to one (episodes, validations) pair per seed;
    either may be None where a seed lacks it."""
    fig, (ax_t, ax_v) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for k, (label, seeds) in enumerate(agents.items()):
        color = f"C{k}"
        runs = [e for e, _ in seeds if e is not None and len(e) >= SEED_WINDOW]
        if runs:
            grid = np.linspace(runs[0][SEED_WINDOW - 1, 0], min(e[-1, 0] for e in runs), 200)
            curves = np.array(
                [
                    np.interp(grid, e[SEED_WINDOW - 1 :, 0], 100 * _smooth(e[:, 2], SEED_WINDOW))
                    for e in runs
                ]
            )
            _band(ax_t, grid, curves, color, f"{label} ({len(runs)} seeds)")
        vals = [v for _, v in seeds if v is not None and len(v)]
        if vals:
            steps = sorted(set.intersection(*(set(v[:, 0]) for v in vals)))
            curves = np.array([[100 * v[v[:, 0] == s, 1][0] for s in steps] for v in vals]).reshape(
                len(vals), len(steps)
            )
            _band(ax_v, np.array(steps), curves, color, f"{label} ({len(vals)} seeds)")
    for ax, what in (
        (ax_t, f"training success (%, last {SEED_WINDOW} episodes)"),
        (ax_v, "validation success (%)"),
    ):
        ax.set_ylabel(what)
        ax.set_ylim(-5, 105)
        if ax.lines:
            ax.legend(loc="upper left", fontsize=8)
        else:
            ax.text(0.5, 0.5, "no data", ha="center", transform=ax.transAxes)
    ax_v.set_xlabel("training steps")
    fig.suptitle(title or "training across seeds (line: mean, band: range)")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def training_curve(monitor_dir: Path, png: Path, title: str = "") -> None:
    """Episode reward and success rate over training steps (moving averages of 20 episodes)."""
    data = read_monitor(monitor_dir)
    fig, (ax_r, ax_s) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    if len(data):
        window = min(20, len(data))
        steps = data[window - 1 :, 0]
        ax_r.plot(data[:, 0], data[:, 1], ".", color="0.75", ms=3, label="episode")
        ax_r.plot(steps, _smooth(data[:, 1], window), color="C0", label=f"mean of {window}")
        ax_s.plot(steps, 100 * _smooth(data[:, 2], window), color="C2")
        ax_r.legend(loc="upper left")
    else:
        ax_r.text(0.5, 0.5, "no episode finished yet", ha="center", transform=ax_r.transAxes)
    ax_r.set_ylabel("episode reward")
    ax_s.set_ylabel("success rate (%)")
    ax_s.set_xlabel("training steps")
    ax_s.set_ylim(-5, 105)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


@dataclass
class Path2D:
    """One flown path to draw: positions, and whether it ended in a collision."""

    label: str
    xy: np.ndarray
    collision: bool


@dataclass
class MapPanel:
    """One map (bounds and obstacle rectangles) with paths flown over it."""

    title: str
    bounds: Rect
    obstacles: Sequence[Rect]
    paths: list[Path2D] = field(default_factory=list)
    starts: list[np.ndarray] = field(default_factory=list)
    goals: list[np.ndarray] = field(default_factory=list)


def paths_figure(panels: Sequence[MapPanel], labels: Sequence[str], png: Path, cols: int = 3):
    """Top-down maps with each agent's paths in its own colour (× marks a collision)."""
    colours = {label: f"C{i}" for i, label in enumerate(labels)}
    cols = min(cols, len(panels))
    rows = -(-len(panels) // cols)
    x0, y0, x1, y1 = panels[0].bounds
    aspect = (y1 - y0) / (x1 - x0)
    fig, axes = plt.subplots(
        rows, cols, figsize=(4.2 * cols, 4.2 * cols * aspect * rows / cols + 1)
    )
    for ax, panel in zip(np.ravel(axes), panels, strict=False):
        bx0, by0, bx1, by1 = panel.bounds
        ax.add_patch(Rectangle((bx0, by0), bx1 - bx0, by1 - by0, fill=False, lw=2, color="k"))
        for ox0, oy0, ox1, oy1 in panel.obstacles:
            ax.add_patch(Rectangle((ox0, oy0), ox1 - ox0, oy1 - oy0, color="#b04a35"))
        for s in panel.starts:
            ax.plot(*s[:2], "s", color="gold", ms=9, mec="k")
        for g in panel.goals:
            ax.plot(*g[:2], "*", color="limegreen", ms=14, mec="k")
        for path in panel.paths:
            c = colours[path.label]
            ax.plot(path.xy[:, 0], path.xy[:, 1], color=c, lw=1.3, alpha=0.85)
            if path.collision and len(path.xy):
                ax.plot(*path.xy[-1], "x", color=c, ms=10, mew=2.5)
        ax.set_title(panel.title, fontsize=9)
        ax.set_xlim(bx0 - 0.1, bx1 + 0.1)
        ax.set_ylim(by0 - 0.1, by1 + 0.1)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
    for ax in np.ravel(axes)[len(panels) :]:
        ax.axis("off")
    handles = [plt.Line2D([], [], color=colours[lb], lw=2, label=lb) for lb in labels]
    handles.append(plt.Line2D([], [], color="k", marker="x", ls="", label="collision"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=9)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(png, dpi=120)
    plt.close(fig)


def threshold_figure(
    thresholds: Sequence[float],
    seconds: Mapping[str, Sequence[Interval]],
    png: Path,
    title: str = "",
) -> None:
    """Mean time per episode within a distance of an obstacle, per agent, against the distance
    (the paper's Figure "average time spent under different distance thresholds"), with each
    mean's confidence interval as a band."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for i, (label, values) in enumerate(seconds.items()):
        mean, low, high = (
            np.array([getattr(v, k) for v in values]) for k in ("mean", "low", "high")
        )
        ax.plot(thresholds, mean, marker="o", ms=3, color=f"C{i}", label=label)
        ax.fill_between(thresholds, low, high, color=f"C{i}", alpha=0.2, lw=0)
    ax.set_xlabel("distance to the nearest obstacle below (m)")
    ax.set_ylabel("mean time per episode (s)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def seed_figure(
    scores: Mapping[str, Mapping[str, Sequence[float]]],
    means: Mapping[str, Mapping[str, Interval]],
    panels: Mapping[str, str],
    png: Path,
    title: str = "",
) -> None:
    """Per agent, every training seed's score as a dot and the mean over seeds with its interval
    as a bar; one panel per score (``panels``: score name → axis label). ``scores`` and ``means``
    are by agent, then by score name."""
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 3.6), squeeze=False)
    rng = np.random.default_rng(0)  # the dots' sideways jitter, the same in every drawing
    for ax, (name, axis_label) in zip(axes[0], panels.items(), strict=True):
        for i, label in enumerate(scores):
            values = np.asarray(scores[label][name])
            ax.scatter(i + rng.uniform(-0.12, 0.12, len(values)), values, s=14, color=f"C{i}")
            iv = means[label][name]
            ax.errorbar(
                i + 0.3,
                iv.mean,
                yerr=[[iv.mean - iv.low], [iv.high - iv.mean]],
                fmt="o",
                color="black",
                capsize=3,
                ms=4,
            )
        ax.set_xticks(range(len(scores)), list(scores), rotation=30, ha="right")
        ax.set_xlim(-0.5, len(scores) - 0.2)
        ax.set_ylabel(axis_label)
        ax.grid(alpha=0.3, axis="y")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)
