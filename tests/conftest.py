"""Shared fixtures: the thesis baseline scenario and its geometry, and the expensive setup that
many tests share, made once per test session: the README's commands that others start from
(one trained case-3 run with its small dataset, one absolute run, one sweep, one set of demo
bundles, one user table)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from hydra.core.config_store import ConfigStore
from threadpoolctl import threadpool_limits

from physics.gear.geometry import mesh_geometry
from physics.params import GearPair, Scenario

#: a parallel run's workers (pytest-xdist) each take one core: one thread for numba's kernels,
#: BLAS and torch in the worker (numba and torch are normally not loaded yet; BLAS is, and is
#: limited where it stands) and in the apps it starts. A two-thread BLAS product on a core the other
#: worker keeps busy waits for it: a line projection of the loop took 40 times longer
THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.update(dict.fromkeys(THREADS, "1"))
    threadpool_limits(1)
    if "numba" in sys.modules:  # a plugin loaded it first: read the thread count again now,
        sys.modules["numba"].config.reload_config()  # before its pool starts


@pytest.fixture(autouse=True)
def _one_thread_each_worker():
    """Keep the workers' thread settings for every test: a library that rewrites the
    environment would otherwise leave numba, which reads NUMBA_NUM_THREADS again whenever it
    compiles, refusing a thread count that differs from its running pool's."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        os.environ.update(dict.fromkeys(THREADS, "1"))
    yield


@pytest.fixture(scope="session")
def baseline() -> Scenario:
    return Scenario()


@pytest.fixture(scope="session")
def geom():
    return mesh_geometry(GearPair())


@pytest.fixture(scope="session")
def readme_folder(tmp_path_factory) -> Callable[[str], tuple[Path, subprocess.CompletedProcess]]:
    """``readme_folder(key)``: the folder in which the README's (or a docs page's) command or
    snippet ``key`` ran, after its own start, and its process; each runs once per session.
    Tests read this folder; a test that writes starts from a copy (``readme.copy_start``)."""
    from tests.acceptance.readme import ALL, copy_start, run_step

    made: dict[str, tuple[Path, subprocess.CompletedProcess] | BaseException] = {}

    def get(key: str) -> tuple[Path, subprocess.CompletedProcess]:
        if key not in made:
            case = ALL[key]
            try:
                folder = tmp_path_factory.mktemp("readme")
                if case.start is not None:
                    copy_start(get(case.start)[0], folder, case.only)
                made[key] = (folder, run_step(key, folder))
            except BaseException as err:  # later tests that need it fail at once, alike
                made[key] = err
                raise
        result = made[key]
        if isinstance(result, BaseException):
            pytest.fail(f"the setup {key!r} failed before: {result}", pytrace=False)
        return result

    return get


#: the config groups train.py registers (``surrogate.settings.register``)
TRAIN_GROUPS = ("data", "model", "trainer")


@pytest.fixture
def config_store() -> ConfigStore:
    """Hydra's config store as a fresh app process finds it: without the groups train.py
    registers (where ``data=`` is a plain key, as in the loop, a ``data`` group would make it a
    group choice). A test that composes a train config registers them itself; after the test
    they are as they were."""
    repo = ConfigStore.instance().repo
    saved = {group: repo.pop(group) for group in TRAIN_GROUPS if group in repo}
    yield ConfigStore.instance()
    for group in TRAIN_GROUPS:
        repo.pop(group, None)
    repo.update(saved)


def _group(item: pytest.Item) -> str:
    """A test's group in a parallel run: a README command or snippet with the first command of
    the chain it starts from (what a chain makes is made once, on one worker; chains run side
    by side); any other test with the rest of its file (its module fixtures are made once). A
    test that reads a README command's run without naming it as its ``key`` parameter names it
    in its module's ``README_KEY``."""
    if "readme_folder" not in item.fixturenames:
        return item.nodeid.split("::")[0]
    from tests.acceptance.readme import ALL

    key = getattr(item, "callspec", None) and item.callspec.params.get("key")
    key = key if key in ALL else item.module.README_KEY
    while ALL[key].start is not None:
        key = ALL[key].start
    return f"readme: {key}"


def pytest_sessionstart(session: pytest.Session) -> None:
    """A parallel run's controller, before its workers start: the compiled kernels into
    numba's cache where it lacks them (``tests/kernel_cache.py``), once for all workers."""
    from tests import kernel_cache

    config = session.config
    if (config.getoption("numprocesses", None) and not hasattr(config, "workerinput")
            and kernel_cache.stale()):
        failed = kernel_cache.compile_all()
        if failed:
            config.issue_config_time_warning(pytest.PytestWarning(
                f"the kernels were not compiled ahead: {failed[-2000:]}"), stacklevel=2)


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the markers
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Keep what a shared fixture makes on one worker of a parallel run (pytest-xdist,
    ``--dist loadgroup``; :func:`_group`)."""
    for item in items:
        item.add_marker(pytest.mark.xdist_group(_group(item)))


def pytest_configure(config: pytest.Config) -> None:
    """Refuse a parallel run whose workers would not see the groups: pytest-xdist marks a
    grouped test by a suffix of its node id, which pytest 9 ignores; every worker would then
    make each shared fixture again (about a minute of the run)."""
    if config.getoption("dist", "no") == "loadgroup" and pytest.version_tuple[0] >= 9:
        raise pytest.UsageError(
            f"pytest {pytest.__version__} ignores pytest-xdist's --dist loadgroup groups; "
            'install the pinned versions: pip install -e ".[dev]"')
