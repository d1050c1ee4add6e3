"""Wear and vibration datasets across the operating cases of thesis Table 11 (thesis 4.1-4.3).

One *unit* of work is one replicate of one case: its operating point is jittered (seeded), the
dynamically coupled wear evolution is run over the cycle grid, every wear state's DTE is
simulated (one batch), the declared measurement chain of :mod:`physics.measurement` gives the
DTE and the housing acceleration, noise is added at the configured SNR (seeded), and the
features of :mod:`physics.features` are taken of both (columns ``dte_*`` and ``acc_*``).
A unit gives one row per cycle count.

Units are grouped in *chunks*, the independent jobs of a Hydra multirun; each chunk is written
atomically to ``<name>_chunks/chunk_<i>.parquet`` under the output folder; the folder's
``manifest.json`` holds, per finished chunk, the hash of everything that determines it and the
sha256 of the chunk's bytes. A finished chunk of the same hash whose bytes still match is not
computed again (a killed run resumes); one whose bytes do not (damaged on disk) is set aside as
``*.damaged`` with a warning and computed again, on resume and before the merge. One build
writes a dataset at a time (:func:`acquire_output`). The storage (manifest, chunk states,
locks) is :mod:`physics.dataset.chunks`. :func:`merge` joins the chunks into
``<name>.parquet`` and a JSON sidecar. Everything is seeded, so the same config gives
byte-identical files.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import math
import numbers
import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib.metadata import version
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from joblib import delayed
from tqdm import tqdm

from physics.dataset.chunks import (
    chunk_folder,
    chunk_is_done,
    chunk_path,
    chunk_state,
    lock_file,
    read_manifest,
    record_chunk,
    set_aside_damaged,
    take_dataset_lock,
)
from physics.dynamics.evolution import simulate_dynamic_wear
from physics.dynamics.model import build_model, simulate
from physics.dynamics.model_form import FACTORS
from physics.files import atomic_write, check_writable, read_lock, release_lock, sha256_file
from physics.gear.stiffness import MeshStiffness, SainsotRangeWarning, mesh_stiffness
from physics.interrupt import shielded, worker_results
from physics.params import (
    OutOfScope,
    PhysicsConfig,
    Scenario,
    bounded,
    case_values,
    operating_cases,
    scenario_from_config,
    validate_fields,
)
from physics.scope import check_record, mesh_frequency_hz
from physics.signals.features import FEATURES, feature_units, features
from physics.signals.measurement import add_noise, housing_acceleration, transfer_path
from physics.signals.order_analysis import (
    LINE_ORDERS,
    MESH_ORDERS,
    PHASE_PARTS,
    VECTOR_PARTS,
    mesh_harmonics,
)
from physics.tribology.asperity_table import check_scenario

log = logging.getLogger(__name__)
#: the rows' layout; part of the digest, so chunks of another layout are not reused
SCHEMA_VERSION = 4
#: columns besides the features, with their units
BASE_COLUMNS = {
    "case": "1", "replicate": "1", "cycles": "1", "n1_rpm": "r/min", "torque_Nm": "N m",
    "eta0_Pa_s": "Pa s", "sigma_um": "um", "root_wear_mm": "mm", "max_wear_mm": "mm",
    "mean_wear_mm": "mm",
}
#: the pinion flank's form deviation (:func:`physics.gear.accuracy.form_deviation`): its
#: parameters and their units
FORM = {"form_deviation_um": "um", "form_waves": "1", "form_phase_rad": "rad"}
#: the dynamics parameters a trajectory draws (:class:`NuisanceRanges`)
DYNAMIC_NUISANCE = ("damping_ratio", "eccentricity1_um", "profile_error_um", "half_backlash_um",
                    "housing_mass_kg", *FACTORS, *FORM)
#: the drawn nuisance kept as columns (for analysis; not network inputs), with their units
NUISANCE_COLUMNS = {"damping_ratio": "1", "eccentricity1_um": "um", "profile_error_um": "um",
                    "half_backlash_um": "um", "housing_mass_kg": "kg", "transfer_fn_hz": "Hz",
                    "transfer_zeta": "1", "snr_db": "dB", "wear_coeff_factor": "1",
                    "boundary_share": "1", **{f: "1" for f in FACTORS}, **FORM}


@dataclass(frozen=True)
class NuisanceRanges:
    """What a real gearbox never matches exactly, drawn per trajectory (uniform; the wear
    coefficient's factor log-uniform) so that a network trained on the dataset learns wear, not
    one gearbox. ``data.nuisance.*`` in the configs; each range ``[low, high]``.

    - operating point: the case's speed and torque of Table 11 times ``U(1 -+ pct/100)``
      (``speed_pct``, ``torque_pct``): the envelope around Table 11;
    - ``damping_ratio``: 0.03-0.17 of critical, the whole span Kasuba & Evans (ASME J. Mech.
      Des. 103 (1981) 398) report for spur meshes;
    - ``eccentricity1_um`` (half the pinion's radial run-out) and ``profile_error_um`` (half its
      profile form tolerance): ISO 1328 accuracy grades 4 to 9, the span of industrial spur
      gearboxes from ground to hobbed unground teeth, for the thesis's pinion (m 2 mm, d 36
      mm; :mod:`physics.gear.accuracy`): run-out ``F_r = 0.8 F_p`` (ISO 1328-2:1997, annex B)
      8-46 um, profile form (ISO 1328-1:1995) 2.8-16 um;
    - ``half_backlash_um``: 47.5-152 um, half the normal backlash from the ISO/TR 10064-2:1996
      minimum ``(2/3)(0.06 + 0.0005 a + 0.03 m)`` mm of a = 45 mm, m 2 (95 um) to the largest
      backlash of a grade-9 pair built for it: both teeth thinner by their tooth thickness
      tolerance ``T_sn = 2 tan(alpha) sqrt(F_r^2 + b_r^2)`` (ISO/TR 10064-2) and the centre
      distance at its upper allowance (:func:`physics.gear.accuracy.maximum_backlash_um`,
      304 um);
    - ``housing_mass_kg``: 10-40 kg, effective mass of small single-stage housings (no source
      gives a wider span for this size; the measured-data loop calibrates it);
    - ``transfer_fn_hz``, ``transfer_zeta``: one housing resonance between mesh and accelerometer
      (2-8 kHz, 2-10 % damping: the first plate modes of small cast gearboxes);
    - ``snr_db``: 20-40 dB measurement noise relative to the AC power;
    - ``wear_coeff_factor``: the wear coefficient of the wear law times 0.5-2 (the spread of
      Archard coefficients measured for one steel pair; Stachowiak & Batchelor, Engineering
      Tribology, 4th ed., ch. 12);
    - ``boundary_share``: the share of running time under boundary lubrication, worn by the
      dry law (``physics.params.Tribology``): ``[0, 1]``, the thesis's lubricated (2.6) and dry
      (2.7.5) laws as end members. No measurement fixes it for a given gearbox, and
      the worn profile's shape follows it (case 3 after 1.5e7 cycles: root wear 6.7 times the
      path average under the lubricated law, 2.6 times under the dry law); ``[0, 0]`` trains
      on the lubricated law alone;
    - ``stiffness_factor`` 0.6-1.6, ``double_contact_factor`` 0.7-1.5, ``resonance_factor``
      0.6-1.6: the declared model's form uncertainty (:mod:`physics.dynamics.model_form`;
      log-uniform; ``[1, 1]`` is the thesis model). ISO 6336-1, the potential-energy method
      and finite-element or measured stiffnesses of one pair differ by 10-30 %, a mount's
      compliance in series lowers the level, and the blanks' inertias leave out shafts, hubs
      and couplings (a lower resonance) while lateral modes couple in: about twice that
      scatter either way.

    - ``form_deviation_um`` 1.4-8.0 um, ``form_waves`` 1-6, ``form_phase_rad`` 0-2 pi: the
      pinion flank's profile form deviation (:func:`physics.gear.accuracy.form_deviation`),
      half its peak-to-valley over the span of ``profile_error_um`` (half ``f_f_alpha`` of
      grades 4-9), one to six half-waves over the active profile (from a bulge or hollow to
      grinding or feed waviness; an assumption, no source states the span), at any phase: the
      unit-to-unit shape of the transmission error over a mesh period, which the mesh-rate
      sinusoid alone leaves the same for every gearbox.

    What training over these spans costs on gearboxes inside narrow ranges, and buys beyond
    them: docs/benchmark.md (Training ranges).
    """

    speed_pct: float = bounded(10.0, 0.0, 50.0, closed=True)
    torque_pct: float = bounded(10.0, 0.0, 50.0, closed=True)
    damping_ratio: list[float] = field(default_factory=lambda: [0.03, 0.17])
    eccentricity1_um: list[float] = field(default_factory=lambda: [4.0, 23.0])
    profile_error_um: list[float] = field(default_factory=lambda: [1.4, 8.0])
    half_backlash_um: list[float] = field(default_factory=lambda: [47.5, 152.0])
    housing_mass_kg: list[float] = field(default_factory=lambda: [10.0, 40.0])
    transfer_fn_hz: list[float] = field(default_factory=lambda: [2000.0, 8000.0])
    transfer_zeta: list[float] = field(default_factory=lambda: [0.02, 0.10])
    snr_db: list[float] = field(default_factory=lambda: [20.0, 40.0])
    wear_coeff_factor: list[float] = field(default_factory=lambda: [0.5, 2.0])
    boundary_share: list[float] = field(default_factory=lambda: [0.0, 1.0])
    stiffness_factor: list[float] = field(default_factory=lambda: [0.6, 1.6])
    double_contact_factor: list[float] = field(default_factory=lambda: [0.7, 1.5])
    resonance_factor: list[float] = field(default_factory=lambda: [0.6, 1.6])
    form_deviation_um: list[float] = field(default_factory=lambda: [1.4, 8.0])
    form_waves: list[float] = field(default_factory=lambda: [1.0, 6.0])
    form_phase_rad: list[float] = field(default_factory=lambda: [0.0, 2 * math.pi])

    #: the physical limits each range must lie in
    LIMITS: ClassVar[dict[str, tuple[float, float]]] = {
        "damping_ratio": (0.0, 1.0), "eccentricity1_um": (0.0, 1000.0),
        "profile_error_um": (0.0, 1000.0), "half_backlash_um": (0.0, 1e4),
        "housing_mass_kg": (1e-3, 1e5), "transfer_fn_hz": (10.0, 20000.0),
        "transfer_zeta": (1e-3, 0.9), "snr_db": (-20.0, 200.0), "wear_coeff_factor": (1e-3, 1e3),
        "boundary_share": (0.0, 1.0), **{f: (0.1, 10.0) for f in FACTORS},
        "form_deviation_um": (0.0, 1000.0), "form_waves": (0.1, 100.0),
        "form_phase_rad": (0.0, 2 * math.pi)}
    #: the ranges drawn log-uniformly (factors); the rest uniformly
    LOG: ClassVar[tuple[str, ...]] = ("wear_coeff_factor", *FACTORS)

    def __post_init__(self) -> None:
        validate_fields(self, "data.nuisance")
        for name, (lo_ok, hi_ok) in self.LIMITS.items():
            v = getattr(self, name)
            ok = (len(v) == 2 and all(isinstance(x, numbers.Real) and not isinstance(x, bool)
                                      and math.isfinite(x) for x in v)
                  and lo_ok <= v[0] <= v[1] <= hi_ok)
            if not ok:
                raise ValueError(f"data.nuisance.{name} = {list(v)!r} must be [low, high] with "
                                 f"{lo_ok:g} <= low <= high <= {hi_ok:g}")
            object.__setattr__(self, name, [float(x) for x in v])

    def draw(self, rng: np.random.Generator) -> dict[str, float]:
        """One trajectory's values: the operating-point factors and every range."""
        out = {"speed_factor": 1 + rng.uniform(-1, 1) * self.speed_pct / 100,
               "torque_factor": 1 + rng.uniform(-1, 1) * self.torque_pct / 100}
        for name in self.LIMITS:
            lo, hi = getattr(self, name)
            u = rng.uniform()
            out[name] = lo * (hi / lo) ** u if name in self.LOG else lo + u * (hi - lo)
        return out


#: chunks of a dataset where ``data.chunks`` is not given (fewer where it has fewer units)
CHUNKS = 5


@dataclass(frozen=True)
class DatasetSpec:
    """What a dataset holds; validated on construction."""

    cases: tuple[int, ...] = (1, 2, 3, 4, 5)
    cycles_max: float = bounded(1.5e7, 0.0, 1e10, "pinion cycles of the last wear state")
    wear_states: int = bounded(8, 2, 100_000, "cycle counts per replicate", whole=True)
    #: many gearboxes, few wear states each: the features' spread comes from the nuisance far
    #: more than from wear (docs/surrogate.md, Alternatives considered)
    replicates: int = bounded(64, 1, 100_000, whole=True)
    nuisance: NuisanceRanges = field(default_factory=NuisanceRanges)
    seed: int = bounded(0, 0, 2**32 - 1, whole=True)
    #: independent jobs; None: :data:`CHUNKS`, or one per unit where there are fewer
    chunks: int | None = bounded(None, 1, 100_000, "independent jobs", whole=True)

    def __post_init__(self) -> None:
        validate_fields(self, "data")
        valid = sorted(operating_cases())
        for c in self.cases:
            case_values(c)  # raises, listing the valid cases
        object.__setattr__(self, "cases", tuple(int(c) for c in self.cases))
        if len(set(self.cases)) != len(self.cases) or not self.cases:
            raise ValueError(f"data.cases = {list(self.cases)} must be distinct, from {valid}")
        if isinstance(self.nuisance, Mapping):  # a dict or a Hydra DictConfig
            object.__setattr__(self, "nuisance", NuisanceRanges(**self.nuisance))
        if self.chunks is None:
            object.__setattr__(self, "chunks", min(CHUNKS, self.units))
        if self.chunks > self.units:
            raise ValueError(f"data.chunks = {self.chunks} must lie in [1, {self.units}] (one "
                             "unit is a case-replicate pair)")

    @property
    def units(self) -> int:
        return len(self.cases) * self.replicates

    def cycles(self) -> np.ndarray:
        return np.linspace(0.0, self.cycles_max, self.wear_states)

    def chunk_units(self, chunk: int) -> list[tuple[int, int]]:
        """The (case, replicate) pairs of chunk ``chunk`` (0-based), in a fixed order."""
        if not 0 <= chunk < self.chunks:
            raise ValueError(f"chunk = {chunk} must lie in [0, {self.chunks - 1}]")
        pairs = [(c, r) for c in self.cases for r in range(self.replicates)]
        return pairs[chunk::self.chunks]


def unit_draw(spec: DatasetSpec, case: int, replicate: int) -> dict[str, float]:
    """The seeded nuisance values of one trajectory (:class:`NuisanceRanges`)."""
    return spec.nuisance.draw(np.random.default_rng([spec.seed, case, replicate, 0]))


def unit_scenario(base: Scenario, spec: DatasetSpec, case: int, replicate: int) -> Scenario:
    """The case's operating point and lubricant (Table 11) with this trajectory's draws."""
    values, d = case_values(case), unit_draw(spec, case, replicate)
    op = dataclasses.replace(base.operating, n1_rpm=values["n1_rpm"] * d["speed_factor"],
                             torque_Nm=values["torque_Nm"] * d["torque_factor"])
    lub = dataclasses.replace(base.lubricant, eta0_Pa_s=values["eta0_Pa_s"],
                              alpha_m2_per_N=values["alpha_m2_per_N"],
                              limiting_shear_coeff=values["limiting_shear_coeff"])
    dyn = dataclasses.replace(base.dynamics, **{k: d[k] for k in DYNAMIC_NUISANCE})
    tri = dataclasses.replace(
        base.tribology, wear_coeff=base.tribology.wear_coeff * d["wear_coeff_factor"],
        dry_wear_coeff=base.tribology.dry_wear_coeff * d["wear_coeff_factor"],
        boundary_share=d["boundary_share"])
    return dataclasses.replace(base, operating=op, lubricant=lub, dynamics=dyn, tribology=tri)


def run_unit(base: Scenario, spec: DatasetSpec, case: int, replicate: int,
             keep_signals: bool = False) -> tuple[pd.DataFrame, np.ndarray | None]:
    """Rows (one per cycle count) of one case-replicate pair, and optionally its records.

    The records are ``(row, 2, sample)``: the noisy DTE [m] and housing acceleration [m/s^2].
    """
    scn = unit_scenario(base, spec, case, replicate)
    cycles = spec.cycles()
    ms = mesh_stiffness(scn.gear, scn.material)
    res = simulate_dynamic_wear(scn, float(cycles[-1]), snapshots=list(cycles))
    models, wear = [], []
    for n in cycles:
        w1, w2 = res.snapshots[float(n)]
        models.append(build_model(scn, ms, res.s, w1, w2) if np.any(w1 + w2 > 0)
                      else build_model(scn, ms))
        wear.append((w1[0], w1.max(), float(np.trapezoid(w1, res.s) / np.ptp(res.s))))
    response = simulate(models, scn.dynamics, every_phase=False)  # the records' signals alone
    d = unit_draw(spec, case, replicate)
    rng = np.random.default_rng([spec.seed, case, replicate, 1])
    dte = add_noise(response.dte, d["snr_db"], rng)
    acc = transfer_path(housing_acceleration(response.force, scn.dynamics.housing_mass_kg),
                        scn.dynamics.sample_rate_hz, d["transfer_fn_hz"], d["transfer_zeta"])
    acc = add_noise(acc, d["snr_db"], rng)
    dte_f, acc_f = features(dte), features(acc)
    f_mesh = mesh_frequency_hz(scn)
    # the records' lines against mesh phase zero (t = 0), the mesh phase of their first
    # sample being 2 pi f_mesh time[0]: a tachometer's reference, the same for every record
    dte_h = mesh_harmonics(dte, scn.dynamics.sample_rate_hz, f_mesh,
                           start_phase_rad=2 * np.pi * f_mesh * response.time[0])
    wear = np.array(wear) * 1e3
    rows = pd.DataFrame({
        "case": case, "replicate": replicate, "cycles": cycles,
        "n1_rpm": scn.operating.n1_rpm, "torque_Nm": scn.operating.torque_Nm,
        "eta0_Pa_s": scn.lubricant.eta0_Pa_s, "sigma_um": scn.tribology.sigma_um,
        "root_wear_mm": wear[:, 0], "max_wear_mm": wear[:, 1], "mean_wear_mm": wear[:, 2],
        **{k: d[k] for k in NUISANCE_COLUMNS},
        **{f"dte_{k}": dte_f[k] for k in FEATURES},
        **{f"acc_{k}": acc_f[k] for k in FEATURES},
        **{f"dte_{k}": v for k, v in dte_h.items()},
    })
    numbers = rows.select_dtypes("number")
    bad = ~np.isfinite(numbers.to_numpy(float))
    if bad.any():  # a model failure is an error, never a row
        r, c = np.argwhere(bad)[0]
        raise FloatingPointError(f"case {case}, replicate {replicate}: the model gave a "
                                 f"non-finite {numbers.columns[c]} at {cycles[r]:g} cycles")
    signals = np.stack([dte, acc], axis=1).astype(np.float32) if keep_signals else None
    return rows, signals


def units() -> dict[str, str]:
    """Unit of every column of the dataset."""
    out = dict(BASE_COLUMNS) | NUISANCE_COLUMNS
    out.update({f"dte_{k}": u for k, u in feature_units("m").items()})
    out.update({f"acc_{k}": u for k, u in feature_units("m/s^2").items()})
    out.update({f"dte_mesh{k}_db": "dB" for k in MESH_ORDERS})
    out.update({f"dte_mesh{k}_{f}": "1" for k in MESH_ORDERS for f in PHASE_PARTS})
    out.update({f"dte_line{k}_{p}": "m" for k in LINE_ORDERS for p in VECTOR_PARTS})
    return out


def config_hash(payload: dict[str, Any]) -> str:
    """Stable hash of everything that determines the data (the resolved config)."""
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _write_parquet(df: pd.DataFrame, path: Path, meta: dict[str, str]) -> None:
    table = pa.Table.from_pandas(df, preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           **{k.encode(): v.encode() for k, v in meta.items()}})
    atomic_write(path, lambda p: pq.write_table(table, p, compression="zstd"))


def run_chunk(base: Scenario, spec: DatasetSpec, chunk: int, folder: Path, digest: str,
              keep_signals: bool = False) -> bool:
    """Compute and write one chunk into ``folder`` unless it is there; True if computed.
    The chunk's sha256 goes into the folder's manifest once its files are in place."""
    path = chunk_path(folder, chunk)
    if chunk_is_done(folder, chunk, digest, keep_signals):
        return False
    frames, signals, left = [], [], []
    with warnings.catch_warnings():
        # the gear's range warning is issued once by the caller (generate), not once per unit
        warnings.simplefilter("ignore", SainsotRangeWarning)
        for case, rep in spec.chunk_units(chunk):
            try:
                rows, sig = run_unit(base, spec, case, rep, keep_signals)
            except OutOfScope as err:  # this gearbox failed: recorded, not a row
                left.append({"case": case, "replicate": rep, "reason": str(err)})
                continue
            frames.append(rows)
            if sig is not None:
                signals.append(sig)
    signals_sha = None
    if keep_signals:
        stack = np.concatenate(signals) if signals else np.empty((0, 2, 0), np.float32)
        npy = path.with_suffix(".npy")
        atomic_write(npy, lambda p: np.save(p.open("wb"), stack))
        signals_sha = sha256_file(npy)
    df = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=list(units()))
    _write_parquet(df, path, {"gearwear_hash": digest, "gearwear_left_scope": json.dumps(left)})
    record_chunk(folder, path.name, {"hash": digest, "sha256": sha256_file(path),
                                      "signals_sha256": signals_sha})
    return True


def left_scope(path: Path) -> list[dict]:
    """The trajectories of a finished chunk that left the model's scope (:func:`run_chunk`)."""
    meta = pq.read_schema(path).metadata or {}
    return json.loads(meta.get(b"gearwear_left_scope", b"[]").decode())


def _read_chunk(path: Path) -> tuple[pd.DataFrame, list[dict]]:
    try:
        return pq.read_table(path).to_pandas(), left_scope(path)
    except (OSError, pa.ArrowException, ValueError) as err:
        raise ValueError(f"chunk {path} cannot be read ({type(err).__name__}); set it aside "
                         "(rename it) and run the same command again to compute it") from None


def merge(spec: DatasetSpec, out: Path, name: str, digest: str, sidecar: dict[str, Any],
          keep_signals: bool = False) -> Path:
    """Join the finished chunks into ``<name>.parquet`` (+ ``.json``, and ``_signals.npy``).
    Each chunk is checked against the sha256 in the manifest first; the sidecar holds the
    sha256 of the files it describes."""
    folder = chunk_folder(out, name)
    manifest = read_manifest(folder)
    states = {c: chunk_state(folder, c, digest, keep_signals, manifest)
              for c in range(spec.chunks)}
    missing = [c for c, s in states.items() if s != "done"]
    if missing:
        raise ValueError(f"chunks {missing} of this config (hash {digest}) in {folder} are "
                         f"{sorted({states[c] for c in missing})}, not as the manifest records "
                         "them; a whole build (python -m physics.dataset without chunk=, or "
                         "build_dataset) computes them again before it merges")
    read = [_read_chunk(chunk_path(folder, c)) for c in range(spec.chunks)]
    df = pd.concat([f for f, _ in read], ignore_index=True)
    left = [u for _, lft in read for u in lft]
    if left:
        log.warning("%d of %d trajectories left the model's scope during their wear life and "
                    "are not in the dataset (listed in %s.json, left_scope): %s", len(left),
                    spec.units, name, ", ".join(f"case {u['case']} replicate {u['replicate']}"
                                                for u in left))
    order = np.lexsort((df.cycles.to_numpy(), df.replicate.to_numpy(), df.case.to_numpy()))
    df = df.iloc[order].reset_index(drop=True)
    target = out / f"{name}.parquet"
    _write_parquet(df, target, {"gearwear_hash": digest})
    shas = {"sha256": sha256_file(target)}
    if keep_signals:
        sig = np.concatenate([np.load(chunk_path(folder, c).with_suffix(".npy"))
                              for c in range(spec.chunks)])[order]
        sig_path = out / f"{name}_signals.npy"
        atomic_write(sig_path, lambda p: np.save(p.open("wb"), sig))
        shas["signals_sha256"] = sha256_file(sig_path)
    text = json.dumps({**sidecar, "schema_version": SCHEMA_VERSION, "hash": digest,
                       "rows": len(df), "units": units(), "left_scope": left, **shas},
                      indent=2, sort_keys=True, default=str)
    atomic_write(out / f"{name}.json", lambda p: p.write_text(text + "\n"))
    return target


def spec_from_config(data: dict[str, Any]) -> DatasetSpec:
    fields = {f.name for f in dataclasses.fields(DatasetSpec)}
    unknown = sorted(set(data) - fields)
    if unknown:
        raise ValueError(f"data: unknown key(s) {unknown}; allowed: {sorted(fields)}")
    values = dict(data)
    if "cases" in values:
        values["cases"] = tuple(values["cases"])
    return DatasetSpec(**values)


NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


@dataclass
class DatasetConfig(PhysicsConfig):
    """Schema of ``python -m physics.dataset`` (``conf/dataset/dataset.yaml``)."""

    data: DatasetSpec = field(default_factory=DatasetSpec)
    out_dir: str = "data"  # relative to the folder the command runs in
    name: str = "dataset"  # <out_dir>/<name>.parquet, <name>.json (and <name>_signals.npy)
    chunk: int | None = None  # null: every chunk, then merge; i: only chunk i (multirun job)
    store_signals: bool = False  # also keep the noisy records (float32) beside the parquet
    progress: bool = True
    jobs: int = 2  # chunks run in parallel processes


@dataclass(frozen=True)
class DatasetJob:
    """A checked dataset build: what to compute and where (nothing computed yet)."""

    base: Scenario
    spec: DatasetSpec
    out: Path
    name: str
    todo: tuple[int, ...]  # chunks still to compute
    merge: bool  # all chunks were asked for: join them when done
    jobs: int = 2
    store_signals: bool = False
    progress: bool = True
    chunk: int | None = None  # the one chunk asked for (a multirun job), None for all

    @property
    def digest(self) -> str:
        return dataset_digest(self.base, self.spec)

    @property
    def folder(self) -> Path:
        return chunk_folder(self.out, self.name)

    @property
    def path(self) -> Path:
        return self.out / f"{self.name}.parquet"


def dataset_digest(base: Scenario, spec: DatasetSpec) -> str:
    """Hash of everything that determines the rows (the physics and the dataset spec)."""
    return config_hash({"scenario": dataclasses.asdict(base), "data": dataclasses.asdict(spec),
                        "schema_version": SCHEMA_VERSION})


def plan_dataset(base: Scenario, spec: DatasetSpec, out_dir: str | Path, name: str = "dataset",
                 chunk: int | None = None, jobs: int = 2, store_signals: bool = False,
                 progress: bool = True, out_key: str = "out_dir") -> DatasetJob:
    """Check a dataset build before any work: the name, the chunk, the jobs, every unit's
    scenario against the model's scope and the output folder (named ``out_key`` in a
    refusal: the setting that gave it); finished chunks (same hash) are left out."""
    if not isinstance(name, str) or not NAME.match(name):
        raise ValueError(f"name = {name!r} must be a plain file name (letters, digits, '_', "
                         "'-', '.'; no folders): the dataset is written to <out_dir>/<name>"
                         ".parquet; choose the folder with out_dir")
    for key, v, lo in (("jobs", jobs, 1), ("chunk", chunk, 0)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, numbers.Integral)
                              or v < lo):
            raise ValueError(f"{key} = {v!r} must be a whole number >= {lo}")
    chunks = range(spec.chunks) if chunk is None else [int(chunk)]
    if chunk is not None:
        spec.chunk_units(int(chunk))  # raises for a chunk outside the spec
    for c in chunks:
        for case, rep in spec.chunk_units(c):
            check_scenario(check_record(unit_scenario(base, spec, case, rep)))
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out_key} = {str(out_dir)!r} is a file; give a folder")
    check_writable(out, out_key)
    digest = dataset_digest(base, spec)
    folder = chunk_folder(out, name)
    manifest = read_manifest(folder) if folder.is_dir() else {}
    todo = tuple(c for c in chunks
                 if chunk_state(folder, c, digest, bool(store_signals), manifest) != "done")
    return DatasetJob(base, spec, out, name, todo, chunk is None, int(jobs),
                      bool(store_signals), bool(progress),
                      None if chunk is None else int(chunk))


def lock_path(job: DatasetJob) -> Path:
    """The lock file of a build (:func:`physics.dataset.chunks.lock_file`)."""
    return lock_file(job.out, job.name, job.chunk)


def check_not_users(job: DatasetJob, out_key: str = "out_dir") -> None:
    """Refuse, before work, a build that would replace a dataset file it did not make: a
    ``<name>.parquet``, ``<name>_signals.npy`` or ``<name>.json`` in the output folder is the
    user's own unless the ``<name>.json`` beside it is the record every build writes (a JSON
    object with this app's ``hash`` and ``schema_version``)."""
    record = job.out / f"{job.name}.json"
    files = (job.out / f"{job.name}.parquet", job.out / f"{job.name}_signals.npy", record)
    found = [f for f in files if f.exists()]
    if not job.merge or not found or _built_here(record):
        return
    why = (f"no build of this app made it ({record.name} is not its record)" if record.exists()
           else f"no build of this app made it (no {record.name} beside it)")
    raise ValueError(f"{out_key} = {str(job.out)!r} already holds {found[0].name}, which "
                     f"this build would replace: {why}; choose another folder or name, or move "
                     "it")


def _built_here(record: Path) -> bool:
    """Whether ``record`` is the ``<name>.json`` a build of this app wrote."""
    try:
        data = json.loads(record.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and {"hash", "schema_version"} <= data.keys()


def acquire_output(job: DatasetJob) -> Path:
    """Make this process the one writer of the dataset ``job`` builds, before any work
    (:func:`physics.dataset.chunks.take_dataset_lock`); raises ValueError naming the other
    run's pid and its lock file."""
    return take_dataset_lock(job.out, job.name, job.chunk, job.digest)


def build_dataset(job: DatasetJob) -> Path | None:
    """Compute the chunks of ``job`` (in ``job.jobs`` processes) and merge them into the
    dataset when all were asked for; returns the dataset's path (None for a single chunk).

    The build holds the dataset's lock (:func:`acquire_output`; taken here unless the app took
    it already) and releases it at the end, also when it fails. Damaged chunks are set aside
    and computed again, before the work and again before the merge."""
    own = lock_path(job)
    held = (read_lock(own) or {}).get("pid") == os.getpid()
    if not held:
        acquire_output(job)
    try:
        remove_temporaries(job)  # of an earlier run of it that was killed outright
        return _build(job)
    except BaseException:
        # Ctrl-C, SIGTERM or a failure: a worker that was ended mid-write leaves its
        # temporary file, which this build removes while it still holds the lock (whole,
        # also when Ctrl-C comes again)
        with shielded():
            remove_temporaries(job)
        raise
    finally:
        release_lock(own)


def remove_temporaries(job: DatasetJob) -> None:
    """Remove the temporary files (:func:`physics.files.atomic_write`) of the outputs ``job``
    writes: of its chunks, and for a whole build of the manifest and the merged files too.
    Only the build holding the lock calls this, so no other writer's file is touched."""
    chunks = range(job.spec.chunks) if job.merge else [job.chunk]
    patterns = [f".chunk_{c:03d}.*.tmp" for c in chunks if c is not None]
    if job.merge:
        patterns.append(".*.tmp")
        for stem in (job.name, f"{job.name}_signals"):
            for path in job.out.glob(f".{stem}.*.tmp"):
                path.unlink(missing_ok=True)
    for pattern in patterns:
        for path in job.folder.glob(pattern):
            path.unlink(missing_ok=True)


def _compute(job: DatasetJob, todo: tuple[int, ...]) -> None:
    set_aside_damaged(job.folder, todo, job.digest, job.store_signals)
    if todo:
        MeshStiffness(job.base.gear, job.base.material)  # states the gear-body warning once
    jobs = max(1, min(job.jobs, len(todo)))
    args = (job.base, job.spec)
    with tqdm(total=len(todo), desc="chunks", unit="chunk", disable=not job.progress) as bar:
        if jobs == 1:
            for c in todo:
                run_chunk(*args, c, job.folder, job.digest, job.store_signals)
                bar.update(1)
        else:  # loky processes: they also start inside a joblib-launched multirun job
            tasks = (delayed(run_chunk)(*args, c, job.folder, job.digest, job.store_signals)
                     for c in todo)
            with worker_results(tasks, jobs) as runs:
                for _ in runs:
                    bar.update(1)


def _build(job: DatasetJob) -> Path | None:
    _compute(job, job.todo)
    if not job.merge:
        return None
    # the chunks this run did not compute are checked again before they are merged
    again = tuple(c for c in range(job.spec.chunks)
                  if chunk_state(job.folder, c, job.digest, job.store_signals) != "done")
    if again:
        _compute(job, again)
    sidecar = {"config": {"scenario": dataclasses.asdict(job.base),
                          "data": dataclasses.asdict(job.spec)},
               "seed": job.spec.seed, "package_version": version("gearwear"),
               "description": "one row per (case, replicate, cycles); features of the DTE and "
                              "the housing acceleration after noise"}
    return merge(job.spec, job.out, job.name, job.digest, sidecar, job.store_signals)


def chunks_kept(job: DatasetJob) -> str:
    """What an interrupted build kept, and how to go on."""
    done = [c for c in range(job.spec.chunks)
            if chunk_is_done(job.folder, c, job.digest, job.store_signals)]
    if not done:
        return (f"no chunk of the {job.spec.chunks} was finished, nothing is kept; run the "
                "same command again")
    runs = [[done[0], done[0]]]  # the kept chunks' numbers as ranges: 0-15, 18
    for c in done[1:]:
        if c == runs[-1][1] + 1:
            runs[-1][1] = c
        else:
            runs.append([c, c])
    numbers = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs)
    return (f"{len(done)} of {job.spec.chunks} chunks are kept in {job.folder} (chunk "
            f"{numbers}); the same command resumes from them")


def base_scenario(cfg: dict[str, Any]) -> Scenario:
    return scenario_from_config({k: v for k, v in cfg.items() if k != "case"})
