"""The bundle's records as model inputs (:func:`prepare`): each record a scenario with its worn
teeth (:mod:`physics.loop.measured.worn_states`), its measured signature and noise level, and its
group.

Records of one (speed, torque, quantity, sampling rate) form a **group** (:class:`Group`) with
its own signature definition and entry scatter; a bundle may mix operating points, quantities,
sampling rates and record lengths. Records are split into train and test by record within each
group (the manifest's ``split`` column where given, else seeded), never by windows of one
record.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from physics.dynamics.model import PairModel
from physics.gear.stiffness import mesh_stiffness
from physics.loop.config import LoopSettings
from physics.loop.measured.bundle import Bundle, record_scenario
from physics.loop.measured.worn_states import (
    records_cycles,
    records_history,
    wear_grid_cycles,
    worn_models,
)
from physics.loop.threads import each
from physics.params import Scenario
from physics.signals.order_analysis import signature_names, signature_segments, white_noise_std


@dataclass(frozen=True)
class Group:
    """Records of one operating point, quantity and sampling rate: one signature definition.

    ``entry_sd`` is each entry's scatter between the measured segments (noise), ``discrepancy_sd``
    the model-form discrepancy of :func:`~physics.loop.model.discrepancy.discrepancy_sd` (zero until
    it is estimated); a residual is standardised by their quadrature sum, :attr:`sd`.
    """

    # n1_rpm, torque_Nm (None: unknown), quantity, fs_hz
    key: tuple[float, float | None, str, float]
    records: np.ndarray  # indices into the bundle
    names: list[str]  # the signature's entries
    entry_sd: np.ndarray  # [dB]
    discrepancy_sd: np.ndarray  # [dB]

    @property
    def sd(self) -> np.ndarray:
        return np.hypot(self.entry_sd, self.discrepancy_sd)

    @property
    def label(self) -> str:
        return group_label(self.key)


def group_label(key: tuple[float, float | None, str, float]) -> str:
    """A group's name: ``<n1>rpm_<torque>Nm_<quantity>_<fs>Hz`` (``unknownNm`` for records of
    unknown torque)."""
    n1, torque, quantity, fs = key
    return f"{n1:g}rpm_{'unknown' if torque is None else f'{torque:g}'}Nm_{quantity}_{fs:g}Hz"


@dataclass
class Records:
    """The bundle's records as model inputs, with their measured signatures."""

    bundle: Bundle
    scenarios: list[Scenario]
    models: list[PairModel]  # declared model with worn teeth, default nuisance
    measured: list[np.ndarray]  # segment-averaged signature of each record [dB]
    groups: list[Group]
    group_of: np.ndarray  # each record's index into ``groups``
    noise_std: np.ndarray
    train: np.ndarray  # indices
    test: np.ndarray
    settings: LoopSettings
    wear_states: list[list[tuple[float, PairModel]]] = field(default_factory=list)
    cache: dict = field(default_factory=dict)  # simulations by dynamic parameters
    # records whose manifest leaves the torque unknown: the configured torque times the
    # calibrated ``torque_factor`` (:data:`~physics.loop.model.declared.TORQUE`)
    torque_unknown: np.ndarray | None = None
    # the unit's calibration held at its own first records' (:func:`physics.loop.search.fit.held`):
    # ``m_h`` is not levelled again, by the declared model or any candidate
    held: bool = False

    def group(self, i: int) -> Group:
        """The group of record ``i``."""
        return self.groups[self.group_of[i]]


def split_records(man: pd.DataFrame, test_fraction: float, seed: int,
                  strata: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Train/test record indices: the manifest's split where given, else seeded by record,
    within each stratum (group of :func:`group_keys`) so that every group with two free
    records holds some out."""
    given = man.split.astype("string").fillna("").to_numpy(str)
    idx = np.arange(len(man))
    strata = np.zeros(len(man), int) if strata is None else np.asarray(strata)
    rng = np.random.default_rng(seed)
    test = [idx[given == "test"]]
    for s in dict.fromkeys(strata.tolist()):  # in order of first appearance
        free = idx[(given == "") & (strata == s)]
        n_test = max(1, round(test_fraction * len(free))) if len(free) > 1 else 0
        if n_test:
            test.append(rng.choice(free, n_test, replace=False))
    test = np.sort(np.concatenate(test).astype(int))
    train = np.setdiff1d(idx, test)
    if len(train) == 0 or len(test) == 0:
        raise ValueError(f"the bundle needs at least one train and one test record (it has "
                         f"{len(man)} records); add records or set the split column")
    return train, test


def group_keys(man: pd.DataFrame) -> tuple[list[tuple], np.ndarray]:
    """The distinct (n1_rpm, torque_Nm, quantity, fs_hz) of a manifest, in order of first
    appearance, and each record's index into them; an unknown torque is None (the records of
    unknown torque at one speed, quantity and rate form one group)."""
    torque = [float(t) if np.isfinite(t) else None for t in man.torque_Nm.astype(float)]
    keys = list(zip(man.n1_rpm.astype(float), torque, man.quantity,
                    man.fs_hz.astype(float), strict=True))
    distinct = list(dict.fromkeys(keys))
    return distinct, np.array([distinct.index(k) for k in keys], int)


def prepare(bundle: Bundle, base: Scenario, settings: LoopSettings) -> Records:
    """Scenarios, worn models, measured signatures, noise levels, groups and the split of a
    bundle. Records of one operating point, quantity and sampling rate form a group with its
    own signature definition and entry scatter; a bundle may hold any number of groups."""
    man = bundle.manifest
    scenarios = [record_scenario(base, row) for row in man.itertuples(index=False)]
    ms = mesh_stiffness(base.gear, base.material)
    keys, group_of = group_keys(man)
    train, test = split_records(man, settings.test_fraction, settings.seed, group_of)
    keyed: dict[tuple, list[int]] = {}
    for i, scn in enumerate(scenarios):  # an unknown torque: the configured one's worn states
        keyed.setdefault((scn.operating.n1_rpm, scn.operating.torque_Nm), []).append(i)
    models: list[PairModel | None] = [None] * len(man)
    wear_states: list[list[tuple[float, PairModel]]] = [[] for _ in range(len(man))]

    def worn(idx: list[int]) -> tuple:  # one operating point's wear run and worn models
        scn, rows = scenarios[idx[0]], man.iloc[idx]
        history = records_history(scn, rows)
        cycles = dict(zip(idx, records_cycles(history, rows), strict=True))
        grid = wear_grid_cycles(history, max(cycles.values()), settings.wear_grid)
        return (cycles, grid, *worn_models(scn, ms, [*cycles.values(), *grid], history))

    points = list(keyed.values())
    for idx, (cycles, grid, by_cycles, root) in zip(points, each(worn, points, "wear runs"),
                                                     strict=True):
        for i in idx:
            models[i] = by_cycles[cycles[i]]
            wear_states[i] = [(root[float(g)], by_cycles[float(g)]) for g in grid]
    fs = man.fs_hz.to_numpy(float)
    dte = (man.quantity == "dte_m").to_numpy()
    segments = [signature_segments(bundle.signals[r], fs[i], *shaft_rates(scenarios[i]),
                                   scenarios[i].gear.z1, dte[i], settings.segment_s)
                for i, r in enumerate(man.record)]
    if min(s.shape[0] for s in segments) < 2:
        raise ValueError(f"every record needs at least two analysis segments of "
                         f"{settings.segment_s:g} s (their scatter is the noise of the "
                         "comparison); lengthen the records or shorten segment_s")
    groups = []
    for g, key in enumerate(keys):
        members = np.flatnonzero(group_of == g)
        scn = scenarios[members[0]]
        names = signature_names(*shaft_rates(scn), scn.gear.z1, key[3], key[2] == "dte_m")
        sd = entry_scatter([segments[i] for i in np.intersect1d(members, train)]
                           or [segments[i] for i in members], settings.floor_db)
        groups.append(Group(key, members, names, sd, np.zeros_like(sd)))
    noise = np.array([white_noise_std(bundle.signals[r], fs[i],
                                      0.5 * shaft_rates(scenarios[i])[0] * scenarios[i].gear.z1)
                      for i, r in enumerate(man.record)])
    return Records(bundle, scenarios, models, [s.mean(axis=0) for s in segments], groups,
                   group_of, noise, train, test, settings, wear_states,
                   torque_unknown=~np.isfinite(man.torque_Nm.to_numpy(float)))


def entry_scatter(segments: list[np.ndarray], floor_db: float) -> np.ndarray:
    """Scatter [dB] of each signature entry of a one-segment model against an n-segment mean:
    var = sd^2 (1 + 1/n), the median over the records given (a group's train records; its
    test records only where it has no train record: their segments are noise, not a fit),
    plus the model error floor ``floor_db`` in quadrature."""
    var = np.median([s.var(axis=0, ddof=1) * (1 + 1 / s.shape[0]) for s in segments], axis=0)
    return np.sqrt(var + floor_db**2)


def shaft_rates(scn: Scenario) -> tuple[float, float]:
    f1 = scn.operating.n1_rpm / 60
    return f1, f1 * scn.gear.z1 / scn.gear.z2


def by_group(rec: Records, idx: np.ndarray) -> dict[int, list[int]]:
    """Positions in ``idx`` of each group's records, by group index in order (groups without a
    record in ``idx`` left out)."""
    out: dict[int, list[int]] = {}
    for j, i in enumerate(idx):
        out.setdefault(int(rec.group_of[i]), []).append(j)
    return dict(sorted(out.items()))
