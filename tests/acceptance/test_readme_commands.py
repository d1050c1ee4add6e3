"""Every command and snippet of README.md, run as a subprocess in a fresh folder, as typed.

Only size overrides are added (fewer replicates, wear states, epochs, records, trials); never a
switch that changes which code path runs (never a single-process job count, never a pre-built
dataset). Scripts of the checkout (``train.py``, ``bench/*.py``) run by their path in the checkout.
A command that needs the output of another (``surrogate.predict`` needs a trained model) runs that
one first in the same folder. Placeholders of the README (``<run>``, ``<time>``) are filled with
what those earlier commands wrote. ``test_every_readme_command_has_an_acceptance_test`` fails when
the README documents a command that this table does not cover, or when the table names one the
README no longer has.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path

import pandas as pd
import pytest
from readme import ROOT, commands, snippets

from physics.loop import LoopConfig
from physics.reproduce.thesis import ReproduceConfig

#: run by .ci/run itself, exactly as the README writes them
BY_CI = {
    'python3.11 -m venv .venv && . .venv/bin/activate && pip install -e ".[dev]"': "the install",
    "pytest": "the test run (this suite)",
}
#: a smaller dataset for train.py to build (the sizes of the dataset spec)
#: a dataset of 4 replicates per case in 2 chunks, one trajectory each to validate and test
SMALL_SPLIT = ["data.val_replicates=1", "data.test_replicates=1"]
TINY_DATA = ["+data.generate.replicates=4", "+data.generate.wear_states=4",
             "+data.generate.chunks=2", *SMALL_SPLIT]
FAST_TRAIN = ["trainer.max_epochs=3", "trainer.min_epochs=1", "model.members=2"]
FAST_REPRO = ["solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
              "stiffness.positions=40", "evolution.cases=[3]", "evolution.points=9",
              "evolution.table14_cycles=[0,1.5e7]"]
SMALL_DATASET = ["data.replicates=2", "data.wear_states=3"]
SMALL_BUNDLE = {"records=10, duration_s=1.0": "records=6, duration_s=0.5",
                "effect=\"friction\", seed=1)": "effect=\"friction\", seed=1, wear_mm=(0, 0.012))",
                "seed=2,\n": "seed=2, wear_mm=(0, 0.012),\n"}
TRAIN_CASE3 = "python train.py case=3"
TRAIN_BASELINE = "python train.py case=3 experiment=baseline"
DEMO = 'make_bundle("demo_bundle", Scenario(), "friction", seed=1,'
USER_TABLE = 'rows = pd.read_parquet("data/dataset_case3.parquet")'
TABLE_ARGS = "data.table=my_wear_table.csv data.group=rig +data.columns.p2p=dte_peak_to_peak"


def _files(*patterns: str) -> Callable[[Path], None]:
    def check(folder: Path) -> None:
        for pattern in patterns:
            assert list(folder.glob(pattern)), f"{pattern} missing in {folder}"
    return check


def _trained(folder: Path) -> None:
    _files("data/dataset_case3.parquet", "logs/train/runs/case3_*/wear_surrogate.pt",
           "logs/train/runs/case3_*/parity.png", "logs/train/runs/case3_*/checkpoints/*.ckpt")(
        folder)
    run = next(folder.glob("logs/train/runs/case3_*"))
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["train_rows"] > 0 and "test_mean_relative_error_pct" in metrics


def _mean_wear(folder: Path) -> None:
    run = next(folder.glob("logs/train/runs/case3_*"))
    predictions = pd.read_csv(run / "test_predictions.csv")
    assert {"mean_wear_mm", "mean_wear_mm_pred", "mean_wear_mm_upper"} <= set(predictions.columns)


def _baseline(folder: Path) -> None:
    """The baseline model's readings of every row, with the gearbox columns it was given."""
    wear = pd.read_csv(folder / "wear.csv")
    rows = pd.read_parquet(folder / "data" / "dataset_case3.parquet")
    assert {"case", "replicate", "cycles", "mean_wear_mm_pred"} <= set(wear.columns)
    assert len(wear) == len(rows) and wear.mean_wear_mm_pred.notna().all()
    assert (wear.replicate.to_numpy() == rows.replicate.to_numpy()).all()


def _summary(folder: Path) -> None:
    table = pd.read_csv(next(folder.glob("logs/train/multiruns/*/summary.csv")))
    assert len(table) == 5 and set(table.status) == {"ok"}


def _report(folder: Path) -> None:
    report = next(folder.glob("logs/loop/runs/*/report.json"))
    keys = set(json.loads(report.read_text()))
    assert {"chosen_effect", "error_before", "error_after"} <= keys


def _referenced(folder: Path) -> None:
    """The report says which reference records it was read against, per group."""
    _report(folder)
    report = json.loads(next(folder.glob("logs/loop/runs/*/report.json")).read_text())
    assert report["form_reference"]["records"] == {"2000rpm_300Nm_dte_m_40960Hz": 2,
                                                   "1800rpm_290Nm_dte_m_40960Hz": 2}


@dataclass(frozen=True)
class Case:
    size: tuple[str, ...] = ()  # size overrides appended to the command
    before: tuple[str, ...] = ()  # commands or snippets (by key) run first in the folder
    check: Callable[[Path], None] | None = None
    slow: bool = False
    needs_shared: bool = False  # reads ../shared beside the repository
    replace: dict[str, str] = field(default_factory=dict)  # size changes of a snippet
    timeout: float = 900  # [s] a hang's guard; a bench's own solo timing alone takes minutes


CASES: dict[str, Case] = {
    TRAIN_CASE3: Case(tuple(TINY_DATA + FAST_TRAIN),
                      check=_trained),
    "python -m physics.reproduce": Case(tuple(FAST_REPRO), check=_files(
        "outputs/*/*/table02_speed.csv", "outputs/*/*/wear_profile.png",
        "outputs/*/*/table14_dte_features_case3.csv")),
    "python -m physics.reproduce out_dir=results gear.module_mm=3 gear.bore_radius1_mm=12 "
    "gear.bore_radius2_mm=20 operating.torque_Nm=250 lubricant=pao":
        Case(tuple(FAST_REPRO), check=_files("results/table05_lubricant.csv")),
    "python -m physics.reproduce case=4": Case(tuple(FAST_REPRO),
                                               check=_files("outputs/*/*/table03_torque.csv")),
    "python -m physics.reproduce --help": Case(),
    "python bench/bench_wear.py": Case(slow=True),
    "python bench/bench_stiffness.py": Case(slow=True),
    "python bench/bench_dynamics.py": Case(slow=True),
    "python bench/bench_dataset.py": Case(slow=True),
    "python bench/bench_mixed_ehl.py": Case(slow=True),
    "python bench/bench_surrogate.py": Case(slow=True),
    "python train.py case=3 data.target=mean_wear_mm": Case(tuple(TINY_DATA + FAST_TRAIN),
                                                            check=_mean_wear),
    "python train.py -m case=1,2,3,4,5": Case(tuple(TINY_DATA + FAST_TRAIN), check=_files(
        "logs/train/multiruns/*/4/wear_surrogate.pt")),
    "python train.py -m model.width=16,32 model.members=3,5": Case(
        tuple([*TINY_DATA, "trainer.max_epochs=3", "trainer.min_epochs=1"]),
        check=_files("logs/train/multiruns/*/3/metrics.json")),
    "python train.py hparams_search=optuna": Case(
        tuple([*TINY_DATA, "hydra.sweeper.n_trials=2", *FAST_TRAIN]),
        check=_files("optuna_case3.db")),
    "python train.py experiment=all_cases": Case(tuple(TINY_DATA + FAST_TRAIN),
                                                 check=_files("logs/train/runs/caseall_*")),
    "python train.py experiment=model_form": Case(tuple(TINY_DATA + FAST_TRAIN), check=_files(
        "data/dataset_case3_model_form.parquet", "logs/train/runs/case3_*/wear_surrogate.pt")),
    "python -m surrogate.summarise logs/train/multiruns/<time>": Case(
        before=("python train.py -m case=1,2,3,4,5",), check=_summary),
    "python -m surrogate.predict ckpt=logs/train/runs/<run>/wear_surrogate.pt "
    "input=data/dataset_case3.parquet output=wear.csv": Case(before=(TRAIN_CASE3,),
                                                       check=_files("wear.csv")),
    TRAIN_BASELINE: Case(tuple(TINY_DATA + FAST_TRAIN), check=_mean_wear),
    "python -m surrogate.predict ckpt=logs/train/runs/<run>/wear_surrogate.pt "
    "input=data/dataset_case3.parquet gearbox=[case,replicate] output=wear.csv": Case(
        before=(TRAIN_BASELINE,), check=_baseline),
    f"python train.py {TABLE_ARGS} data.sensors=[dte]": Case(
        tuple(FAST_TRAIN + SMALL_SPLIT), before=(USER_TABLE,),
        check=_files("logs/train/runs/case3_*/metrics.json")),
    f"python train.py {TABLE_ARGS} init_from=logs/train/runs/<run>/wear_surrogate.pt "
    "model.trainable=head": Case(("trainer.max_epochs=3", "trainer.min_epochs=1", *SMALL_SPLIT),
                                 before=(USER_TABLE,)),
    "python -m surrogate.benchmark": Case(("--max-epochs", "3"), slow=True),
    "python train.py --help": Case(),
    "python -m physics.dataset": Case(tuple(SMALL_DATASET), check=_files(
        "data/dataset.parquet", "data/dataset.json")),
    "python -m physics.dataset out_dir=noisy data.replicates=4 data.nuisance.snr_db=[15,25] "
    "store_signals=true": Case(("data.wear_states=3",), check=_files(
        "noisy/dataset_signals.npy")),
    "python -m physics.dataset -m chunk=0,1,2,3,4 hydra/launcher=joblib": Case(
        tuple(SMALL_DATASET), check=_files("data/dataset_chunks/chunk_004.parquet")),
    "python -m physics.loop data=demo_bundle": Case(("loop.max_nfev=4",), before=(DEMO,),
                                                    check=_report),
    "python -m physics.loop data=demo_bundle loop.candidates=[friction,tip_relief] loop.seed=1":
        Case(("loop.max_nfev=4",), before=(DEMO,), check=_report),
    "python -m physics.loop data=independent_bundle reference=sister_bundle": Case(
        ("loop.max_nfev=4", "loop.explore=4"), before=(DEMO,), check=_referenced),
    "python -m physics.loop data=../shared/reference/thesis_tables/"
    "table15_measured_acceleration_features.csv": Case(("loop.max_nfev=4",),
                                                        needs_shared=True, check=_report),
    "python -m physics.loop --help": Case(),
    "python bench/bench_loop.py": Case(("--seeds", "1", "--null-seeds", "1", "--records", "6"),
                                       slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent --both": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent --reference": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
}
SNIPPETS: dict[str, Case] = {
    's = Surrogate.load("logs/train/runs/<run>/wear_surrogate.pt")': Case(before=(TRAIN_CASE3,)),
    USER_TABLE: Case(before=(TRAIN_CASE3,), check=_files("my_wear_table.csv")),
    "res = simulate_wear(Scenario(operating=Operating(n1_rpm=2000, torque_Nm=300)), "
    "cycles=1e6)": Case(),
    DEMO: Case(replace=SMALL_BUNDLE, check=_files("demo_bundle/manifest.csv",
                                                  "independent_bundle/signals/*.npy",
                                                  "sister_bundle/manifest.csv")),
}


#: top-level keys each --help must show: the fields of the app's schema
HELP_KEYS = {
    "python -m physics.reproduce --help": [f.name for f in fields(ReproduceConfig)],
    "python -m physics.loop --help": [f.name for f in fields(LoopConfig)],
    "python train.py --help": ["case", "seed", "data", "model", "trainer", "callbacks",
                               "logger", "paths"],
}


def _fill(text: str, folder: Path) -> str:
    """The README's placeholders, filled with what earlier commands wrote in ``folder``."""
    for key, pattern in (("<run>", "logs/train/runs/*"), ("<time>", "logs/train/multiruns/*")):
        if key in text:
            text = text.replace(key, sorted(folder.glob(pattern))[-1].name)
    return text


def _run(argv: list[str], folder: Path, timeout: float = 900) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    proc = subprocess.run(argv, cwd=folder, capture_output=True, text=True, timeout=timeout,
                          env=env)
    assert proc.returncode == 0, f"{argv} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return proc


def run_step(key: str, folder: Path) -> subprocess.CompletedProcess:
    """Run a README command or snippet (by key) in ``folder`` with its size overrides."""
    if key in SNIPPETS:
        case, code = SNIPPETS[key], snippets()[key]
        for old, new in case.replace.items():
            assert old in code, f"size override {old!r} no longer matches the snippet"
            code = code.replace(old, new)
        for step in case.before:
            run_step(step, folder)
        return _run([sys.executable, "-c", _fill(code, folder)], folder)
    case = CASES[key]
    for step in case.before:
        run_step(step, folder)
    argv = _fill(key, folder).split()
    argv[0] = sys.executable
    if argv[1].startswith("bench/") or argv[1] == "train.py":  # scripts of the checkout
        argv[1] = str(ROOT / argv[1])
    if case.needs_shared:
        argv = [a.replace("../shared", str(ROOT.parent / "shared")) for a in argv]
    return _run(argv + list(case.size), folder, case.timeout)


def test_every_readme_command_has_an_acceptance_test():
    documented = set(commands())
    missing = documented - set(CASES) - set(BY_CI)
    stale = set(CASES) - documented
    assert not missing, f"README commands without an acceptance test: {sorted(missing)}"
    assert not stale, f"acceptance tests of commands the README no longer has: {sorted(stale)}"
    assert set(snippets()) == set(SNIPPETS)


def _params(table: dict[str, Case]) -> list:
    return [pytest.param(k, marks=[pytest.mark.slow] if c.slow else [], id=k[:60])
            for k, c in table.items()]


@pytest.mark.parametrize("key", _params(CASES))
def test_readme_command(key, tmp_path):
    case = CASES[key]
    if case.needs_shared and not (ROOT.parent / "shared").is_dir():
        pytest.skip("shared/ is not beside this checkout")
    proc = run_step(key, tmp_path)
    if key.endswith("--help"):  # the help shows the config, generated from the app's schema
        assert "Powered by Hydra" in proc.stdout and "== Config ==" in proc.stdout
        for name in HELP_KEYS[key]:
            assert f"\n{name}:" in proc.stdout, f"{name} missing from {key}"
    if case.check is not None:
        case.check(tmp_path)


@pytest.mark.parametrize("key", _params(SNIPPETS))
def test_readme_snippet(key, tmp_path):
    run_step(key, tmp_path)
    if SNIPPETS[key].check is not None:
        SNIPPETS[key].check(tmp_path)

