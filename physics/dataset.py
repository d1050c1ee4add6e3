"""Wear and vibration datasets across the operating cases of thesis Table 11 (thesis 4.1-4.3).

One *unit* of work is one replicate of one case: its operating point is jittered (seeded), the
dynamically coupled wear evolution is run over the cycle grid, every wear state's DTE is
simulated (one batch), the declared measurement chain of :mod:`physics.measurement` gives the
DTE and the housing acceleration, noise is added at the configured SNR (seeded), and the
features of :mod:`physics.features` are taken of both (columns ``dte_*`` and ``acc_*``).
A unit gives one row per cycle count.

Units are grouped in *chunks*, the independent jobs of a Hydra multirun; each chunk is written
atomically to ``<name>_chunks/chunk_<i>.parquet`` under the output folder, with the hash of
everything that determines it in its file metadata, and a finished chunk with the same hash is
not computed again (a killed run resumes). :func:`merge` joins the chunks into
``<name>.parquet`` and a JSON sidecar. Everything is seeded, so the same config gives
byte-identical files.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from physics.dynamics import build_model, simulate
from physics.evolution import simulate_dynamic_wear
from physics.features import FEATURES, feature_units, features
from physics.files import atomic_write
from physics.measurement import add_noise, housing_acceleration
from physics.params import Scenario, case_values, operating_cases, scenario_from_config
from physics.stiffness import MeshStiffness, SainsotRangeWarning

SCHEMA_VERSION = 1
#: columns besides the features, with their units
BASE_COLUMNS = {
    "case": "1", "replicate": "1", "cycles": "1", "n1_rpm": "r/min", "torque_Nm": "N m",
    "eta0_Pa_s": "Pa s", "sigma_um": "um", "root_wear_mm": "mm", "max_wear_mm": "mm",
    "mean_wear_mm": "mm",
}


@dataclass(frozen=True)
class DatasetSpec:
    """What a dataset holds; validated on construction."""

    cases: tuple[int, ...] = (1, 2, 3, 4, 5)
    cycles_max: float = 1.5e7
    wear_states: int = 32
    replicates: int = 8
    speed_jitter_pct: float = 1.0
    torque_jitter_pct: float = 2.0
    snr_db: float = 30.0
    seed: int = 0
    chunks: int = 5

    def __post_init__(self) -> None:
        valid = sorted(operating_cases())
        for c in self.cases:
            case_values(c)  # raises, listing the valid cases
        if len(set(self.cases)) != len(self.cases) or not self.cases:
            raise ValueError(f"cases = {list(self.cases)} must be distinct, from {valid}")
        checks = [
            ("cycles_max", self.cycles_max > 0, "> 0"),
            ("wear_states", isinstance(self.wear_states, int) and self.wear_states >= 2, ">= 2"),
            ("replicates", isinstance(self.replicates, int) and self.replicates >= 1, ">= 1"),
            ("speed_jitter_pct", 0 <= self.speed_jitter_pct < 50, "in [0, 50)"),
            ("torque_jitter_pct", 0 <= self.torque_jitter_pct < 50, "in [0, 50)"),
            ("snr_db", self.snr_db > -20, "> -20 dB (inf: no noise)"),
            ("chunks", isinstance(self.chunks, int) and 1 <= self.chunks <= self.units, f"in "
             f"[1, {self.units}] (one unit is a case-replicate pair)"),
        ]
        for name, ok, rule in checks:
            if not ok:
                raise ValueError(f"data.{name} = {getattr(self, name)!r} must be {rule}")

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


def unit_scenario(base: Scenario, spec: DatasetSpec, case: int, replicate: int) -> Scenario:
    """The case's operating point (Table 11) with this replicate's seeded jitter."""
    values = case_values(case)
    rng = np.random.default_rng([spec.seed, case, replicate, 0])
    speed, torque = rng.uniform(-1, 1, size=2)
    op = dataclasses.replace(
        base.operating,
        n1_rpm=values["n1_rpm"] * (1 + speed * spec.speed_jitter_pct / 100),
        torque_Nm=values["torque_Nm"] * (1 + torque * spec.torque_jitter_pct / 100))
    lub = dataclasses.replace(base.lubricant, eta0_Pa_s=values["eta0_Pa_s"],
                              alpha_m2_per_N=values["alpha_m2_per_N"],
                              limiting_shear_coeff=values["limiting_shear_coeff"])
    return dataclasses.replace(base, operating=op, lubricant=lub)


def run_unit(base: Scenario, spec: DatasetSpec, case: int, replicate: int,
             keep_signals: bool = False) -> tuple[pd.DataFrame, np.ndarray | None]:
    """Rows (one per cycle count) of one case-replicate pair, and optionally its records.

    The records are ``(row, 2, sample)``: the noisy DTE [m] and housing acceleration [m/s^2].
    """
    scn = unit_scenario(base, spec, case, replicate)
    cycles = spec.cycles()
    ms = MeshStiffness(scn.gear, scn.material)
    res = simulate_dynamic_wear(scn, float(cycles[-1]), snapshots=list(cycles))
    models, wear = [], []
    for n in cycles:
        w1, w2 = res.snapshots[float(n)]
        models.append(build_model(scn, ms, res.s, w1, w2) if np.any(w1 + w2 > 0)
                      else build_model(scn, ms))
        wear.append((w1[0], w1.max(), float(np.trapezoid(w1, res.s) / np.ptp(res.s))))
    response = simulate(models, scn.dynamics)
    rng = np.random.default_rng([spec.seed, case, replicate, 1])
    dte = add_noise(response.dte, spec.snr_db, rng)
    acc = add_noise(housing_acceleration(response.force, scn.dynamics.housing_mass_kg),
                    spec.snr_db, rng)
    dte_f, acc_f = features(dte), features(acc)
    wear = np.array(wear) * 1e3
    rows = pd.DataFrame({
        "case": case, "replicate": replicate, "cycles": cycles,
        "n1_rpm": scn.operating.n1_rpm, "torque_Nm": scn.operating.torque_Nm,
        "eta0_Pa_s": scn.lubricant.eta0_Pa_s, "sigma_um": scn.tribology.sigma_um,
        "root_wear_mm": wear[:, 0], "max_wear_mm": wear[:, 1], "mean_wear_mm": wear[:, 2],
        **{f"dte_{k}": dte_f[k] for k in FEATURES},
        **{f"acc_{k}": acc_f[k] for k in FEATURES},
    })
    signals = np.stack([dte, acc], axis=1).astype(np.float32) if keep_signals else None
    return rows, signals


def units() -> dict[str, str]:
    """Unit of every column of the dataset."""
    out = dict(BASE_COLUMNS)
    out.update({f"dte_{k}": u for k, u in feature_units("m").items()})
    out.update({f"acc_{k}": u for k, u in feature_units("m/s^2").items()})
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


def chunk_folder(out: Path, name: str) -> Path:
    """Where the chunks of dataset ``name`` live (one folder per dataset name)."""
    return out / f"{name}_chunks"


def chunk_path(folder: Path, chunk: int) -> Path:
    return folder / f"chunk_{chunk:03d}.parquet"


def chunk_is_done(path: Path, digest: str) -> bool:
    if not path.is_file():
        return False
    try:
        meta = pq.read_schema(path).metadata or {}
    except (OSError, pa.ArrowInvalid):
        return False  # unreadable: compute it again
    return meta.get(b"gearwear_hash", b"").decode() == digest


def run_chunk(base: Scenario, spec: DatasetSpec, chunk: int, folder: Path, digest: str,
              keep_signals: bool = False) -> bool:
    """Compute and write one chunk into ``folder`` unless it is there; True if computed."""
    path = chunk_path(folder, chunk)
    if chunk_is_done(path, digest):
        return False
    frames, signals = [], []
    with warnings.catch_warnings():
        # the gear's range warning is issued once by the caller (generate), not once per unit
        warnings.simplefilter("ignore", SainsotRangeWarning)
        for case, rep in spec.chunk_units(chunk):
            rows, sig = run_unit(base, spec, case, rep, keep_signals)
            frames.append(rows)
            if sig is not None:
                signals.append(sig)
    if keep_signals:
        stack = np.concatenate(signals)
        atomic_write(path.with_suffix(".npy"), lambda p: np.save(p.open("wb"), stack))
    _write_parquet(pd.concat(frames, ignore_index=True), path, {"gearwear_hash": digest})
    return True


def merge(spec: DatasetSpec, out: Path, name: str, digest: str, sidecar: dict[str, Any],
          keep_signals: bool = False) -> Path:
    """Join the finished chunks into ``<name>.parquet`` (+ ``.json``, and ``_signals.npy``)."""
    folder = chunk_folder(out, name)
    missing = [c for c in range(spec.chunks) if not chunk_is_done(chunk_path(folder, c), digest)]
    if missing:
        raise ValueError(f"chunks {missing} of this config are not finished in {out}; run them "
                         f"first (chunk=<i>) or run without chunk= to do all")
    frames = [pq.read_table(chunk_path(folder, c)).to_pandas() for c in range(spec.chunks)]
    df = pd.concat(frames, ignore_index=True)
    order = np.lexsort((df.cycles.to_numpy(), df.replicate.to_numpy(), df.case.to_numpy()))
    df = df.iloc[order].reset_index(drop=True)
    target = out / f"{name}.parquet"
    _write_parquet(df, target, {"gearwear_hash": digest})
    if keep_signals:
        sig = np.concatenate([np.load(chunk_path(folder, c).with_suffix(".npy"))
                              for c in range(spec.chunks)])[order]
        atomic_write(out / f"{name}_signals.npy", lambda p: np.save(p.open("wb"), sig))
    text = json.dumps({**sidecar, "schema_version": SCHEMA_VERSION, "hash": digest,
                       "rows": len(df), "units": units()}, indent=2, sort_keys=True,
                      default=str)
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


def base_scenario(cfg: dict[str, Any]) -> Scenario:
    return scenario_from_config({k: v for k, v in cfg.items() if k != "case"})
