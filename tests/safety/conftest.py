"""What the safety tests share: small models of the user-table kind, each trained once per test
session (once per worker of a parallel run)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(scope="session")
def small_model(tmp_path_factory) -> Callable[[str], Path]:
    """``small_model(kind)``: the ``wear_surrogate.pt`` of a model trained for one epoch on the
    user table of ``test_safety_user_tables`` (``kind``: ``"auto"``, the run's own choice of
    model, or ``"network"``), in ``run/`` of a folder that also holds that table (``in.csv``)
    and the table without its group column (``features.csv``). Tests read these files and
    write elsewhere."""
    made: dict[str, Path] = {}

    def get(kind: str) -> Path:
        if kind not in made:
            from test_safety_user_tables import table, train_cfg

            from surrogate.training import train

            folder = tmp_path_factory.mktemp(f"model_{kind}")
            table().to_csv(folder / "in.csv", index=False)
            table().drop(columns="rig").to_csv(folder / "features.csv", index=False)
            kinds = {"auto": [], "network": ["model.kind=network"]}[kind]
            train(train_cfg(folder, *kinds, table="in.csv", max_epochs=1))
            made[kind] = folder / "run" / "wear_surrogate.pt"
        return made[kind]

    return get
