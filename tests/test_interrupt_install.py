"""Importing the package changes no process state: ``import physics`` (and its apps' packages,
the surrogate, the apps' entry modules as tests import them) leaves the SIGINT and SIGTERM
handlers and ``sys.unraisablehook`` as they were; only an app run as the program installs its
handlers (:func:`physics.interrupt.install_at_start`)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHECK = """
import signal, sys

def sentinel(signum, frame):
    pass

signal.signal(signal.SIGINT, sentinel)
signal.signal(signal.SIGTERM, sentinel)
hook = sys.unraisablehook
sys.orig_argv = [sys.executable, "-m", "physics.loop"]  # as an app's process starts

import physics, physics.loop, physics.dataset, physics.reproduce, surrogate
{more}
changed = [name for name, now in (("SIGINT", signal.getsignal(signal.SIGINT)),
                                  ("SIGTERM", signal.getsignal(signal.SIGTERM)),
                                  ("unraisablehook", sys.unraisablehook))
           if now is not (hook if name == "unraisablehook" else sentinel)]
print("changed:", changed)
"""


def imports_change(more: str = "") -> str:
    run = subprocess.run([sys.executable, "-c", CHECK.format(more=more)], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout.strip().splitlines()[-1]


def test_importing_the_packages_touches_no_signal_handler():
    assert imports_change() == "changed: []"


def test_importing_the_apps_entry_modules_touches_no_signal_handler():
    """As tests import them (their ``prepare``): the handlers come only with ``python -m``."""
    more = ("import physics.interrupt, physics.command, physics.loop.__main__, "
            "physics.dataset.__main__, physics.reproduce.__main__, surrogate.predict")
    assert imports_change(more) == "changed: []"


def test_an_app_run_as_the_program_installs_its_handlers():
    script = ("import signal\nfrom physics import interrupt\n"
              "interrupt.install_at_start('__main__')\n"
              "print(signal.getsignal(signal.SIGINT) is interrupt._on_signal "
              "and signal.getsignal(signal.SIGTERM) is interrupt._on_signal)")
    run = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert run.stdout.strip() == "True", run.stderr[-3000:]
