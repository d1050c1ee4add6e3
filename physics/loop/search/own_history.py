"""The unit's own history as its form reference: ``reference=first:N`` or ``reference=before:X``.

The commonest reference a user has is not a sister unit but the gearbox's own earliest records:
from commissioning, or from before a change (a repair, a new lubricant, a suspected onset).
Such records share everything with the later ones that a sister unit does not (its errors, its
mounting, its sensor's place), so the declared model's form error measured on them is the
same unit's, not the twin-unit floor (docs/loop.md). :func:`parse_history` reads the two
forms; :func:`split_history` cuts a bundle into the reference records and the records the loop
analyses (the reference records are left out of the analysis); the reference is then
calibrated as a sister unit's is (:func:`physics.loop.search.form_error.form_reference`), and that
calibration is held for the analysed records (:func:`physics.loop.search.fit.held`).

- ``first:N``: the first ``N`` records of each group (operating point, quantity, sampling
  rate), in the order of their load cycles, else of a ``time`` column (ISO 8601);
- ``before:X``: the records before ``X`` load cycles (a number) or before the date or time
  ``X`` (ISO 8601, ``YYYY-MM-DD`` or ``YYYY-MM-DDThh:mm``; by the ``time`` column).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from physics.loop.config import LoopSettings
from physics.loop.measured.bundle import Bundle
from physics.loop.measured.records import group_keys, group_label
from physics.loop.search.form_error import FormReference, form_reference
from physics.params import Scenario

#: the optional manifest column that dates each record (ISO 8601)
TIME_COLUMN = "time"
_FORM = re.compile(r"^\s*(first|before)\s*:\s*(.*?)\s*$")
#: records of a group the analysis needs beside the reference's (a train and a test record)
MIN_ANALYSED = 2


@dataclass(frozen=True)
class History:
    """A reference taken from the bundle's own earliest records (:func:`parse_history`)."""

    spec: str  # as given, e.g. "first:2"
    first: int | None = None  # first N records of each group ...
    cycles: float | None = None  # ... or those before this many load cycles ...
    time: pd.Timestamp | None = None  # ... or before this date


def parse_history(spec: object) -> History | None:
    """``reference=`` as the unit's own history, or None where it is not of that form (then
    it names a sister bundle's folder). A malformed value of the form is refused."""
    if not isinstance(spec, str):
        return None
    m = _FORM.match(spec)
    if m is None:
        return None
    kind, value = m.groups()
    if kind == "first":
        if not re.fullmatch(r"\d+", value) or int(value) < 1:
            raise ValueError(f"reference={spec}: first:N takes a whole number N >= 1 of "
                             "records per group, the earliest by cycles or time; e.g. "
                             "reference=first:2")
        return History(spec, first=int(value))
    try:
        cycles = float(value)
    except ValueError:
        cycles = None
    if cycles is not None:
        if not (np.isfinite(cycles) and cycles > 0):
            raise ValueError(f"reference={spec}: before:X takes a number of load cycles > 0 "
                             "or an ISO 8601 date; e.g. reference=before:2e6 or "
                             "reference=before:YYYY-MM-DD")
        return History(spec, cycles=cycles)
    try:
        when = pd.Timestamp(value)
    except (ValueError, TypeError):
        when = None
    if when is None or when is pd.NaT:
        raise ValueError(f"reference={spec}: {value!r} is neither a number of load cycles nor "
                         "an ISO 8601 date; e.g. reference=before:2e6 or "
                         "reference=before:YYYY-MM-DD")
    return History(spec, time=when)


def _times(bundle: Bundle, spec: str) -> np.ndarray:
    man = bundle.manifest
    if TIME_COLUMN not in man.columns:
        raise ValueError(f"reference={spec}: the manifest has no {TIME_COLUMN!r} column to "
                         "date the records by; add one (ISO 8601, YYYY-MM-DD or "
                         "YYYY-MM-DDThh:mm), or "
                         "give the cycles (reference=before:<cycles>) or a sister bundle")
    out = []
    for rec, text in zip(man.record, man[TIME_COLUMN], strict=True):
        try:
            t = pd.Timestamp(str(text).strip())
        except (ValueError, TypeError):
            t = pd.NaT
        if t is pd.NaT:
            raise ValueError(f"reference={spec}: record {rec!r}: {TIME_COLUMN} = {text!r} is "
                             "not an ISO 8601 date; write YYYY-MM-DD or YYYY-MM-DDThh:mm")
        out.append(t.tz_localize(None) if t.tzinfo is not None else t)
    return np.array([t.value for t in out], float)  # ns since the epoch


def life_order(bundle: Bundle, spec: str) -> np.ndarray:
    """Each record's place in the unit's life: its load cycles where every record states
    them, else its ``time`` (refused if the manifest has neither for every record)."""
    cycles = bundle.manifest.cycles.to_numpy(float)
    if np.isfinite(cycles).all():
        return cycles
    if TIME_COLUMN in bundle.manifest.columns:
        return _times(bundle, spec)
    rec = bundle.records[int(np.argmin(np.isfinite(cycles)))]
    raise ValueError(f"reference={spec}: record {rec!r} has no cycles and the manifest no "
                     f"{TIME_COLUMN!r} column, so the earliest records are not known; state "
                     "every record's cycles or add a time column (ISO 8601), or give a sister "
                     "bundle as reference=")


def subset(bundle: Bundle, keep: np.ndarray) -> Bundle:
    """The bundle with only the records ``keep`` (a mask over its manifest)."""
    man = bundle.manifest[keep].reset_index(drop=True)
    return dataclasses.replace(bundle, manifest=man,
                               signals={r: bundle.signals[r] for r in man.record})


def split_history(bundle: Bundle, history: History) -> tuple[Bundle, Bundle]:
    """(reference, analysed): the bundle's records of ``history`` and the others. Refused
    where the reference would lack a group the analysis has, or a group would keep fewer
    than two records for the analysis (a train and a test record)."""
    spec = history.spec
    man = bundle.manifest
    keys, group_of = group_keys(man)
    if history.time is not None:
        life = _times(bundle, spec)
        ref = life < history.time.tz_localize(None).value if history.time.tzinfo else \
            life < history.time.value
    elif history.cycles is not None:
        life = man.cycles.to_numpy(float)
        if not np.isfinite(life).all():
            rec = bundle.records[int(np.argmin(np.isfinite(life)))]
            raise ValueError(f"reference={spec}: record {rec!r} states no cycles; before:X in "
                             "cycles needs every record's cycles; state them, or date the "
                             "records (time column) and give before:<ISO date>")
        ref = life < history.cycles
    else:
        life = life_order(bundle, spec)
        ref = np.zeros(len(man), bool)
        for g in range(len(keys)):
            members = np.flatnonzero(group_of == g)
            ref[members[np.argsort(life[members], kind="stable")[:history.first]]] = True
    for g, key in enumerate(keys):
        members = group_of == g
        kept = int((members & ~ref).sum())
        if 0 < kept < MIN_ANALYSED or (kept == 0 and history.first is not None):
            raise ValueError(f"reference={spec} leaves {kept} record(s) of group "
                             f"{group_label(key)} for the analysis, which needs at least "
                             f"{MIN_ANALYSED} (a train and a test record); take fewer or "
                             "earlier records as the reference")
        if kept and not (members & ref).any():
            raise ValueError(f"reference={spec} takes no record of group {group_label(key)} "
                             "(each group is referred to its own reference records); take a "
                             "later limit, or give a sister bundle")
    if not (~ref).any():
        raise ValueError(f"reference={spec} takes every record of the bundle: none is left "
                         "for the analysis; take an earlier limit")
    reference = subset(bundle, ref)
    reference.manifest["split"] = ""  # drawn anew: the bundle's split was for the analysis
    return reference, subset(bundle, ~ref)


def own_reference(bundle: Bundle, spec: str | History, base: Scenario,
                  settings: LoopSettings) -> tuple[FormReference, Bundle]:
    """The form reference of ``bundle``'s own earliest records (``spec``: ``first:N`` or
    ``before:X``), calibrated as a sister unit's is (its calibration then held for the later
    records, :func:`physics.loop.search.fit.held`), and the bundle of the records left for the
    analysis."""
    history = spec if isinstance(spec, History) else parse_history(spec)
    if history is None:
        raise ValueError(f"reference={spec}: not of the form first:N or before:X (cycles or an "
                         "ISO 8601 date); e.g. reference=first:2")
    reference, analysed = split_history(bundle, history)
    return (form_reference(reference, base, settings, source=source(history.spec),
                           same_unit=True), analysed)


def source(spec: str) -> str:
    """How a report names a reference of the unit's own earliest records ``spec``."""
    return f"this unit's own earliest records ({spec})"
