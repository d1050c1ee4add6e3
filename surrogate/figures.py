"""Figures: the parity plot of a training run and the benchmark's figures, one per question.

- :func:`parity_figure`, :func:`add_baselines`: a run's predicted against true wear, with its
  interval and the models scored beside the one kept (``parity.png`` of a run folder);
- :func:`error_summary`: how far each model is from the truth on each of the benchmark's test
  sets, beside the thesis's estimator and the null model fitted on the same rows
  (``summary.png``);
- :func:`parity_of_set`: for one test set, every model's readings against the true wear, the
  networks on one panel and the estimators fitted beside them on the other
  (``parity/<test set>.png``).
"""

from __future__ import annotations

import textwrap

import numpy as np
import pandas as pd

from physics.files import pyplot
from surrogate import baselines


def parity_figure(true: np.ndarray, pred: np.ndarray, half: np.ndarray | None, title: str,
                  label: str, ax=None, name: str = "surrogate"):
    """Predicted against true wear with the identity line (and intervals if given: ``half``
    widths, or a (2, rows) array of the widths below and above); ``name`` labels the points in
    the legend."""
    fig = None
    if ax is None:
        fig, ax = pyplot().subplots(figsize=(5, 5))
    ax.errorbar(true, pred, yerr=half, fmt="o", ms=3, alpha=0.6, elinewidth=0.6, label=name)
    top = max(float(np.max(true)), float(np.max(pred)), ax.get_xlim()[1] / 1.05 if ax.lines
              else 0.0)
    lim = [0, top * 1.05]
    ax.plot(lim, lim, "k--", lw=1)
    lines = [w for part in title.split("\n") for w in textwrap.wrap(part, 70)]  # to the axes
    ax.set(xlim=lim, ylim=lim, xlabel=f"true {label}", ylabel=f"predicted {label}",
           title="\n".join(lines))
    ax.title.set_fontsize(8)
    return fig if fig is not None else ax.figure


#: markers of the baselines in a parity plot
_MARKERS = {"linear": "x", "estimator": "+", "monotone": "1", "average": "2",
            "network": "."}


def add_baselines(ax, true: np.ndarray, readings: dict[str, np.ndarray]) -> None:
    """The baselines' readings in a parity plot: the median as a horizontal line, the others
    as points; the axes widened to hold them, and the legend."""
    for name, value in readings.items():
        if name == "median" and (len(value) == 0 or np.ptp(value) == 0):
            ax.axhline(float(value[0]) if len(value) else 0.0, color="0.5", ls=":", lw=1,
                       label=baselines.LABELS[name])
        else:
            ax.plot(true, value, _MARKERS.get(name, "."), ms=4, alpha=0.6,
                    label=baselines.LABELS[name])
    top = max([ax.get_xlim()[1], *(1.05 * float(np.max(v)) for v in readings.values()
                                   if len(v))])
    ax.set(xlim=(0, top), ylim=(0, top))
    ax.legend(fontsize=7)


#: the benchmark's test sets in the order the figures show them, with their labels
TEST_SETS = {
    "heldout_trajectories": "held-out trajectories",
    "new_gearboxes": "32 new gearboxes of the default ranges",
    "heldout_operating_point_inside": "operating point left out: case 2 (inside)",
    "heldout_operating_point_outside": "operating point left out: case 5 (at the edge)",
    "nuisance_shifted": "nuisance-shifted gearboxes",
    "beyond_ranges": "beyond the nuisance ranges",
    "dry_wear_law": "dry wear law",
    "model_form_off": "model form off",
    "independent_simulator": "independent simulator",
    "independent_fleet": "independent fleet",
    "independent_fleet_heldout": "independent fleet, held-out gearboxes",
}
#: the readings :func:`error_summary` compares (``benchmark.csv``'s ``estimator`` column):
#: label, marker and colour
READERS = {"surrogate": ("network", "o", "C0"),
           "empirical_inverse": ("thesis's estimator", "^", "C3"),
           "training_median": ("null model (training median)", "s", "0.55")}


def label_of_set(name: str) -> str:
    """A test set's label in the figures (its name where :data:`TEST_SETS` has none)."""
    return TEST_SETS.get(name, name.replace("_", " "))


def _by_test_set(scenarios) -> dict[str, list[str]]:
    """The models of each test set, from ``model/test set`` scenario names: the sets in the
    order of :data:`TEST_SETS` (others after them), the models in their order of appearance."""
    sets: dict[str, list[str]] = {}
    for scenario in dict.fromkeys(scenarios):
        model, test = scenario.split("/", 1)
        sets.setdefault(test, []).append(model)
    order = [*(s for s in TEST_SETS if s in sets), *(s for s in sets if s not in TEST_SETS)]
    return {s: sets[s] for s in order}


def error_summary(table: pd.DataFrame):
    """How far each model is from the truth on each test set: one panel per test set, one row
    per model scored on it, the mean relative error [%] of the network, of the thesis's
    estimator and of the null model fitted on the same training rows (:data:`READERS`), on a
    common log scale; a dot is the mean over the training seeds, its bar their range.
    ``table``: the benchmark's rows (columns ``scenario`` = ``model/test set``, ``estimator``,
    ``mean_relative_error_pct``, ``seed``). Returns the figure."""
    plt = pyplot()
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    mre = table[table.mean_relative_error_pct > 0].groupby(
        ["scenario", "estimator"], sort=False).mean_relative_error_pct.agg(["mean", "min", "max"])
    sets = _by_test_set(table.scenario)
    cols = min(3, len(sets))
    grid = [list(sets)[k:k + cols] for k in range(0, len(sets), cols)]
    heights = [max(len(sets[s]) for s in row) + 1 for row in grid]
    tall = 0.42 * sum(heights) + 1.2 * len(grid) + 1.0  # inches: the panels, then the top
    fig, axes = plt.subplots(len(grid), cols, sharex=True, squeeze=False,
                             figsize=(6.0 * cols, tall), gridspec_kw={"height_ratios": heights})
    for row, names in zip(axes, grid, strict=False):
        for ax, test in zip(row, names, strict=False):
            models = sets[test]
            for k, (reader, (_, marker, colour)) in enumerate(READERS.items()):
                y = np.arange(len(models)) + (k - 1) * 0.22  # the readers side by side
                for i, model in enumerate(models):
                    key = (f"{model}/{test}", reader)
                    if key not in mre.index:
                        continue
                    mean, lo, hi = mre.loc[key]
                    ax.plot([lo, hi], [y[i], y[i]], color=colour, lw=1.5)
                    ax.plot(mean, y[i], marker, color=colour, ms=6)
            ax.set_yticks(np.arange(len(models)), models, fontsize=9)
            ax.set_ylim(len(models) - 0.5, -0.5)
            ax.set_title(label_of_set(test), fontsize=11)
            ax.set_xscale("log")
            ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 3.0)))
            ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
            ax.grid(axis="x", which="both", color="0.9")
            ax.axvline(100.0, color="0.3", lw=0.8, ls=":")
        for ax in row[len(names):]:
            ax.set_visible(False)
    for column in axes.T:  # the scale under the lowest panel of each column
        ax = [a for a in column if a.get_visible()][-1]
        ax.set_xlabel("mean relative error [%] (log scale)", fontsize=10)
        ax.xaxis.set_tick_params(labelbottom=True)
    handles = [plt.Line2D([], [], marker=m, color=c, lw=1.5, label=lab)
               for lab, m, c in READERS.values()]
    fig.suptitle("How far each model reads from the true wear, per test set (dot: mean over "
                 "the training seeds, bar: their range; dotted: 100 %)", fontsize=12,
                 y=1 - 0.15 / tall, va="top")
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 1 - 0.5 / tall),
               ncol=len(READERS), fontsize=10, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.95 / tall))
    return fig


def parity_of_set(test: str, plots: dict[str, dict]):
    """The readings of one test set against its true wear: the networks (``plots``: model ->
    its :func:`surrogate.benchmark.evaluate` plot data, the first training seed's) on one
    panel, the thesis's estimator fitted on each network's training rows on the other, each
    model in its own colour, each panel on its own scale with the identity line. Each model is
    scored on its own target (mean or root depth), named in the legend. Returns the figure."""
    fig, axes = pyplot().subplots(1, 2, figsize=(11, 5.4))
    for ax, (key, who) in zip(axes, (("surrogate", "network"),
                                     ("estimator", "thesis's estimator")), strict=True):
        for model, d in plots.items():
            parity_figure(d["true"] * 1e3, d[key] * 1e3, None, "", "", ax,
                          name=f"{model} ({d['target'].replace('_wear_mm', '')})")
        ax.set_title(who, fontsize=11)
        ax.set_xlabel("true wear [um]", fontsize=10)
        ax.set_ylabel("read wear [um]", fontsize=10)
        ax.legend(fontsize=8, title="model (target depth)", title_fontsize=8)
    fig.suptitle(label_of_set(test), fontsize=12)
    fig.tight_layout()
    return fig
