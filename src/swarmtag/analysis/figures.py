"""Figures of a study's results: PA and latency curves with bands, parameter sweeps, urgency.

Each function draws one figure from a ``MetricsReport`` (or per-urgency
latencies) and writes it as a PNG atomically; matplotlib is imported
lazily (the ``plot`` extra). These are the figures of the published study,
plus latency per urgency level. Each condition keeps one colour in every
figure (``condition_colours``: viridis along a one-parameter sweep, a
qualitative palette otherwise), legends sit outside the axes, and each PNG
carries a one-sentence caption (its ``Description`` text, which
``swarmtag.analysis.html`` shows under it).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._atomic import atomic_path
from swarmtag._plotting import pyplot
from swarmtag.analysis.html import CAPTION_KEY
from swarmtag.analysis.latency import UrgencyLatency, latency_by_urgency
from swarmtag.analysis.ranking import RankRow
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.analysis.summary import MetricsReport
from swarmtag.analysis.tables import metric_label, unit_word
from swarmtag.errors import PolicyError, StatisticsError
from swarmtag.io import CarrierLog
from swarmtag.policy import Urgency, Weighted, parse_policy

__all__ = [
    "condition_colours",
    "draw_curves",
    "figure_files",
    "latency_curve_figure",
    "pa_curve_figure",
    "pareto_figure",
    "sweep_figure",
    "urgency_latency_figure",
    "write_figures",
]

_SIZE: Final = (6.4, 4.2)
_DPI: Final = 120
"""Pixels per inch of the PNGs."""
_SWEEP_RANGE: Final = (0.0, 0.88)
"""The stretch of viridis a sweep spans: its last yellows are too pale on white."""
Colour = tuple[float, float, float, float]
"""RGBA, each 0-1 (matplotlib's)."""


def _save(fig: Any, path: str | os.PathLike[str], caption: str) -> None:  # noqa: ANN401 - a Figure
    """Write the PNG with ``caption`` as its description, the figure drawn once.

    ``tight_layout`` makes room for outside legends, so no ``bbox_inches="tight"``
    (a second draw to measure); the pixels go from the Agg canvas to Pillow as RGB (the
    figure is opaque: an alpha channel would only double the compression time).
    """
    from PIL import Image, PngImagePlugin  # noqa: PLC0415 - Pillow comes with matplotlib

    fig.set_dpi(_DPI)  # before the layout, so that it measures the text as drawn
    fig.tight_layout()
    fig.canvas.draw()
    pixels = np.asarray(fig.canvas.buffer_rgba())
    info = PngImagePlugin.PngInfo()
    info.add_text(CAPTION_KEY, caption)
    with atomic_path(path) as temp:
        Image.fromarray(pixels[..., :3]).save(temp, format="png", pnginfo=info, dpi=(_DPI, _DPI))


def _outside_legend(ax: Any, **options: Any) -> Any:  # noqa: ANN401 - matplotlib Axes, Legend
    """A legend right of the axes, top-aligned, so that it never covers the data."""
    return ax.legend(
        loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=8, **options
    )


def condition_colours(names: Sequence[str]) -> dict[str, Colour]:
    """One distinct colour per condition, the same in every figure of a report.

    A sweep of one parameter (all weighted, or all urgency) runs along
    viridis in parameter order, so neighbours look alike and the ends apart;
    other sets take tab10 (tab20 past ten conditions) in the given order.
    """
    plt = pyplot()
    if _sweepable(names):
        ordered = sorted(names, key=_parameter)
        low, high = _SWEEP_RANGE
        steps = np.linspace(low, high, len(ordered))
        cmap = plt.get_cmap("viridis")
        return {name: tuple(cmap(float(step))) for name, step in zip(ordered, steps, strict=True)}
    palette = plt.get_cmap("tab10" if len(names) <= 10 else "tab20")
    return {name: tuple(palette(i % palette.N)) for i, name in enumerate(names)}


def draw_curves(ax: Any, report: MetricsReport, *, pa: bool) -> None:  # noqa: ANN401 - an Axes
    """PA(p) (``pa``) or pooled latency against the percentile, one line and 95 % band each.

    Draws on a matplotlib ``Axes`` the caller owns: the figure files and the
    notebook's plots (``swarmtag.simulate(...).plot_pa``) share it. Each
    condition in its ``condition_colours`` colour, the legend right of the axes.
    """
    colours = condition_colours([c.condition for c in report.conditions])
    band = min(0.2, 0.8 / len(colours))  # many overlapping bands: fainter, or they turn to mud
    for statistics in report.conditions:
        curve = statistics.pa_curve if pa else statistics.latency_curve
        colour = colours[statistics.condition]
        ax.plot(
            curve.x, curve.value, marker="o", markersize=3, color=colour,
            label=statistics.condition,
        )  # fmt: skip
        ax.fill_between(curve.x, curve.low, curve.high, color=colour, alpha=band, lw=0)
    if pa:
        ax.set_xlabel("threshold p (%)")
        ax.set_ylabel("PA(p), mean over runs")
        ax.set_ylim(0, 1.02)
    else:
        ax.set_xlabel("percentile of pooled latencies")
        ax.set_ylabel(f"latency ({unit_word(report.time_unit)})")
    ax.set_title(
        f"{'Priority alignment' if pa else 'Latency'} with 95 % bootstrap bands "
        f"({report.n_resamples} resamples)",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    _outside_legend(ax)


_CURVE_CAPTIONS: Final = {
    True: "Priority alignment PA(p), the share of the p % most urgent carriers among the first "
    "p % delivered, against the threshold p: the mean over runs per condition, its 95 % "
    "bootstrap band shaded.",
    False: "Latency of the delivered carriers, pooled over runs, at each percentile per "
    "condition, its 95 % bootstrap band shaded; lower is faster.",
}


def _curves(report: MetricsReport, path: str | os.PathLike[str], *, pa: bool) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=_SIZE)
    try:
        draw_curves(ax, report, pa=pa)
        _save(fig, path, _CURVE_CAPTIONS[pa])
    finally:
        plt.close(fig)


def pa_curve_figure(report: MetricsReport, path: str | os.PathLike[str]) -> None:
    """PA(p) against the threshold p for every condition, with 95 % bands."""
    _curves(report, path, pa=True)


def latency_curve_figure(report: MetricsReport, path: str | os.PathLike[str]) -> None:
    """Pooled latency against the percentile for every condition, with 95 % bands."""
    _curves(report, path, pa=False)


def _floats(values: Iterable[float | None]) -> NDArray[np.float64]:
    """An array with NaN where a figure is undefined (matplotlib leaves a gap)."""
    return np.array([np.nan if v is None else v for v in values], dtype=np.float64)


def _parameter(name: str) -> float:
    policy = parse_policy(name)
    if isinstance(policy, Weighted):
        return policy.w
    if isinstance(policy, Urgency):
        return policy.alpha
    msg = f"{name}: a sweep needs weighted or urgency conditions"
    raise StatisticsError(msg)


def sweep_figure(
    report: MetricsReport,
    path: str | os.PathLike[str],
    *,
    metrics: Sequence[str] = ("pa", "p95_latency"),
) -> None:
    """Each metric (value and 95 % CI) against the policy parameter (w or alpha), one panel each."""
    names = [c.condition for c in report.conditions]
    x = np.array([_parameter(name) for name in names])
    order = np.argsort(x)
    colours = condition_colours(names)
    plt = pyplot()
    parameter = "w" if isinstance(parse_policy(names[0]), Weighted) else "alpha"
    fig, axes = plt.subplots(1, len(metrics), figsize=(4.2 * len(metrics), 3.8), squeeze=False)
    try:
        for ax, metric in zip(axes[0], metrics, strict=True):
            estimates = [report.condition(names[i]).estimate(metric) for i in order]
            value = np.array([np.nan if e.value is None else e.value for e in estimates])
            low = np.array(
                [
                    np.nan if e.confidence_interval.low is None else e.confidence_interval.low
                    for e in estimates
                ]
            )
            high = np.array(
                [
                    np.nan if e.confidence_interval.high is None else e.confidence_interval.high
                    for e in estimates
                ]
            )
            ax.plot(x[order], value, color="0.45", zorder=1)
            ax.fill_between(x[order], low, high, color="0.5", alpha=0.2, lw=0)
            ax.scatter(
                x[order], value, c=[colours[names[i]] for i in order], s=30, zorder=2,
                edgecolors="k", linewidths=0.5,
            )  # fmt: skip
            ax.set_xlabel(parameter)
            ax.set_ylabel(metric_label(metric, report.time_unit))
            ax.grid(alpha=0.3)
        fig.suptitle("Parameter sweep, values with 95 % bootstrap CIs", fontsize=10)
        labels = " and ".join(metric_label(m, report.time_unit) for m in metrics)
        caption = (
            f"{labels} against the policy parameter {parameter}, one point per condition "
            "(coloured as in the curves) with its 95 % bootstrap interval shaded."
        )
        _save(fig, path, caption)
    finally:
        plt.close(fig)


def pareto_figure(
    ranked: Mapping[str, Sequence[RankRow]],
    path: str | os.PathLike[str],
    *,
    time_unit: str | None,
) -> None:
    """PA against throughput per scale (95 % CIs as bars), P95 as colour, the Pareto front joined.

    ``ranked``: each scale's ``rank_conditions`` rows; one panel per scale.
    """
    plt = pyplot()
    panels = len(ranked)
    fig, axes = plt.subplots(1, panels, figsize=(5.2 * panels, 4.4), squeeze=False)
    try:
        for ax, (scale, rows) in zip(axes[0], ranked.items(), strict=True):
            x = _floats(row.throughput.value for row in rows)
            y = _floats(row.pa.value for row in rows)
            colour = _floats(row.p95.value for row in rows)
            for row, xi, yi in zip(rows, x, y, strict=True):
                xs, ys = row.throughput.confidence_interval, row.pa.confidence_interval
                if None not in (xs.low, xs.high, ys.low, ys.high):
                    ax.errorbar(
                        xi, yi, xerr=[[xi - xs.low], [xs.high - xi]],
                        yerr=[[yi - ys.low], [ys.high - yi]], color="0.6", lw=0.8, zorder=1,
                    )  # fmt: skip

            labels: dict[tuple[int, int], tuple[float, float, list[str]]] = {}
            span = (np.nanmax(x) - np.nanmin(x) or 1.0, np.nanmax(y) - np.nanmin(y) or 1.0)
            for row, xi, yi in zip(rows, x, y, strict=True):  # points within 2 %: one label
                cell = (round(40 * xi / span[0]), round(40 * yi / span[1]))
                labels.setdefault(cell, (xi, yi, []))[2].append(row.condition.split(":")[0])
            for xi, yi, names in labels.values():
                ax.annotate(
                    " / ".join(names), (xi, yi), textcoords="offset points", xytext=(5, 4),
                    fontsize=8,
                )  # fmt: skip
            front = sorted((xi, yi) for row, xi, yi in zip(rows, x, y, strict=True) if row.pareto)
            if len(front) > 1:
                ax.plot(*zip(*front, strict=True), ls="--", color="tab:red", lw=1, zorder=1)
            points = ax.scatter(x, y, c=colour, cmap="viridis", s=50, zorder=2, edgecolors="k")
            fig.colorbar(points, ax=ax, label=metric_label("p95_latency", time_unit))
            ax.set_xlabel(metric_label("throughput", time_unit))
            ax.set_ylabel("PA (5-50 %)")
            ax.set_title(scale, fontsize=10)
            ax.grid(alpha=0.3)
        fig.suptitle(
            "PA against throughput (95 % CIs); dashed: the Pareto front; colour: P95", fontsize=10
        )
        caption = (
            "PA against throughput per condition, one panel per swarm size, with 95 % bootstrap "
            "intervals as bars and P95 latency as colour; the dashed line joins the conditions "
            "no other beats on both PA and throughput (the Pareto front)."
        )
        _save(fig, path, caption)
    finally:
        plt.close(fig)


def urgency_latency_figure(
    by_condition: Mapping[str, Sequence[UrgencyLatency]],
    path: str | os.PathLike[str],
    *,
    time_unit: str | None,
) -> None:
    """Mean and P95 latency per urgency level at run start, one line pair per condition."""
    plt = pyplot()
    colours = condition_colours(list(by_condition))
    fig, ax = plt.subplots(figsize=_SIZE)
    try:
        for name, levels in by_condition.items():
            u = [level.urgency for level in levels]
            mean = _floats(level.mean for level in levels)
            p95 = _floats(level.p95 for level in levels)
            ax.plot(u, mean, marker="o", markersize=4, color=colours[name], label=name)
            ax.plot(u, p95, marker="^", markersize=4, linestyle="--", color=colours[name])
        ax.set_xlabel("urgency at run start")
        ax.set_ylabel(f"latency ({unit_word(time_unit)})")
        ax.set_xticks(range(10))
        ax.set_title("Latency per urgency level (delivered carriers)", fontsize=10)
        ax.grid(alpha=0.3)
        # One legend (conditions by colour, then the two line styles), so the bounds hold it.
        handles, _ = ax.get_legend_handles_labels()
        handles += [
            plt.Line2D([], [], color="0.3", marker="o", markersize=4, label="mean"),
            plt.Line2D([], [], color="0.3", marker="^", markersize=4, ls="--", label="P95"),
        ]
        _outside_legend(ax, handles=handles)
        caption = (
            "Mean (solid) and P95 (dashed) latency of the delivered carriers by the urgency "
            "level they had at run start, per condition; the most urgent are on the right."
        )
        _save(fig, path, caption)
    finally:
        plt.close(fig)


def _sweepable(names: Sequence[str]) -> bool:
    """Two or more conditions of one parametrised policy (all weighted, or all urgency)."""
    try:
        kinds = {type(parse_policy(name)) for name in names}
    except PolicyError:  # a rule of one's own not loaded here: not a sweep
        return False
    return len(names) >= 2 and len(kinds) == 1 and kinds <= {Weighted, Urgency}


def figure_files(report: MetricsReport, folder: str | os.PathLike[str]) -> list[Path]:
    """The PNGs ``write_figures`` writes for ``report`` in ``folder``, in its order (none drawn).

    Always the PA curves, latency curves and latency per urgency level; the
    parameter sweep too when all conditions are one parametrised policy.
    """
    out = Path(folder)
    files = [out / "pa_curves.png", out / "latency_curves.png", out / "urgency_latency.png"]
    if _sweepable([c.condition for c in report.conditions]):
        files.append(out / "sweep.png")
    return files


def write_figures(
    report: MetricsReport, log: CarrierLog, folder: str | os.PathLike[str]
) -> list[Path]:
    """Every figure that applies to ``report`` (computed from ``log``): ``figure_files``."""
    written = figure_files(report, folder)
    pa_curve_figure(report, written[0])
    latency_curve_figure(report, written[1])
    levels = {
        c.condition: latency_by_urgency(ConditionRuns.from_log(log, c.condition))
        for c in report.conditions
    }
    urgency_latency_figure(levels, written[2], time_unit=report.time_unit)
    if len(written) > 3:
        sweep_figure(report, written[3])
    return written
