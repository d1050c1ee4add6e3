"""Reproduce the thesis's tables from the physics: ``python -m physics.reproduce``.

A Hydra app (config ``conf/reproduce.yaml``). It writes, into ``out_dir`` (default: the Hydra run
folder), CSV files named and shaped like the thesis's own (:data:`physics.reference.THESIS_TABLES`):

- ``table02_speed.csv`` ... ``table06_center_distance.csv`` (thesis 2.7.2-2.7.6, 1e6 cycles),
- ``table07_tvms_energy_vs_fem.csv``, ``fem_convergence.csv``, ``table08_wear_vs_stiffness.csv``,
  ``tvms.csv`` and ``tvms.png`` (mesh stiffness, thesis 3.1-3.2),
- ``table09_dynamics_vs_wear.csv``, ``table10_dynamic_vs_quasistatic.csv``, ``dte.csv`` and
  ``dte_spectrum.png`` (torsional dynamics and the dynamic-load coupling, 3.3-3.5),
- ``wear_evolution.csv``, ``wear_evolution.png`` and ``table12_evolution_fits_case{1..5}.csv``
  (pinion root wear against cycles for the cases of Table 11, and the candidate laws, 4.1),
- ``table14_dte_features_case3.csv``, ``feature_trends.png`` and ``estimator_accuracy.csv``
  (vibration features against wear, and the empirical-inverse estimator of 4.4 fitted to them and
  with the thesis's own coefficients on the thesis's own data),
- ``wear_profile.csv`` and ``wear_profile.png`` (baseline wear of both flanks, 2.7),
  ``contact_state.csv`` (the unworn contact along the path: load, Hertz, the mixed-EHL solver's
  films, pressure peak and asperity share beside the Masjedi-Khonsari regression's, flash
  temperature, wear rates) and ``ehl_pressure_film.png`` (the solver's pressure and film at the
  pinion root, the pitch point and the pinion tip).

Film thickness, film ratio, asperity load ratio and Hertz pressure are reported at the pitch
point of the unworn pair (single-tooth zone); average wear is the mean pinion wear depth over the
active flank; ``total_wear_relative`` is the worn area of both flanks relative to the standard
centre distance. Every value is computed; nothing is copied from the thesis.

``record_hashes=true`` then records the sha256 of each table in
``tests/reproduce/table_hashes.sha256`` of the repository checkout, the record that
``tests/reproduce/test_reproduce_hashes.py`` compares the default run with.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from physics.dynamics.evolution import (
    fit_evolution_models,
    root_wear_evolution,
    simulate_dynamic_wear,
)
from physics.dynamics.model import build_model, simulate
from physics.estimators.empirical_inverse import EmpiricalInverse, accuracy
from physics.files import (
    check_fresh,
    check_outside,
    check_writable,
    read_csv_table,
    resolved,
    sha256_file,
    write_csv,
    write_text,
)
from physics.gear.contact import reduced_modulus
from physics.gear.geometry import MeshGeometry
from physics.gear.load_sharing import pair_loads
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.gear.tooth_fem import FEResult, fe_pair_stiffness
from physics.params import (
    Lubricant,
    PhysicsConfig,
    Scenario,
    config_choices,
    config_file,
    scenario_for_case,
    scenario_from_config,
)
from physics.reference import THESIS_TABLES
from physics.reproduce import plots
from physics.reproduce.localised import (
    MEASURED_TABLE,
    measured_table,
    table15_model,
    table15_operating_points,
    thesis_tables_fix,
)
from physics.scope import check_record, check_scope
from physics.signals.features import features
from physics.tribology.asperity_table import check_scenario
from physics.tribology.mixed_ehl import EHLSolution, solve_line_contact
from physics.tribology.wear import WearResult, quasi_static_force, simulate_wear

log = logging.getLogger(__name__)


def _with(scn: Scenario, part: str, **changes) -> Scenario:
    return dataclasses.replace(scn, **{part: dataclasses.replace(getattr(scn, part), **changes)})


def pitch_state(res: WearResult) -> dict[str, float]:
    """Contact state of the unworn pair at the pitch point."""
    st = res.first_rate.state
    return {n: float(np.interp(0.0, res.s, getattr(st, n)))
            for n in ("h_min", "film_ratio", "asperity_ratio", "p_max", "flash_temperature")}


def parameter_sweep(scn: Scenario, cycles: float, part: str, name: str, values: list[float],
                    shown: dict[str, tuple[str, float]]) -> pd.DataFrame:
    """Average pinion wear after ``cycles`` and pitch-point contact quantities with
    ``scn.<part>.<name>`` set to each value (thesis 2.7.2-2.7.4). ``shown`` maps a column to
    (a key of :func:`pitch_state`, its unit factor)."""
    rows = []
    for v in values:
        res = simulate_wear(_with(scn, part, **{name: float(v)}), cycles)
        state = pitch_state(res)
        rows.append({name: v, **{col: state[key] * f for col, (key, f) in shown.items()},
                     "avg_wear_um": res.mean_depth() * 1e6})
    return pd.DataFrame(rows)


ASPERITY = {"asperity_load_ratio_pct": ("asperity_ratio", 100.0)}


def table_speed(scn: Scenario, cycles: float, speeds: list[float]) -> pd.DataFrame:
    """Table 2 (2.7.2)."""
    return parameter_sweep(scn, cycles, "operating", "n1_rpm", speeds,
                           {"min_film_thickness_nm": ("h_min", 1e9), **ASPERITY})


def table_torque(scn: Scenario, cycles: float, torques: list[float]) -> pd.DataFrame:
    """Table 3 (2.7.3)."""
    return parameter_sweep(scn, cycles, "operating", "torque_Nm", torques,
                           {"max_hertz_pressure_MPa": ("p_max", 1e-6), **ASPERITY})


def table_roughness(scn: Scenario, cycles: float, sigmas: list[float]) -> pd.DataFrame:
    """Table 4 (2.7.4)."""
    return parameter_sweep(scn, cycles, "tribology", "sigma_um", sigmas,
                           {"film_thickness_ratio": ("film_ratio", 1.0), **ASPERITY})


def table_lubricant(
    scn: Scenario, cycles: float, lubricants: dict[str, Lubricant]
) -> pd.DataFrame:
    rows = []
    for name, lub in lubricants.items():
        res = simulate_wear(dataclasses.replace(scn, lubricant=lub), cycles)
        rows.append({"condition": name, "avg_wear_um": res.mean_depth() * 1e6,
                     "max_wear_um": res.pinion.max() * 1e6, "note": ""})
    dry = simulate_wear(_with(scn, "tribology", regime="dry"), cycles)
    k = scn.tribology.dry_wear_coeff
    rows.append({"condition": "dry friction", "avg_wear_um": dry.mean_depth() * 1e6,
                 "max_wear_um": dry.pinion.max() * 1e6,
                 "note": f"classical Archard with k={k:g}"})
    return pd.DataFrame(rows)


def table_center_distance(scn: Scenario, cycles: float, offsets_pct: list[float]) -> pd.DataFrame:
    if 0.0 not in [float(o) for o in offsets_pct]:
        raise ValueError(f"center_distance_offsets_pct = {offsets_pct} must contain 0: the "
                         "total wear is reported relative to the standard centre distance")
    a0 = scn.gear.standard_center_distance_mm
    results = []
    for off in offsets_pct:
        a = round(a0 * (1 + off / 100), 6)
        results.append((a, simulate_wear(_with(scn, "gear", center_distance_mm=a), cycles)))
    ref = next(r for a, r in results if abs(a - a0) < 1e-9)
    ref_area = ref.worn_area("pinion") + ref.worn_area("gear")
    return pd.DataFrame([
        {"center_distance_mm": a, "contact_ratio": r.geometry.contact_ratio,
         "max_pinion_wear_um": r.pinion.max() * 1e6,
         "total_wear_relative": (r.worn_area("pinion") + r.worn_area("gear")) / ref_area}
        for a, r in results
    ])


def table07_positions(geom: MeshGeometry) -> dict[str, np.ndarray]:
    """Roll coordinates of the pairs in contact at the three mesh positions of Table 7.

    Over one mesh period the pair entering at the start of contact shares the load with the pair
    one base pitch ahead for ``(eps - 1) p_b`` of roll, then carries it alone. "First" and
    "second double-tooth zone" are taken a quarter and three quarters into the double-contact
    interval (the entering pair near the pinion root, then the leaving pair near the pinion
    tip); "single-tooth zone" is the middle of the single-contact interval.
    """
    d = (geom.contact_ratio - 1) * geom.base_pitch
    first, second = geom.s_start + 0.25 * d, geom.s_start + 0.75 * d
    return {
        "first double-tooth zone": np.array([first, first + geom.base_pitch]),
        "single-tooth zone": np.array([0.5 * sum(geom.single_zone)]),
        "second double-tooth zone": np.array([second, second + geom.base_pitch]),
    }


def _fem_at_positions(scn: Scenario, plane: str, refine: float) -> tuple[dict, FEResult]:
    ms = mesh_stiffness(scn.gear, scn.material)
    positions = table07_positions(ms.geometry)
    s = np.concatenate(list(positions.values()))
    force = quasi_static_force(scn, ms.geometry)
    share = pair_loads(ms.geometry, s, force, np.zeros_like, ms.pair_function())
    fe = fe_pair_stiffness(scn.gear, scn.material, ms.geometry, s, share, plane, refine)
    return positions, fe


def table_tvms_fem(scn: Scenario, refine: float, plane: str = "strain") -> pd.DataFrame:
    """Table 7: mesh stiffness by the energy method and by FE at three mesh positions."""
    ms = MeshStiffness(scn.gear, scn.material, plane=plane)
    positions, fe = _fem_at_positions(scn, plane, refine)
    rows, i = [], 0
    for label, s in positions.items():
        k_pe = float(ms.pair(s).sum())
        k_fe = float(fe.pair_stiffness[i:i + len(s)].sum())
        i += len(s)
        rows.append({"meshing_position": label, "energy_method_1e8_N_per_m": k_pe / 1e8,
                     "fem_1e8_N_per_m": k_fe / 1e8,
                     "relative_error_pct": abs(k_pe - k_fe) / k_fe * 100})
    return pd.DataFrame(rows)


def table_fem_convergence(scn: Scenario, refines: list[float]) -> pd.DataFrame:
    """FE mesh stiffness at the Table 7 positions for successively finer meshes, both planes."""
    rows = []
    for plane in ("strain", "stress"):
        for refine in refines:
            positions, fe = _fem_at_positions(scn, plane, refine)
            i = 0
            for label, s in positions.items():
                rows.append({"plane": plane, "refine": refine, "elements_pinion": fe.elements[0],
                             "elements_gear": fe.elements[1], "meshing_position": label,
                             "fem_1e8_N_per_m": float(fe.pair_stiffness[i:i + len(s)].sum()) / 1e8})
                i += len(s)
    return pd.DataFrame(rows)


def table_wear_stiffness(scn: Scenario, cycles: list[float], n_positions: int
                         ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Table 8 and ``tvms.csv``: worn profiles from the wear model and their mesh stiffness."""
    ms = mesh_stiffness(scn.gear, scn.material)
    res = simulate_wear(scn, max(cycles), snapshots=cycles)
    single = table07_positions(ms.geometry)["single-tooth zone"]
    rows, curves = [], []
    for n in cycles:
        w1, w2 = res.snapshots[float(n)]
        k_single = float(ms.pair(single, res.s, w1, w2).sum())
        rows.append({"wear_cycles": n, "pinion_root_wear_mm": w1[0] * 1e3,
                     "single_tooth_stiffness_1e8_N_per_m": k_single / 1e8})
        cyc = ms.mesh_cycle(n_positions, res.s, w1, w2)
        curves.append(pd.DataFrame({
            "cycles": n, "roll_mm": cyc["roll"] * 1e3, "k_total_N_per_m": cyc["k_total"],
            "k_pair1_N_per_m": cyc["k_pair1"], "k_pair2_N_per_m": cyc["k_pair2"]}))
    table = pd.DataFrame(rows)
    healthy = table.single_tooth_stiffness_1e8_N_per_m.iloc[0]
    table["reduction_pct"] = (1 - table.single_tooth_stiffness_1e8_N_per_m / healthy) * 100
    return table, pd.concat(curves, ignore_index=True)


def dynamic_states(scn: Scenario, cycles: list[float]) -> tuple[WearResult, dict]:
    """Dynamically coupled wear of ``scn`` and the response of each listed wear state."""
    ms = mesh_stiffness(scn.gear, scn.material)
    res = simulate_dynamic_wear(scn, max(cycles), snapshots=cycles)
    states = {}
    for n in cycles:
        w1, w2 = res.snapshots[float(n)]
        model = build_model(scn, ms, res.s, w1, w2) if n > 0 else build_model(scn, ms)
        states[n] = (model, simulate(model, scn.dynamics))
    return res, states


def table_dynamics_vs_wear(states: dict) -> pd.DataFrame:
    """Table 9: combined error amplitude, maximum DTE and dynamic mesh force per wear state."""
    rows = []
    for n, (model, resp) in states.items():
        e = model.combined_error(resp.time)
        rows.append({"wear_cycles": n, "combined_error_amplitude_um": (e.max() - e.min()) / 2e-6,
                     "max_dte_um": float(resp.dte.max()) * 1e6,
                     "max_dynamic_mesh_force_N": float(resp.force.max())})
    return pd.DataFrame(rows)


def table_dynamic_vs_quasistatic(scn: Scenario, dynamic: WearResult) -> pd.DataFrame:
    """Table 10: pinion and gear wear under quasi-static and dynamic load at the same cycles."""
    static = simulate_wear(scn, dynamic.cycles)
    rows = [("max pinion wear", lambda r: r.pinion.max() * 1e3),
            ("average pinion wear", lambda r: r.mean_depth("pinion") * 1e3),
            ("total pinion wear", lambda r: r.worn_area("pinion") * 1e6),
            ("total gear wear", lambda r: r.worn_area("gear") * 1e6)]
    out = []
    for label, f in rows:
        qs, dy = f(static), f(dynamic)
        out.append({"quantity": label, "quasi_static_mm": qs, "dynamic_mm": dy,
                    "increase_pct": (dy / qs - 1) * 100})
    return pd.DataFrame(out)


def dte_frame(states: dict, cycles: list[float]) -> pd.DataFrame:
    """DTE and dynamic mesh force records (``dte.csv``) of the listed wear states."""
    parts = []
    for n in cycles:
        _, resp = states[n]
        parts.append(pd.DataFrame({"cycles": n, "time_s": resp.time - resp.time[0],
                                   "dte_m": resp.dte[0], "force_N": resp.force[0]}))
    return pd.concat(parts, ignore_index=True)


def evolution_tables(cfg: DictConfig, cases: list[int], cycles: np.ndarray, fit_until: float
                     ) -> tuple[pd.DataFrame, dict[int, pd.DataFrame]]:
    """Pinion root wear against cycles for each case, and the candidate-law fits (Table 12).

    Each case is the configured scenario (gear, material, lubricant, tribology, ...) with the
    operating point and lubricant values of Table 11.
    """
    curves, fits = [], {}
    for case in cases:
        scn = scenario_for_case(cfg, case)
        root, _ = root_wear_evolution(scn, cycles, dynamic=True)
        curves.append(pd.DataFrame({"case": case, "cycles": cycles, "root_wear_mm": root * 1e3}))
        fits[case] = pd.DataFrame([
            {"model": r["model"], "rmse_mm": r["rmse"], "r2": r["r2"],
             "max_relative_error_pct": r["max_relative_error_pct"]}
            for r in fit_evolution_models(cycles, root * 1e3, fit_until)])
    return pd.concat(curves, ignore_index=True), fits


def table_dte_features(res: WearResult, states: dict, cycles: list[float]) -> pd.DataFrame:
    """Table 14: DTE features of the wear states (thesis 4.2)."""
    rows = []
    for n in cycles:
        _, resp = states[n]
        f = {k: float(v[0]) for k, v in features(resp.dte).items()}
        rows.append({"cycles_1e6": n / 1e6, "wear_mm": res.snapshots[n][0][0] * 1e3,
                     "rms_1e-5_m": f["rms"] / 1e-5, "peak_to_peak_1e-5_m": f["peak_to_peak"] / 1e-5,
                     "kurtosis": f["kurtosis"], "crest": f["crest"], "margin": f["margin"],
                     "impulse": f["impulse"]})
    return pd.DataFrame(rows)


def table_estimator_accuracy(table14: pd.DataFrame, thesis_data: Path | None) -> pd.DataFrame:
    """Accuracy of the empirical-inverse estimator (thesis 4.4) in its two modes."""
    rows = []
    p2p, kurt = table14["peak_to_peak_1e-5_m"] * 1e-5, table14["kurtosis"]
    wear, cycles = table14["wear_mm"], table14["cycles_1e6"] * 1e6
    try:
        fitted = EmpiricalInverse.fit(cycles, p2p, kurt, wear)
        rows.append({"estimator": "fitted to this model (in sample)", "data": "table14 (ours)",
                     **accuracy(fitted.predict(p2p, kurt), wear)})
    except ValueError as err:
        log.warning("estimator fitted to our Table 14: %s", err)
    if thesis_data is not None:
        d = pd.read_csv(thesis_data)
        est = EmpiricalInverse.from_config("thesis")
        rows.append({"estimator": "thesis coefficients", "data": "thesis Table 14",
                     **accuracy(est.predict(d["peak_to_peak_1e-5_m"] * 1e-5, d["kurtosis"]),
                                d["wear_mm"])})
    else:
        log.info("thesis_tables=null: the check of the thesis's own estimator on its own "
                 "Table 14 is skipped")
    return pd.DataFrame(rows)


def contact_state_frame(res: WearResult, regression: WearResult | None = None) -> pd.DataFrame:
    """Contact state of the unworn pair along the path of contact (``contact_state.csv``).

    Film, pressure peak and asperity share are those of ``res``'s model (the mixed-EHL solver
    by default); ``regression``, the same scenario with ``asperity_model = "regression"``, adds
    the Masjedi-Khonsari film and share beside them.
    """
    st, rate = res.first_rate.state, res.first_rate
    df = pd.DataFrame({
        "roll_mm": res.s * 1e3, "zone": np.where(res.double, "double", "single"),
        "pair_load_N": rate.load, "half_width_um": st.half_width * 1e6,
        "p_max_MPa": st.p_max * 1e-6, "pressure_peak_MPa": st.p_peak * 1e-6,
        "sliding_velocity_m_s": st.v_s, "entraining_velocity_m_s": st.v_e,
        "h_min_nm": st.h_min * 1e9, "h_central_nm": st.h_central * 1e9,
        "film_ratio": st.film_ratio, "asperity_load_ratio_pct": st.asperity_ratio * 100,
        "flash_temperature_K": st.flash_temperature, "lubricant_density_kg_m3": st.density,
        "film_deficiency": rate.psi, "pinion_wear_rate_m_per_cycle": rate.pinion,
        "gear_wear_rate_m_per_cycle": rate.gear,
    })
    if regression is not None:
        ref = regression.first_rate.state
        df["h_min_regression_nm"] = ref.h_min * 1e9
        df["asperity_load_ratio_regression_pct"] = ref.asperity_ratio * 100
    return df


def ehl_profiles(scn: Scenario, res: WearResult) -> dict[str, EHLSolution]:
    """The mixed-EHL solver's pressure and film at the pinion root (start of contact), the
    pitch point and the pinion tip (end of contact) of the unworn pair of ``res``: direct
    solves at the load, radius and entraining velocity of its contact state."""
    st, lub, mat = res.first_rate.state, scn.lubricant, scn.material
    e_prime = 2 * reduced_modulus(mat, mat)
    out = {}
    for label, s in (("pinion root", res.s[0]), ("pitch point", 0.0), ("pinion tip", res.s[-1])):
        def at(x: np.ndarray, s: float = s) -> float:
            return float(np.interp(s, res.s, x))

        out[label] = solve_line_contact(
            at(st.load_per_width), at(st.R), at(st.v_e), e_prime, lub.eta0_Pa_s,
            lub.alpha_m2_per_N, lub.temp_visc_coeff_per_K, lub.rho0_kg_m3,
            scn.operating.bulk_temperature_K, scn.tribology.sigma_um * 1e-6)
    return out


def wear_profile_frame(res: WearResult) -> pd.DataFrame:
    """Both flanks' wear against roll coordinate and flank radius (``wear_profile.csv``)."""
    r1, r2 = res.geometry.flank_radii(res.s)
    zone = np.where(res.double, "double", "single")
    parts = [
        pd.DataFrame({"side": side, "roll_mm": res.s * 1e3, "radius_mm": r * 1e3,
                      "zone": zone, "wear_um": h * 1e6})
        for side, r, h in (("pinion", r1, res.pinion), ("gear", r2, res.gear))
    ]
    return pd.concat(parts, ignore_index=True)


def _lubricant_from_group(name: str) -> Lubricant:
    known = config_choices("lubricant")
    if name not in known:
        raise ValueError(f"lubricants: {name!r} is not in conf/physics/lubricant; choose from "
                         f"{known}")
    values = OmegaConf.create(config_file("lubricant", f"{name}.yaml").read_text())
    return scenario_from_config({"lubricant": values}).lubricant


#: the thesis's Table 14 in ``thesis_tables``, and the columns the check of its estimator reads
THESIS_TABLE14 = "table14_dte_features_case3.csv"
TABLE14_COLUMNS = ("wear_mm", "peak_to_peak_1e-5_m", "kurtosis")


def _thesis_table14(folder: str | None) -> Path | None:
    """The thesis's Table 14 CSV in ``folder`` (``thesis_tables=``), checked before any work
    with every other table of the folder the run reads (Table 15: :func:`measured_table`):
    present, UTF-8 CSV, the columns read, finite numbers."""
    if folder is None:
        return None
    path = Path(folder) / THESIS_TABLE14
    fix = thesis_tables_fix()
    if not path.is_file():
        raise ValueError(f"thesis_tables = {folder!r} holds no {THESIS_TABLE14}; {fix}")
    read_csv_table(path, "thesis_tables: Table 14", fix, numeric=TABLE14_COLUMNS)
    measured_table(Path(folder))
    return path


@dataclass
class StiffnessStudy:
    """Mesh-stiffness tables (thesis 3.1-3.2)."""

    positions: int = 200  # mesh positions per mesh period in tvms.csv
    wear_cycles: list[float] = field(default_factory=lambda: [0.0, 5e6, 1e7, 1.5e7])  # Table 8
    fem_refine: float = 4.0  # FE mesh of Table 7 (converged: see fem_convergence.csv)
    fem_refines: list[float] = field(default_factory=lambda: [1.0, 2.0, 4.0, 8.0])


@dataclass
class EvolutionStudy:
    """Dynamics and wear evolution tables (thesis 3.4-4.2)."""

    table9_cycles: list[float] = field(default_factory=lambda: [0.0, 5e6, 1e7, 1.5e7])
    table14_cycles: list[float] = field(
        default_factory=lambda: [0.0, 2e6, 4e6, 6e6, 8e6, 1e7, 1.2e7, 1.5e7])
    cases: list[int] = field(default_factory=lambda: [1, 2, 3, 4, 5])  # Table 11 cases
    cycles_max: float = 1.5e7
    points: int = 31  # cycle grid of the evolution curves
    fit_until: float = 1e7  # Table 12: fit on N <= this, judge beyond


@dataclass
class ReproduceConfig(PhysicsConfig):
    """Schema of ``python -m physics.reproduce`` (``conf/reproduce/reproduce.yaml``)."""

    #: folder of the thesis's tables, for the check of its estimator (4.4) on its own data and
    #: the measured rises beside Table 15's model; default: those shipped with the package
    #: (:data:`physics.reference.THESIS_TABLES`); null: both are left out
    thesis_tables: str | None = str(THESIS_TABLES)
    case: int | None = None  # 1-5: operating point and lubricant of thesis Table 11
    out_dir: str = "${hydra:runtime.output_dir}"
    cycles: float = 1e6  # pinion cycles of the parametric studies (thesis 2.7)
    speeds_rpm: list[float] = field(default_factory=lambda: [1000.0, 2000.0, 3000.0])  # Table 2
    torques_Nm: list[float] = field(default_factory=lambda: [250.0, 300.0, 350.0])  # Table 3
    roughness_um: list[float] = field(default_factory=lambda: [0.3, 0.5, 1.0])  # Table 4
    lubricants: list[str] = field(default_factory=lambda: ["pao", "sae30"])  # Table 5
    center_distance_offsets_pct: list[float] = field(
        default_factory=lambda: [-0.1, 0.0, 0.1])  # Table 6
    stiffness: StiffnessStudy = field(default_factory=StiffnessStudy)
    evolution: EvolutionStudy = field(default_factory=EvolutionStudy)
    #: Table 15 by the model also at every speed and torque of Tables 2 and 3 (the rig's
    #: operating point is not stated): table15_operating_points.csv and .png
    table15_operating_points: bool = True
    #: after the tables, record their sha256 in tests/reproduce/table_hashes.sha256 of the
    #: checkout (HASH_RECORD): the default run only, from a repository checkout
    record_hashes: bool = False
    #: replace the tables and figures an earlier run left in out_dir (else refused before work)
    overwrite: bool = False


@dataclass(frozen=True)
class ReproducePlan:
    """A validated reproduction: everything :func:`run` needs, nothing computed yet."""

    cfg: DictConfig
    scenario: Scenario
    lubricants: dict[str, Lubricant]
    thesis14: Path | None
    out: Path
    record: Path | None = None  # where the tables' hashes are recorded (record_hashes=true)
    run_folder: Path | None = None  # the Hydra run's folder (a new one each run)


def _positive(name: str, values: list[float], whole: bool = False) -> None:
    for v in values:
        bad = not (isinstance(v, int | float) and math.isfinite(v) and v >= 0)
        if bad or (whole and v != int(v)):
            raise ValueError(f"{name} = {v!r} must be a finite number >= 0"
                             + (" and whole" if whole else ""))


#: the most pinion cycles a table may ask for: 1e11 is 95 years at 2000 r/min
MAX_CYCLES = 1e11


def _cycles(name: str, values: list[float]) -> None:
    _positive(name, values)
    for v in values:
        if v > MAX_CYCLES:
            raise ValueError(f"{name} = {v!r} pinion cycles is beyond any gear's life (at most "
                             f"{MAX_CYCLES:g}, 95 years at 2000 r/min); give fewer cycles")


@contextlib.contextmanager
def _entry(key: str, value: float):
    """Checks of one entry of list ``key``: a refusal names the list and the entry (the
    scenario's own message names the parameter the entry sets)."""
    try:
        yield
    except ValueError as err:
        raise ValueError(f"{key}: the entry {value!r} is refused: {err}; change or drop that "
                         f"entry of {key}") from None


#: the record of the default run's tables, in the repository checkout this package is run from
#: (beside its pyproject.toml)
HASH_RECORD = Path(__file__).resolve().parents[2] / "tests" / "reproduce" / "table_hashes.sha256"
#: tables left out of the record: they follow the thesis's own data, not the physics
UNRECORDED = frozenset({"estimator_accuracy.csv"})
#: the keys that may be given with record_hashes=true: they change no recorded table
#: (thesis_tables does: Table 15's model holds the measured rises beside its own)
RECORD_KEYS = frozenset({"record_hashes", "out_dir", "overwrite"})


def table_hashes(folder: Path, names: list[str]) -> dict[str, str]:
    """The sha256 of each table ``names`` (file names) in ``folder``, but the unrecorded ones."""
    return {name: sha256_file(folder / name) for name in names if name not in UNRECORDED}


def write_hash_record(record: Path, hashes: dict[str, str]) -> Path:
    """Write ``hashes`` to ``record`` as ``sha256sum`` does (``<digest>  <name>``), sorted by
    name, atomically."""
    return write_text(record, "".join(f"{hashes[n]}  {n}\n" for n in sorted(hashes)))


def _task_overrides() -> list[str] | None:
    """The command line's overrides of this run (None outside a Hydra app)."""
    from hydra.core.hydra_config import HydraConfig

    try:
        return list(HydraConfig.get().overrides.task)
    except ValueError:  # HydraConfig not set
        return None


def _hash_record(cfg: DictConfig) -> Path | None:
    """The record to write (``record_hashes=true``), checked: it is the default run's, so the
    run must be the command's default one, run from a repository checkout."""
    if not cfg.record_hashes:
        return None
    checkout = HASH_RECORD.parents[2]
    if not (HASH_RECORD.parent.is_dir() and (checkout / "pyproject.toml").is_file()):
        raise ValueError(f"record_hashes = true: the hashes are recorded in "
                         f"tests/reproduce/{HASH_RECORD.name} of the repository checkout, and "
                         f"this package is installed without it ({checkout} holds no "
                         "pyproject.toml and tests/reproduce); run the command in a checkout "
                         "installed with pip install -e .[dev], or drop record_hashes=true")
    overrides = _task_overrides()
    if overrides is None:
        raise ValueError("record_hashes = true: the hashes are recorded by the command "
                         "python -m physics.reproduce record_hashes=true only; call it so, or "
                         "set record_hashes to false")
    changed = [o for o in overrides if o.split("=")[0].lstrip("+~") not in RECORD_KEYS]
    if changed:
        raise ValueError(f"record_hashes = true with {' '.join(changed)}: the record holds the "
                         "default run's tables, which the test compares with a default run; "
                         f"drop {' '.join(changed)} (only {', '.join(sorted(RECORD_KEYS))} may "
                         "be given with it)")
    check_writable(HASH_RECORD.parent, "record_hashes")
    return HASH_RECORD


def prepare(cfg: DictConfig) -> ReproducePlan:
    """Check the whole reproduction before any work: the hash record (``record_hashes``), the
    output folder takes files, and every scenario it will run is built and checked against the
    model's scope (:func:`physics.scope.check_scope`)."""
    record = _hash_record(cfg)
    check_writable(cfg.out_dir, "out_dir")
    check_fresh(cfg.out_dir, "out_dir", OUTPUTS, cfg.overwrite, "overwrite=true")
    thesis14 = _thesis_table14(cfg.thesis_tables)
    if thesis14 is not None:
        check_outside(cfg.out_dir, "out_dir", {
            "thesis_tables": cfg.thesis_tables, "the thesis's Table 14": thesis14,
            "the thesis's Table 15": thesis14.parent / MEASURED_TABLE})
    scn = check_record(scenario_from_config(cfg))
    lubs = {lub.name: lub for lub in map(_lubricant_from_group, cfg.lubricants)}
    st, ev = cfg.stiffness, cfg.evolution
    _cycles("cycles", [cfg.cycles])
    for name in ("speeds_rpm", "torques_Nm", "roughness_um"):
        if not cfg[name]:
            raise ValueError(f"{name} is empty; give at least one value")
    check_scenario(scn)
    for n in cfg.speeds_rpm:
        with _entry("speeds_rpm", n):
            check_scenario(check_scope(_with(scn, "operating", n1_rpm=n)))
    for t in cfg.torques_Nm:
        with _entry("torques_Nm", t):
            check_scenario(check_scope(_with(scn, "operating", torque_Nm=t)))
    for s in cfg.roughness_um:
        with _entry("roughness_um", s):
            check_scenario(_with(scn, "tribology", sigma_um=s))
    for lub in lubs.values():
        check_scenario(dataclasses.replace(scn, lubricant=lub))
    for off in cfg.center_distance_offsets_pct:
        a = scn.gear.standard_center_distance_mm * (1 + off / 100)
        with _entry("center_distance_offsets_pct", off):
            check_scenario(_with(scn, "gear", center_distance_mm=a))
    _cycles("stiffness.wear_cycles", list(st.wear_cycles))
    _cycles("evolution.table9_cycles", list(ev.table9_cycles))
    _cycles("evolution.table14_cycles", list(ev.table14_cycles))
    _cycles("evolution.cycles_max", [ev.cycles_max])
    if not ev.table9_cycles or not ev.table14_cycles:
        raise ValueError("evolution.table9_cycles and evolution.table14_cycles need at least "
                         "one value each")
    if not 0 < ev.fit_until <= ev.cycles_max or ev.points < 5:
        raise ValueError(f"evolution: fit_until = {ev.fit_until} must lie in (0, cycles_max = "
                         f"{ev.cycles_max}] and points = {ev.points} must be >= 5")
    _check_fit_grid(int(ev.points), float(ev.fit_until), float(ev.cycles_max))
    if st.positions < 10 or min(st.fem_refines, default=1) <= 0 or st.fem_refine <= 0:
        raise ValueError(f"stiffness: positions = {st.positions} must be >= 10 and the FE "
                         "refinements > 0")
    for case in ev.cases:
        check_scenario(check_record(scenario_for_case(cfg, case)))
    return ReproducePlan(cfg, scn, lubs, thesis14, resolved(cfg.out_dir), record,
                         _hydra_run_folder())


#: the kinds of file a run writes into out_dir (an earlier run's are refused without overwrite)
OUTPUTS = ("*.csv", "*.png")
#: the points of the evolution grid Table 12's fits need at N <= fit_until and beyond it
#: (:func:`physics.dynamics.evolution.fit_evolution_models`)
FIT_POINTS, JUDGED_POINTS = 5, 2


def evolution_grid(points: int, cycles_max: float) -> np.ndarray:
    """The cycle grid of the evolution curves and Table 12's fits."""
    return np.linspace(0.0, cycles_max, points)


def _check_fit_grid(points: int, fit_until: float, cycles_max: float) -> None:
    """Refuse (ValueError, one line) an evolution grid on which Table 12's fits cannot run:
    fewer than :data:`FIT_POINTS` points at ``N <= fit_until`` or fewer than
    :data:`JUDGED_POINTS` beyond it; the message names the grid and the points that would do."""
    def counts(n: int) -> tuple[int, int]:
        grid = evolution_grid(n, cycles_max)
        return int((grid <= fit_until).sum()), int((grid > fit_until).sum())

    def enough(n: int) -> bool:
        fit, judged = counts(n)
        return fit >= FIT_POINTS and judged >= JUDGED_POINTS

    if enough(points):
        return
    fit, judged = counts(points)
    # the grid's share beyond fit_until is about 1 - fit_until / cycles_max: the first grid
    # that holds the points needed lies near the count that share asks for
    share = 1.0 - fit_until / cycles_max
    start = max(points, int(max(FIT_POINTS / (1.0 - share), JUDGED_POINTS / share)) - 2
                if share > 0 else points)
    found = next((n for n in range(start, start + 50) if enough(n)), None) if share > 1e-4 else None
    fix = (f"give evolution.points={found} or more, or move evolution.fit_until"
           if found is not None else "lower evolution.fit_until below evolution.cycles_max")
    raise ValueError(f"evolution.points = {points} (a grid from 0 to evolution.cycles_max = "
                     f"{cycles_max:g}) puts {fit} cycle counts at N <= evolution.fit_until = "
                     f"{fit_until:g} and {judged} beyond it; Table 12's fits need >= "
                     f"{FIT_POINTS} and >= {JUDGED_POINTS}: {fix}")


def _hydra_run_folder() -> Path | None:
    """This Hydra run's folder, resolved (None outside a Hydra app)."""
    from hydra.core.hydra_config import HydraConfig

    try:
        return resolved(HydraConfig.get().runtime.output_dir)
    except (ValueError, AttributeError):
        return None


def interrupted_note(plan: ReproducePlan) -> str:
    """What an interrupted reproduction kept and how to compute the rest, truly: the folder is
    named only where it exists; a rerun into the same folder needs ``overwrite=true`` once it
    holds tables (:func:`physics.files.check_fresh`), while a run into its own new Hydra folder
    (the default ``out_dir``) does not."""
    out = plan.out
    written = (sorted(p.name for pattern in OUTPUTS for p in out.glob(pattern) if p.is_file())
               if out.is_dir() else [])
    if not written:
        return "no table was written yet; run the command again"
    where = f"{len(written)} table(s) and figure(s) written so far are in {out}"
    if plan.run_folder is not None and out == plan.run_folder:
        return f"{where}; run the command again to compute them all (in a new run folder)"
    if plan.cfg.overwrite:
        return f"{where}; run the same command again (with its overwrite=true) to compute them all"
    return (f"{where}; run the command again with overwrite=true to compute them all (without "
            f"it, out_dir={out} is refused, as it holds these files)")


def reproduce(cfg: DictConfig) -> dict[str, pd.DataFrame]:
    """Check ``cfg`` (:func:`prepare`), compute every table and write it (:func:`run`)."""
    return run(prepare(cfg))


def run(plan: ReproducePlan) -> dict[str, pd.DataFrame]:
    """Compute every table of this module and write it into ``plan.out``."""
    cfg, scn, lubs, out = plan.cfg, plan.scenario, plan.lubricants, plan.out
    cycles = float(cfg.cycles)
    tables = {
        "table02_speed": table_speed(scn, cycles, list(cfg.speeds_rpm)),
        "table03_torque": table_torque(scn, cycles, list(cfg.torques_Nm)),
        "table04_roughness": table_roughness(scn, cycles, list(cfg.roughness_um)),
        "table05_lubricant": table_lubricant(scn, cycles, lubs),
        "table06_center_distance": table_center_distance(
            scn, cycles, list(cfg.center_distance_offsets_pct)),
    }
    stiff = cfg.stiffness
    tables["table07_tvms_energy_vs_fem"] = table_tvms_fem(scn, float(stiff.fem_refine))
    tables["fem_convergence"] = table_fem_convergence(scn, [float(r) for r in stiff.fem_refines])
    tables["table08_wear_vs_stiffness"], tables["tvms"] = table_wear_stiffness(
        scn, [float(c) for c in stiff.wear_cycles], int(stiff.positions))
    dyn_cfg = cfg.evolution
    t9 = [float(c) for c in dyn_cfg.table9_cycles]
    t14 = [float(c) for c in dyn_cfg.table14_cycles]
    dynamic, states = dynamic_states(scn, sorted(set(t9) | set(t14)))
    tables["table14_dte_features_case3"] = table_dte_features(dynamic, states, t14)
    tables["estimator_accuracy"] = table_estimator_accuracy(
        tables["table14_dte_features_case3"], plan.thesis14)
    tables["table09_dynamics_vs_wear"] = table_dynamics_vs_wear({n: states[n] for n in t9})
    tables["table10_dynamic_vs_quasistatic"] = table_dynamic_vs_quasistatic(scn, dynamic)
    tables["dte"] = dte_frame(states, [t9[0], t9[-1]])
    grid = evolution_grid(int(dyn_cfg.points), float(dyn_cfg.cycles_max))
    tables["wear_evolution"], fits = evolution_tables(
        cfg, [int(c) for c in dyn_cfg.cases], grid, float(dyn_cfg.fit_until))
    for case, df in fits.items():
        tables[f"table12_evolution_fits_case{case}"] = df
    base = simulate_wear(scn, cycles)
    tables["wear_profile"] = wear_profile_frame(base)
    tables["table15_model"] = table15_model(
        scn, base, None if plan.thesis14 is None else plan.thesis14.parent)
    if cfg.table15_operating_points:
        tables["table15_operating_points"] = table15_operating_points(
            scn, base, list(cfg.speeds_rpm), list(cfg.torques_Nm))
    mixed = scn.tribology.regime == "mixed"
    regression = (simulate_wear(_with(scn, "tribology", asperity_model="regression"), 0.0)
                  if mixed and scn.tribology.asperity_model == "solver" else None)
    tables["contact_state"] = contact_state_frame(base, regression)
    for name, df in tables.items():
        write_csv(df, out / f"{name}.csv")
    plots.plot_wear_profile(base, out / "wear_profile.png")
    plots.plot_tvms(tables["tvms"], out / "tvms.png")
    model = next(iter(states.values()))[0]
    plots.plot_dte_spectrum(tables["dte"], model.mesh_frequency_hz,
                            scn.dynamics.sample_rate_hz, out / "dte_spectrum.png")
    plots.plot_wear_evolution(tables["wear_evolution"], out / "wear_evolution.png")
    plots.plot_feature_trends(tables["table14_dte_features_case3"], out / "feature_trends.png")
    plots.plot_table15(tables["table15_model"], out / "table15_model.png")
    if "table15_operating_points" in tables:
        plots.plot_table15_operating_points(
            tables["table15_operating_points"], tables["table15_model"],
            out / "table15_operating_points.png")
    if mixed:
        plots.plot_ehl_pressure_film(ehl_profiles(scn, base), out / "ehl_pressure_film.png")
    log.info("wrote %d tables and wear_profile.png to %s", len(tables), out)
    if plan.record is not None:
        hashes = table_hashes(out, [f"{name}.csv" for name in tables])
        write_hash_record(plan.record, hashes)
        log.info("recorded the hashes of %d tables in %s", len(hashes), plan.record)
    return tables
