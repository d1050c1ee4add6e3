"""The commands and Python snippets of README.md and of the docs, and how the acceptance tests
run them: as a subprocess in a folder, as a user types them.

Only size overrides are added (fewer replicates, wear states, epochs, records, trials, fit
evaluations, candidate effects); never a switch that changes which code path runs (never a
single-process job count). Scripts of the
checkout (``train.py``, ``bench/*.py``) run by their path in the checkout. A command that needs
the output of another (``surrogate.predict`` needs a trained model) starts in a copy of the
folder that command left (:attr:`Case.start`); that command runs once per test session
(``readme_folder`` in ``tests/conftest.py``) and is itself tested in that folder. Placeholders
(``<run>``, ``<time>``) are filled with what the earlier commands wrote.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
_BLOCK = re.compile(r"^```(bash|python)\n(.*?)^```", re.M | re.S)


def blocks(text: str | None = None) -> list[tuple[str, str]]:
    """(language, body) of every bash and python code block."""
    text = README.read_text() if text is None else text
    return [(m.group(1), m.group(2)) for m in _BLOCK.finditer(text)]


def _strip_comment(line: str) -> str:
    """A shell line without its trailing ``# comment`` (a ``#`` after white space)."""
    m = re.search(r"\s#", line)
    return (line[:m.start()] if m else line).strip()


def commands(text: str | None = None) -> list[str]:
    """Every shell command of the README's bash blocks, continuation lines joined, comments
    dropped, white space folded; in order, without repeats."""
    out: list[str] = []
    for lang, body in blocks(text):
        if lang != "bash":
            continue
        pending = ""
        for raw in body.splitlines():
            line = _strip_comment(raw)
            if line.endswith("\\"):
                pending += line[:-1] + " "
                continue
            cmd = " ".join((pending + line).split())
            pending = ""
            if cmd and cmd not in out:
                out.append(cmd)
    return out


def snippets(text: str | None = None) -> dict[str, str]:
    """The README's python blocks, keyed by their first line that is not an import."""
    def key(body: str) -> str:
        return next(line for line in body.splitlines()
                    if line.strip() and not line.startswith(("import ", "from ")))
    return {key(body): body for lang, body in blocks(text) if lang == "python"}


# ---------------------------------------------------------------------------------------------
# size overrides

#: run by .ci/run itself, exactly as the README writes them
BY_CI = {
    'python3.11 -m venv .venv && . .venv/bin/activate && pip install -e ".[dev]"': "the install",
    "pytest": "the test run (this suite)",
}
#: train.py's dataset: 4 replicates per case, 3 wear states over the first 3e6 cycles, 2 chunks
#: (built in parallel processes, as the README's default does); one trajectory each to validate
#: and test
SMALL_SPLIT = ("data.val_replicates=1", "data.test_replicates=1")
TINY_DATA = ("+data.generate.replicates=4", "+data.generate.wear_states=3",
             "+data.generate.cycles_max=3e6", "+data.generate.chunks=2", *SMALL_SPLIT)
FAST_TRAIN = ("trainer.max_epochs=3", "trainer.min_epochs=1", "model.members=2")
#: the reproduction's: coarser grids, one case's evolution, Table 15 at its one operating point
#: (the sweep over Tables 2 and 3's: tests/reproduce/test_table15.py)
FAST_REPRO = ("solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
              "stiffness.positions=40", "evolution.cases=[3]", "evolution.points=9",
              "evolution.table14_cycles=[0,1.5e7]", "table15_operating_points=false")
#: the dataset app's: two cases, two replicates, two wear states, in two chunks
SMALL_DATASET = ("data.cases=[2,3]", "data.replicates=2", "data.wear_states=2", "data.chunks=2")
#: fewer fit evaluations, search points and candidate effects (two, one of them the bundle's)
SMALL_LOOP = ("loop.max_nfev=4", "loop.explore=4", "loop.candidates=[friction,tip_relief]")
SMALL_BUNDLE = {"records=10, duration_s=1.0": "records=6, duration_s=0.5",
                "effect=\"friction\", seed=1)": "effect=\"friction\", seed=1, wear_mm=(0, 0.012))",
                "seed=2,\n": "seed=2, wear_mm=(0, 0.012),\n"}
TRAIN_CASE3 = "python train.py case=3"
SWEEP = "python train.py -m model.width=16,32"
DEMO = 'make_bundle("demo_bundle", Scenario(), "friction", seed=1, records=10, duration_s=1.0)'
USER_TABLE = 'rows = pd.read_parquet("data/dataset_case3.parquet")'
TABLE_ARGS = "data.table=my_wear_table.csv data.group=rig +data.columns.p2p=dte_peak_to_peak"


# ---------------------------------------------------------------------------------------------
# what a command must leave

def files(*patterns: str) -> Callable[[Path], None]:
    def check(folder: Path) -> None:
        for pattern in patterns:
            assert list(folder.glob(pattern)), f"{pattern} missing in {folder}"
    return check


def _runs(folder: Path) -> list[Path]:
    return sorted(folder.glob("logs/train/runs/case3_*"))


def trained(folder: Path) -> None:
    files("data/dataset_case3.parquet", "logs/train/runs/case3_*/wear_surrogate.pt",
          "logs/train/runs/case3_*/parity.png", "logs/train/runs/case3_*/checkpoints/*.ckpt")(
        folder)
    metrics = json.loads((_runs(folder)[-1] / "metrics.json").read_text())
    assert metrics["train_rows"] > 0 and "test_mean_relative_error_pct" in metrics


def absolute(folder: Path) -> None:
    """A run of one record alone: the root wear from the Table 13 features."""
    predictions = pd.read_csv(_runs(folder)[-1] / "test_predictions.csv")
    assert {"root_wear_mm", "root_wear_mm_pred", "root_wear_mm_upper"} <= set(predictions.columns)


def another_run(folder: Path) -> None:
    """A run on the user's table beside the one the folder started with, named after the
    table, with its metrics and the baselines beside the network."""
    runs = sorted(folder.glob("logs/train/runs/my_wear_table_*"))
    assert len(_runs(folder)) == 1 and len(runs) == 1, runs
    metrics = json.loads((runs[0] / "metrics.json").read_text())
    assert "test_linear_mean_relative_error_pct" in metrics


def predicted(folder: Path) -> None:
    """One reading per row of the input, with the model's columns."""
    wear = pd.read_csv(folder / "wear.csv")
    rows = pd.read_parquet(folder / "data" / "dataset_case3.parquet")
    assert len(wear) == len(rows)
    assert {"root_wear_mm_pred", "root_wear_mm_std", "out_of_range"} <= set(wear.columns)
    assert wear.root_wear_mm_pred.notna().all()


def baseline(folder: Path) -> None:
    """The baseline model's readings of every row, with the gearbox columns it was given."""
    wear = pd.read_csv(folder / "wear.csv")
    rows = pd.read_parquet(folder / "data" / "dataset_case3.parquet")
    assert {"case", "replicate", "cycles", "mean_wear_mm_pred"} <= set(wear.columns)
    assert len(wear) == len(rows) and wear.mean_wear_mm_pred.notna().all()
    assert (wear.replicate.to_numpy() == rows.replicate.to_numpy()).all()


def swept(folder: Path) -> None:
    """Two jobs of the joblib launcher, each a trained run, and the sweep's record."""
    sweep = next(folder.glob("logs/train/multiruns/*"))
    files("*/wear_surrogate.pt", "*/metrics.json", "multirun.yaml")(sweep)
    assert sorted(p.name for p in sweep.iterdir() if p.name.isdigit()) == ["0", "1"]


def summary(folder: Path) -> None:
    table = pd.read_csv(next(folder.glob("logs/train/multiruns/*/summary.csv")))
    assert len(table) == 2 and set(table.status) == {"ok"}
    assert {"overrides", "val/mre_pct"} <= set(table.columns)


def report(folder: Path) -> None:
    path = next(folder.glob("logs/loop/runs/*/report.json"))
    keys = set(json.loads(path.read_text()))
    assert {"chosen_effect", "error_before", "error_after"} <= keys


def referenced(folder: Path) -> None:
    """The report says which reference records it was read against, per group."""
    report(folder)
    path = next(folder.glob("logs/loop/runs/*/report.json"))
    assert json.loads(path.read_text())["form_reference"]["records"] == {
        "2000rpm_300Nm_dte_m_40960Hz": 2, "1800rpm_290Nm_dte_m_40960Hz": 2}


# ---------------------------------------------------------------------------------------------
# the tables


@dataclass(frozen=True)
class Case:
    size: tuple[str, ...] = ()  # size overrides appended to the command
    start: str | None = None  # a command or snippet (by key) whose folder this one starts from
    only: tuple[str, ...] = ()  # of that folder, only these entries (all where empty)
    check: Callable[[Path], None] | None = None
    #: a long run whose app and code path the README's commands or the unit tests already run
    #: (pytest -m slow runs it)
    slow: bool = False
    replace: dict[str, str] = field(default_factory=dict)  # size changes of a snippet
    code: str | None = None  # a snippet's code where it is not the README's
    timeout: float = 900  # [s] a hang's guard; a bench's own solo timing alone takes minutes


#: the README's commands
COMMANDS: dict[str, Case] = {
    TRAIN_CASE3: Case(TINY_DATA + FAST_TRAIN, check=trained),
    "python -m physics.reproduce": Case(FAST_REPRO, check=files(
        "outputs/*/*/table02_speed.csv", "outputs/*/*/wear_profile.png",
        "outputs/*/*/table14_dte_features_case3.csv", "outputs/*/*/table15_model.csv")),
    # the rig's contact-driven wear to 0.93 mm at eleven torques (four with both contacts): about
    # 8 minutes
    "python -m physics.reproduce.rig": Case(slow=True, timeout=2700, check=files(
        "outputs/rig/rig_comparison.csv", "outputs/rig/rig_summary.csv",
        "outputs/rig/rig_comparison.png")),
    "python -m physics.dataset": Case(SMALL_DATASET, check=files(
        "data/dataset.parquet", "data/dataset.json")),
    SWEEP: Case(TINY_DATA + FAST_TRAIN, start=TRAIN_CASE3, only=("data",),
                check=swept),
    "python -m surrogate.summarise logs/train/multiruns/<time>": Case(start=SWEEP,
                                                                      check=summary),
    "python -m surrogate.predict ckpt=logs/train/runs/<run>/wear_surrogate.pt "
    "input=data/dataset_case3.parquet gearbox=[case,replicate] output=wear.csv": Case(
        start=TRAIN_CASE3, check=baseline),
    "python -m physics.loop data=demo_bundle": Case(SMALL_LOOP, start=DEMO, check=report),
    "python bench/bench_wear.py": Case(slow=True),
}
#: the README's snippets
SNIPPETS: dict[str, Case] = {
    DEMO: Case(replace=SMALL_BUNDLE, check=files("demo_bundle/manifest.csv",
                                                 "independent_bundle/signals/*.npy",
                                                 "sister_bundle/manifest.csv")),
    "res = simulate_wear(Scenario(operating=Operating(n1_rpm=2000, torque_Nm=300)), "
    "cycles=1e6)": Case(),
    's = Surrogate.load("logs/train/runs/<run>/wear_surrogate.pt")': Case(start=TRAIN_CASE3),
}
#: the commands of the docs pages beyond the README's one example each, run the same way
DOCS: dict[str, Case] = {
    "python -m physics.reproduce out_dir=results gear.module_mm=3 gear.bore_radius1_mm=12 "
    "gear.bore_radius2_mm=20 operating.torque_Nm=250 lubricant=pao":
        Case(FAST_REPRO, check=files("results/table05_lubricant.csv"), slow=True),
    "python -m physics.reproduce case=4": Case(FAST_REPRO, slow=True,
                                               check=files("outputs/*/*/table03_torque.csv")),
    "python -m physics.reproduce --help": Case(),
    # seven gearboxes worn tooth by tooth to 15 um: about 15 minutes; one here
    "python -m physics.reproduce.teeth --out docs/figures --overwrite": Case(
        ("--grades", "5", "--seeds", "1"), slow=True, check=files(
            "docs/figures/tooth_wear.csv", "docs/figures/tooth_wear.png")),
    # seven lives to 0.3 and 1 mm: about 2 minutes; each to a tenth of its depth here
    "python -m physics.reproduce.worn_out --out docs/figures --overwrite": Case(
        ("--quick",), slow=True, check=files("docs/figures/worn_out.csv")),
    "python train.py hparams_search=optuna": Case(
        (*TINY_DATA, "hydra.sweeper.n_trials=1", *FAST_TRAIN), start=TRAIN_CASE3,
        only=("data",), check=files("optuna_case3.db"), slow=True),
    "python train.py experiment=all_cases": Case(
        ("+data.generate.replicates=3", "+data.generate.wear_states=2", *TINY_DATA[2:],
         *FAST_TRAIN), check=files("logs/train/runs/caseall_*"), slow=True),
    # an absolute network: one is trained in-process by tests/surrogate/test_surrogate.py and
    # read by predict in tests/surrogate/test_own_table.py; predict's command runs on the
    # README's baseline network
    "python train.py case=3 data.baseline=false": Case(
        TINY_DATA + FAST_TRAIN, start=TRAIN_CASE3, only=("data",), check=absolute, slow=True),
    "python -m surrogate.predict ckpt=logs/train/runs/<run>/wear_surrogate.pt "
    "input=data/dataset_case3.parquet output=wear.csv": Case(
        start="python train.py case=3 data.baseline=false", check=predicted, slow=True),
    f"python train.py {TABLE_ARGS} data.sensors=[dte]": Case(
        FAST_TRAIN + SMALL_SPLIT, start=USER_TABLE, check=another_run, slow=True),
    f"python train.py {TABLE_ARGS} init_from=logs/train/runs/<run>/wear_surrogate.pt "
    "model.trainable=head": Case(("trainer.max_epochs=3", "trainer.min_epochs=1", *SMALL_SPLIT),
                                 start=USER_TABLE, check=another_run, slow=True),
    "python train.py --help": Case(),
    "python -m physics.dataset out_dir=noisy data.replicates=4 data.nuisance.snr_db=[15,25] "
    "store_signals=true": Case(("data.cases=[3]", "data.wear_states=2", "data.chunks=2"),
                               slow=True, check=files(
        "noisy/dataset_signals.npy")),
    "python -m physics.dataset -m chunk=0,1,2,3,4 hydra/launcher=joblib": Case(
        ("data.cases=[3]", "data.replicates=5", "data.wear_states=2"), slow=True,
        check=files("data/dataset_chunks/chunk_004.parquet")),
    "python -m physics.loop data=independent_bundle reference=sister_bundle": Case(
        SMALL_LOOP, start=DEMO, check=referenced, slow=True),
    "python -m physics.loop data=physics/reference/thesis_tables/"
    "table15_measured_acceleration_features.csv": Case(SMALL_LOOP, check=report, slow=True),
    "python -m physics.loop --help": Case(),
    "python -m surrogate.benchmark": Case(("--max-epochs", "3"), slow=True),
    "python bench/bench_stiffness.py": Case(slow=True),
    "python bench/bench_contact.py": Case(slow=True),
    "python bench/bench_dynamics.py": Case(slow=True),
    "python bench/bench_dataset.py": Case(slow=True),
    "python bench/bench_mixed_ehl.py": Case(slow=True),
    "python bench/bench_surrogate.py": Case(slow=True),
    "python bench/bench_loop.py": Case(("--seeds", "1", "--null-seeds", "1", "--records", "6"),
                                       slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent --both": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent --reference": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
    "python bench/bench_loop.py --own-history 3": Case(
        ("--seeds", "1", "--null-seeds", "1", "--records", "8"), slow=True, timeout=2700),
    "python bench/bench_loop.py --generator independent --own-history 2": Case(
        ("--seeds", "1", "--null-seeds", "1"), slow=True, timeout=2700),
}
#: the snippets of the docs pages (own data): a table of a user's own, from the built dataset
DOCS_SNIPPETS: dict[str, Case] = {
    USER_TABLE: Case(start=TRAIN_CASE3, check=files("my_wear_table.csv"), code="""\
import pandas as pd

rows = pd.read_parquet("data/dataset_case3.parquet")
mine = rows.rename(columns={"dte_peak_to_peak": "p2p"}).assign(rig=rows.replicate)
mine.to_csv("my_wear_table.csv", index=False)  # features, wear_mm, a run id per trajectory
"""),
}
ALL: dict[str, Case] = {**COMMANDS, **SNIPPETS, **DOCS, **DOCS_SNIPPETS}


# ---------------------------------------------------------------------------------------------
# running them


def fill(text: str, folder: Path) -> str:
    """The placeholders, filled with what earlier commands wrote in ``folder``."""
    for key, pattern in (("<run>", "logs/train/runs/*"), ("<time>", "logs/train/multiruns/*")):
        if key in text:
            text = text.replace(key, sorted(folder.glob(pattern))[-1].name)
    return text


def run(argv: list[str], folder: Path, timeout: float = 900) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    proc = subprocess.run(argv, cwd=folder, capture_output=True, text=True, timeout=timeout,
                          env=env)
    assert proc.returncode == 0, f"{argv} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return proc


def snippet_code(key: str) -> str:
    """A snippet's code as the test runs it: with its size changes."""
    case = ALL[key]
    code = case.code if case.code is not None else snippets()[key]
    for old, new in case.replace.items():
        assert old in code, f"size override {old!r} no longer matches the snippet"
        code = code.replace(old, new)
    return code


def run_step(key: str, folder: Path) -> subprocess.CompletedProcess:
    """Run a command or snippet (by key) in ``folder`` (which holds what its start left) with
    its size overrides."""
    case = ALL[key]
    if key in SNIPPETS or key in DOCS_SNIPPETS:
        return run([sys.executable, "-c", fill(snippet_code(key), folder)], folder)
    argv = fill(key, folder).split()
    argv[0] = sys.executable
    if argv[1].startswith("bench/") or argv[1] == "train.py":  # scripts of the checkout
        argv[1] = str(ROOT / argv[1])
    # the reference data of the checkout (the command runs in a folder of its own)
    argv = [a.replace("=physics/reference/", f"={ROOT}/physics/reference/") for a in argv]
    return run(argv + list(case.size), folder, case.timeout)


def copy_start(source: Path, folder: Path, only: tuple[str, ...] = ()) -> None:
    """What a command's start left in ``source``, copied into ``folder``."""
    for name in only or [p.name for p in source.iterdir()]:
        src, dst = source / name, folder / name
        if src.is_dir():
            shutil.copytree(src, dst, symlinks=True, dirs_exist_ok=True)
        else:
            shutil.copy2(src, dst)


#: the reproduction's run, which the tests of its tables read (``tests/reproduce``)
REPRODUCE = "python -m physics.reproduce"
#: the commands and snippets that others start from or read: each runs once per test session
STARTS = sorted({c.start for c in ALL.values() if c.start is not None} | {REPRODUCE})
