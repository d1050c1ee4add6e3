"""Figures of the reproduction (``python -m physics.reproduce``): mesh stiffness, DTE spectrum,
wear evolution, feature trends and wear profile, each from the table it shows, and the
mixed-EHL pressure and film at three mesh positions, from the solver's solutions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from physics.files import pyplot, save_figure
from physics.signals.order_analysis import power_spectrum
from physics.tribology.mixed_ehl import EHLSolution
from physics.tribology.wear import WearResult


def plot_tvms(tvms: pd.DataFrame, path: Path) -> None:
    plt = pyplot()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True,
                                  gridspec_kw={"height_ratios": [2, 1]})
    healthy = tvms[tvms.cycles == tvms.cycles.min()]
    for n, df in tvms.groupby("cycles"):
        ax.plot(df.roll_mm, df.k_total_N_per_m / 1e8, label=f"{n:.3g} cycles")
        ax2.plot(df.roll_mm, (df.k_total_N_per_m.to_numpy()
                              / healthy.k_total_N_per_m.to_numpy() - 1) * 100)
    ax.plot(healthy.roll_mm, healthy.k_pair1_N_per_m / 1e8, "k:", lw=0.8, label="pair 1 (healthy)")
    ax.plot(healthy.roll_mm, healthy.k_pair2_N_per_m / 1e8, "k--", lw=0.8,
            label="pair 2 (healthy)")
    ax.set_ylabel("mesh stiffness [1e8 N/m]")
    ax.set_title("Time-varying mesh stiffness over one mesh period (potential energy method)")
    ax.legend(fontsize=8)
    ax2.set_ylabel("change vs healthy [%]")
    ax2.set_xlabel("roll coordinate of pair 1 [mm] (start of contact = pinion root)")
    save_figure(fig, path)
    plt.close(fig)


def plot_dte_spectrum(dte: pd.DataFrame, mesh_hz: float, fs: float, path: Path) -> None:
    plt = pyplot()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6))
    for n, df in dte.groupby("cycles"):
        x = df.dte_m.to_numpy()
        # Hann-windowed power of each line (A^2/2): amplitude sqrt(2 P)
        f, power = power_spectrum(x, fs)
        spec = np.sqrt(2 * power)
        ax.semilogy(f, spec * 1e6, lw=0.8, label=f"{n:.3g} cycles")
        ax2.plot(df.time_s * 1e3, x * 1e6, lw=0.8, label=f"{n:.3g} cycles")
    for h in range(1, 6):
        ax.axvline(h * mesh_hz, color="k", ls=":", lw=0.6)
    ax.set_xlim(0, 8 * mesh_hz)
    ax.set_xlabel("frequency [Hz] (dotted: mesh harmonics)")
    ax.set_ylabel("DTE amplitude [um]")
    ax.legend(fontsize=8)
    ax2.set_xlim(0, 10 * 1e3 / mesh_hz)
    ax2.set_xlabel("time [ms]")
    ax2.set_ylabel("DTE [um]")
    fig.suptitle("Dynamic transmission error, healthy and worn")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def plot_wear_evolution(curves: pd.DataFrame, path: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    for case, df in curves.groupby("case"):
        ax.plot(df.cycles, df.root_wear_mm * 1e3, label=f"case {case}")
    ax.set_xlabel("pinion cycles")
    ax.set_ylabel("pinion root wear [um]")
    ax.set_title("Pinion root wear under dynamic load (thesis Table 11 cases)")
    ax.legend()
    save_figure(fig, path)
    plt.close(fig)


def plot_feature_trends(table14: pd.DataFrame, path: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    cols = ["rms_1e-5_m", "peak_to_peak_1e-5_m", "kurtosis", "crest", "margin", "impulse"]
    for c in cols:
        v = table14[c].to_numpy()
        span = np.ptp(v)
        ax.plot(table14.wear_mm * 1e3, (v - v.min()) / span if span > 0 else 0 * v, "o-",
                label=f"{c.replace('_1e-5_m', '')} (span {span:.3g})")
    ax.set_xlabel("pinion root wear [um]")
    ax.set_ylabel("feature, min-max normalised")
    ax.set_title("DTE features against wear (case 3)")
    ax.legend(fontsize=7)
    save_figure(fig, path)
    plt.close(fig)


def plot_wear_profile(res: WearResult, path: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(res.s * 1e3, res.pinion * 1e6, label="pinion")
    ax.plot(res.s * 1e3, res.gear * 1e6, label="gear")
    lo, hi = res.geometry.single_zone
    ax.axvspan(lo * 1e3, hi * 1e3, color="0.9", label="single-tooth zone")
    ax.axvline(0.0, color="k", lw=0.6, ls=":")
    ax.set_xlabel("roll distance from pitch point along line of action [mm]\n"
                  "(pinion root / gear tip  <-  ->  pinion tip / gear root)")
    ax.set_ylabel("wear depth [um]")
    ax.set_title(f"Flank wear after {res.cycles:.3g} pinion cycles")
    ax.legend()
    save_figure(fig, path)
    plt.close(fig)


def plot_ehl_pressure_film(solutions: dict[str, EHLSolution], path: Path) -> None:
    """Total and fluid pressure with the asperity pressure on its own scale (top) and the
    nominal film with the +-sigma roughness band (bottom) across the contact, one column per
    mesh position, in Hertz half-widths."""
    plt = pyplot()
    fig, axes = plt.subplots(2, len(solutions), figsize=(4 * len(solutions), 6), sharex=True,
                             squeeze=False)
    for j, (label, sol) in enumerate(solutions.items()):
        x = sol.x / sol.hertz_half_width
        ax, ax2 = axes[0, j], axes[1, j]
        ax.plot(x, (sol.p_h + sol.p_a) * 1e-9, "k", lw=1.2, label="total")
        ax.plot(x, sol.p_h * 1e-9, "C0--", lw=1.0, label="fluid")
        ax.plot(x, sol.hertz_pressure * np.sqrt(np.clip(1 - x * x, 0, None)) * 1e-9, "0.6",
                lw=0.8, ls=":", label="dry Hertz")
        axa = ax.twinx()  # the asperity pressure is a small part of the total: its own scale
        axa.plot(x, sol.p_a * 1e-6, "C3", lw=1.0)
        axa.tick_params(axis="y", colors="C3", labelsize=8)
        axa.set_ylim(0.0, max(float(np.max(sol.p_a)) * 1e-6 * 1.15, 1e-3))
        if j == len(solutions) - 1:
            axa.set_ylabel("asperity pressure [MPa] (red)", color="C3")
        ax.set_title(f"{label}\nasperity share {sol.asperity_load_share * 100:.2g} %, "
                     f"h_min/sigma {sol.film_ratio_min:.2f}", fontsize=9)
        ax2.plot(x, sol.h * 1e6, "C0", lw=1.2, label="film h (mean planes)")
        ax2.fill_between(x, sol.h * 1e6 - sol.sigma * 1e6, sol.h * 1e6 + sol.sigma * 1e6,
                         color="C0", alpha=0.15, lw=0, label="h +- sigma")
        ax2.axhline(0.0, color="k", lw=0.6)
        top = float(np.interp(0.0, x, sol.h)) * 1e6
        ax2.set_ylim(min(-0.1 * top, float(np.min(sol.h - sol.sigma)) * 1e6), 3.0 * top)
        ax2.set_xlabel("x / b (entrainment to the right)")
        if j == 0:
            ax.set_ylabel("pressure [GPa]")
            ax2.set_ylabel("film [um]")
            ax.legend(fontsize=7)
            ax2.legend(fontsize=7)
    fig.suptitle("Mixed-EHL line contact (numerical solver), unworn pair, bulk temperature")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def plot_table15(table: pd.DataFrame, path: Path) -> None:
    """Table 15's rises against induced root wear: measured (where given), one tooth (with its
    span through the housing modes, where computed), all."""
    plt = pyplot()
    names = list(dict.fromkeys(table["feature"]))
    fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names), 3.2))
    for ax, name in zip(np.atleast_1d(axes), names, strict=True):
        df = table[table["feature"] == name]
        um = df["wear_mm"] * 1e3
        for col, style, label in (("rise_measured", "ko-", "measured (thesis Table 15)"),
                                  ("rise_one_tooth", "s--", "model, one tooth"),
                                  ("rise_all_teeth", "^-", "model, every tooth")):
            if df[col].notna().any():
                ax.plot(np.r_[0, um], np.r_[1.0, df[col]], style, label=label)
        if "rise_one_tooth_mode_least" in df and df["rise_one_tooth_mode_least"].notna().any():
            ax.fill_between(np.r_[0, um], np.r_[1.0, df["rise_one_tooth_mode_least"]],
                            np.r_[1.0, df["rise_one_tooth_mode_largest"]], color="C0",
                            alpha=0.2, label="one tooth, through a housing mode")
        ax.set_title(name.replace("_", " "))
        ax.set_xlabel("pinion root wear [um]")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("over the new pair's")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    save_figure(fig, path)
    plt.close(fig)


def plot_table15_operating_points(points: pd.DataFrame, stated: pd.DataFrame,
                                  path: Path) -> None:
    """Table 15's kurtosis rise at its deepest induced wear against the speed, one line per
    torque, one tooth and every tooth, the measured rise as a level."""
    plt = pyplot()
    deepest = points["wear_mm"].max()
    df = points[(points["feature"] == "kurtosis") & np.isclose(points["wear_mm"], deepest)]
    fig, axes = plt.subplots(1, 2, figsize=(8.0, 3.4), sharey=True)
    measured = stated.loc[(stated["feature"] == "kurtosis")
                          & np.isclose(stated["wear_mm"], deepest), "rise_measured"]
    for ax, col, title in zip(axes, ("rise_one_tooth", "rise_all_teeth"),
                              ("root wear on one tooth", "on every tooth"), strict=True):
        for i, (torque, rows) in enumerate(df.groupby("torque_Nm")):
            ax.plot(rows["n1_rpm"], rows[col], "o-", color=f"C{i}", label=f"{torque:g} N m")
        if measured.notna().any():
            ax.axhline(float(measured.iloc[0]), color="k", lw=1,
                       label="measured (thesis Table 15)")
        ax.set(title=f"kurtosis at {deepest * 1e3:g} um, {title}", xlabel="pinion speed [r/min]")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("over the new pair's")
    axes[0].legend(fontsize=7)
    save_figure(fig, path)
    plt.close(fig)
