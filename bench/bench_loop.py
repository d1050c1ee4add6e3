"""Confusion matrix and timing of the measured-data loop on bundles with an undeclared effect.

    python bench/bench_loop.py [--generator own|independent] [--seeds 3] [--null-seeds 6]
                               [--records 12] [--jobs 2] [--model-form] [--starts 1] [--both]
                               [--reference] [--own-history N] [--out DIR] [--timing-only]

For every effect of the library (acceleration bundles; ``sensor``, which only DTE records show,
on DTE bundles) and for bundles without any effect (of both quantities: what a clean bundle of
one sensor passes says nothing about the other's), a generator writes a bundle and
:func:`physics.loop.run_loop` analyses it. ``own`` (default): this project's model,
:func:`physics.testbeds.synthetic.make_bundle` (case 3, nuisance parameters off their defaults, the
effect at a seeded realistic size, 30 dB noise, ``--records`` records of 1 s). ``independent``:
the independent spur-pair simulator of another model form,
:func:`physics.testbeds.independent_simulator.make_independent_bundle` (2000 r/min / 300 N m and
1800 r/min / 290 N m, six wear states each: 12 records of 0.5 s, the effect at its typical
size, 30 dB noise, the gear set's error phases drawn from the seed; the loop is told the
gearbox's bearing-support mode as estimated from its drawings); its true model is not ours,
so the floor column is empty there. Prints and writes ``loop_runs.csv`` (one row per
bundle: truth, choice and verdict, held-out error before/after and that of the data-generating
model itself, wear-estimate error and skill and the model that reads it, seconds, the first
round's best candidate with the null test's figures on it, and the clean floor with whether
halving is attainable at all, :func:`physics.testbeds.loop_bench.attainable`),
``loop_confusion.csv`` (truth x choice counts) and ``loop_timing.json`` (the solo timing),
each bundle's ``report.json`` and ``report.md`` under
``reports/<generator>_<effect>_<seed>_<quantity>/`` (every candidate's figures), the rates
the loop is judged by: right effect named (or an unexplained residual reported), held-out
error at least halved, nothing added on clean bundles, and ``loop_visibility.csv``: for each
bundle the entry family or mesh harmonic whose residual most exceeds that of the other clean
bundles of its quantity (:func:`physics.testbeds.loop_bench.visibility`).
``--both`` (independent generator): every bundle holds the DTE and the housing acceleration of
each operating point and wear state, as a rig with shaft encoders and an accelerometer records
them; what one sensor's records cannot tell apart (a DTE gain from the stiffness level, a
transfer-path mode from the mesh) the other's may.
``--reference``: every bundle is read against a sister gearbox's clean records
(:mod:`physics.loop.search.form_error`): the same generator, another unit of the series
(:data:`physics.testbeds.SISTER_UNIT`: other errors within their tolerance, another damping and
mounting), at the bundle's operating points and quantities; its calibration is made once and
timed apart.
``--own-history N``: every effect appears during the bundle's life (in the records from
:data:`ONSET` of the cycles on, with the independent generator of its largest wear, its records
dated in order of wear; the earlier ones are clean) and every bundle is read against its own
first ``N`` records of each group (``reference=first:N``,
:func:`physics.loop.search.own_history.own_reference`), the reference a user with records from
commissioning has.
Also times one bundle alone (:func:`solo_timing`; ``--timing-only``: that alone), printed
beside the serial design's time (:data:`REFERENCE_S`); the per-bundle seconds of
the table are those of ``--jobs`` bundles sharing the machine, each on its share of numba's
threads.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numba
import numpy as np
import pandas as pd

from physics.loop import EFFECTS, LoopSettings, read_bundle, run_loop, write_report
from physics.loop.model.comparison import residuals, rms
from physics.loop.model.simulation import model_signals
from physics.loop.search.form_error import FormReference
from physics.loop.search.own_history import own_reference
from physics.testbeds import (
    BOTH,
    EFFECT_NAMES,
    attainable,
    base_scenario,
    best_candidate,
    make_bundle,
    make_independent_bundle,
    report_label,
    sister_reference,
    visibility,
)

#: ``--own-history``: the share of the life after which the effect is in the records
ONSET = 0.3
#: effect-to-noise power [dB] below which an effect has not changed the records (round-off)
ABSENT_DB = -100.0
#: the loop's serial design's time for one bundle alone on 2 cores, by (generator, --both,
#: --reference) [s]: what the 30 s target quarters (one BLAS thread, records integrated from a
#: few decay times before their start, the chain batched, candidates and records one by one)
REFERENCE_S = {("independent", False, False): 102.7, ("independent", False, True): 108.6,
               ("own", False, False): 242.5}


def references(generator: str, both: bool, records: int, tmp: Path
               ) -> dict[str, FormReference]:
    """``--reference``: the sister unit's form reference for each bundle quantity, timed."""
    t = time.perf_counter()
    if generator == "independent":  # one sister bundle with both sensors serves every bundle
        ref = sister_reference(generator, BOTH, records, tmp)
        out = {"dte_m": ref, "accel_m_s2": ref, "both": ref}
    else:
        out = {q: sister_reference(generator, (q,), records, tmp) for q in BOTH}
    print(f"sister unit's form reference calibrated in {time.perf_counter() - t:.1f} s")
    return out


def one(job: tuple[str, str | None, int, int, dict, str, tuple[str, ...], str,
                   FormReference | None, int]) -> dict:
    generator, name, seed, records, loop, tmp, quantities, out, reference, history = job
    base = base_scenario(generator)
    quantity = "both" if quantities == BOTH else quantities[0]
    label = report_label(generator, name, seed, quantity)
    folder = Path(tmp) / label
    if generator == "independent":
        path, truth = make_independent_bundle(
            folder, name, quantities=quantities, seed=seed, onset=ONSET if history else None,
            dated=bool(history))
    else:
        path, truth = make_bundle(folder, base, name, seed, quantity=quantity, records=records,
                                  onset=ONSET if history else None)
    settings = LoopSettings(seed=seed, **loop)
    bundle = read_bundle(path)
    t = time.perf_counter()
    if history:  # the unit's own first records: the reference, left out of the analysis
        reference, bundle = own_reference(bundle, f"first:{history}", base, settings)
    r = run_loop(bundle, base, settings, reference=reference)
    seconds = time.perf_counter() - t
    write_report(r, Path(out) / "reports" / label, with_figures=False)
    rec = r.signals["rec"]
    floor = float("nan")
    if generator == "own":  # the data-generating model's own held-out error (noise, scatter)
        floor = rms(residuals(rec, rec.test, model_signals(
            rec, rec.test, truth["nuisance"], EFFECTS.get(name), truth["values"])))
    return {"generator": generator, "truth": name or "none", "quantity": quantity, "seed": seed,
            "chosen": r["chosen_effect"] or "none", "verdict": r["verdict"],
            "effect_to_noise_db": truth["effect_to_noise_db"],
            "error_before": r["error_before"], "error_after": r["error_after"],
            "error_true_model": floor,
            "wear_error_before_pct": r["wear_error_before_pct"],
            "wear_error_after_pct": r["wear_error_after_pct"],
            "wear_skill_before": r["wear_skill_before"], "wear_skill_after": r["wear_skill_after"],
            "wear_read_by": r["wear_read_by"],
            "seconds": seconds, **best_candidate(r)}


def solo_timing(generator: str, loop: dict, tmp: Path, both: bool = False,
                reference: FormReference | None = None) -> dict:
    """Time one bundle alone on the machine (the pool's bundles share its cores): the own
    generator's of 20 records of 1 s, the independent one's of 12 records of 0.5 s (the
    target's size; 24 with ``both``), all with a tip relief, the loop only (a reference
    calibrated before). Returns the figures printed (``loop_timing.json``)."""
    base = base_scenario(generator)
    if generator == "own":
        path, _ = make_bundle(tmp / "timing", base, "tip_relief", 99, records=20)
    else:
        path, _ = make_independent_bundle(tmp / "timing", "tip_relief",
                                          quantities=BOTH if both else ("accel_m_s2",), seed=99)
    bundle = read_bundle(path)
    t, cpu = time.perf_counter(), time.process_time()
    run_loop(bundle, base, LoopSettings(**loop), reference=reference)
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    ref = REFERENCE_S.get((generator, both, reference is not None))
    print(f"one bundle of {len(bundle.records)} records alone: {wall:.1f} s ({cpu:.1f} s of "
          f"CPU; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
          + (f"; the serial design: {ref:.1f} s alone on 2 cores, {ref / wall:.1f} "
             "times this" if ref else "")
          + ("; target: 12 records of 0.5 s in <= 30 s" if generator == "independent" else ""))
    return {"generator": generator, "both": both, "reference": reference is not None,
            "records": len(bundle.records), "wall_s": wall, "cpu_s": cpu,
            "load_average": os.getloadavg()[0], "cores": os.cpu_count()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--generator", choices=("own", "independent"), default="own",
                    help="who makes the bundles: this project's model or the independent one")
    ap.add_argument("--seeds", type=int, default=3, help="bundles per effect")
    ap.add_argument("--null-seeds", type=int, default=6,
                    help="bundles without an effect, of each quantity")
    ap.add_argument("--records", type=int, default=12,
                    help="records (1 s each) per bundle of the own generator")
    ap.add_argument("--jobs", type=int, default=2, help="bundles analysed in parallel")
    ap.add_argument("--model-form", action="store_true",
                    help="calibrate the declared model's form uncertainty (loop.model_form=true)")
    ap.add_argument("--starts", type=int, default=LoopSettings.starts, metavar="N",
                    help="best explored points each candidate's fit starts from (loop.starts)")
    ap.add_argument("--both", action="store_true",
                    help="independent generator: DTE and acceleration records in every bundle")
    ap.add_argument("--reference", action="store_true",
                    help="read every bundle against a sister unit's clean records "
                         "(physics.loop.search.form_error)")
    ap.add_argument("--own-history", type=int, default=0, metavar="N",
                    help="effects appear during the life; each bundle read against its own "
                         "first N records of each group")
    ap.add_argument("--out", default="bench_loop_out",
                    help="folder for the CSV files and the reports")
    ap.add_argument("--timing-only", action="store_true",
                    help="time one bundle alone (solo timing) and stop")
    args = ap.parse_args()
    if args.own_history and args.reference:
        ap.error("--own-history takes no --reference (the bundle's own first records are its "
                 "reference)")
    if args.both and args.generator != "independent":
        ap.error("--both needs --generator independent (the own generator writes one quantity "
                 "per bundle)")
    loop = {"model_form": args.model_form, "starts": args.starts}  # LoopSettings of every run
    try:
        LoopSettings(**loop)
    except ValueError as err:
        ap.error(f"--starts {args.starts}: {err}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        refs = (references(args.generator, args.both, args.records, Path(tmp))
                if args.reference else {})
        if not args.own_history:
            timing = solo_timing(args.generator, loop, Path(tmp), args.both,
                                 refs.get("both" if args.both else "accel_m_s2"))
            (out / "loop_timing.json").write_text(json.dumps(timing, indent=1) + "\n")
        if args.timing_only:
            return
        names = EFFECTS if args.generator == "own" else EFFECT_NAMES
        def sensors(name: str | None) -> list[tuple[str, ...]]:
            if args.both:
                return [BOTH]
            if name is None:  # clean bundles of each quantity
                return [("accel_m_s2",), ("dte_m",)]
            return [("dte_m",) if name == "sensor" else ("accel_m_s2",)]

        def ref(q: tuple[str, ...]) -> FormReference | None:
            return refs.get("both" if q == BOTH else q[0])

        jobs = [(args.generator, n, s, args.records, loop, tmp, q, str(out), ref(q),
                 args.own_history) for n in names for s in range(args.seeds) for q in sensors(n)]
        jobs += [(args.generator, None, 100 + s, args.records, loop, tmp, q, str(out),
                  ref(q), args.own_history)
                 for s in range(args.null_seeds) for q in sensors(None)]
        spawn = multiprocessing.get_context("spawn")  # numba's OpenMP threads do not survive fork
        # the bundles share the cores: each process's loop on its share of numba's threads
        share = max(1, (os.cpu_count() or 1) // args.jobs)
        with ProcessPoolExecutor(args.jobs, mp_context=spawn, initializer=numba.set_num_threads,
                                 initargs=(share,)) as pool:
            rows = list(pool.map(one, jobs))
    runs = attainable(pd.DataFrame(rows))
    runs.to_csv(out / "loop_runs.csv", index=False)
    confusion = pd.crosstab(runs.truth, runs.chosen)
    confusion.to_csv(out / "loop_confusion.csv")
    # an effect that changes the records by no more than round-off is not in the data: such
    # bundles (backlash growth without contact loss) are clean bundles
    present = runs.effect_to_noise_db > ABSENT_DB
    eff = runs[present]
    right = eff.truth == eff.chosen
    halved = eff.error_after <= 0.5 * eff.error_before
    clean = runs[~present]
    print(runs.round(3).to_string(index=False))
    print("\nconfusion matrix (rows: effect in the data, columns: effect the loop chose)")
    print(confusion.to_string())
    print(f"\nright effect named: {right.mean():.0%} of {len(eff)} bundles whose effect changes "
          "the records (target >= 90 %)")
    among = [t == c or t in a.split(";")
             for t, c, a in zip(eff.truth, eff.chosen, eff.also_passing, strict=True)]
    print(f"right effect named, or passing the null test beside the named one: "
          f"{np.mean(among):.0%} of them")
    told = right | (eff.verdict == "unexplained_residual")
    print(f"right effect named, or an unexplained residual reported: {told.mean():.0%} of them "
          f"('none' on {int((eff.verdict == 'none').sum())})")
    unexplained = eff[eff.verdict == "unexplained_residual"]
    print(f"  an unexplained residual whose closest candidate is the right effect: "
          f"{int((unexplained.best == unexplained.truth).sum())} of {len(unexplained)}")
    beyond = eff[eff.beyond_chance]
    print(f"  'none' where the error before exceeds every clean bundle's of its quantity (the "
          f"clean floor's chance level): {int((beyond.verdict == 'none').sum())} of "
          f"{len(beyond)} such bundles (target 0)")
    print(f"held-out error at least halved: {halved.mean():.0%} of them (target >= 90 %)")
    print(f"  halving attainable (error before at least twice the smallest clean bundle's of "
          f"its quantity) on {int(eff.halving_attainable.sum())} of them; halved on "
          f"{int(halved[eff.halving_attainable].sum())} of those")
    at_floor = eff.error_after <= 1.1 * eff.error_true_model
    print(f"held-out error after within 10 % of the true model's: {at_floor.mean():.0%}")
    n_clean = int((runs.truth == "none").sum())
    print(f"nothing added on bundles without an effect in the records: "
          f"{(clean.chosen == 'none').mean():.0%} of {len(clean)} ({n_clean} clean, "
          f"{len(clean) - n_clean} with an effect below round-off; target >= 95 %)")
    for quantity, rows_q in clean.groupby("quantity"):
        print(f"  {quantity}: nothing added on {(rows_q.chosen == 'none').sum()} of {len(rows_q)}")
    print(f"median loop time: {runs.seconds.median():.1f} s per bundle")
    seen = visibility(runs, out)
    if not seen.empty:
        seen.to_csv(out / "loop_visibility.csv", index=False)
        print("\nwhere each bundle's residual most exceeds the other clean bundles' (family or "
              "mesh harmonic; the clean rows are the chance level)")
        print(seen.to_string(index=False))


if __name__ == "__main__":
    main()
