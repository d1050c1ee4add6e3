"""A minimal app on the shared plumbing (physics.command), for the sweep tests: ``x`` must be
>= 0 (checked), and ``x=13`` fails while it works; each job writes ``done.txt``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import hydra
from hydra.core.config_store import ConfigStore
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from physics.command import entry, run_command


@dataclass
class Conf:
    x: int = 0


ConfigStore.instance().store(name="sweep_app", node={
    "defaults": ["sweep_app_schema", "_self_"],
    "hydra": {"callbacks": {"run_record": {"_target_": "physics.command.RunRecord"}},
              "job": {"chdir": False}}})
ConfigStore.instance().store(name="sweep_app_schema", node=Conf)


def prepare(cfg: DictConfig) -> tuple[int, Path]:
    if cfg.x < 0:
        raise ValueError(f"x = {cfg.x} must be >= 0")
    return cfg.x, Path(HydraConfig.get().runtime.output_dir)


def execute(plan: tuple[int, Path]) -> int:
    x, out = plan
    if x == 13:
        raise RuntimeError("thirteen")
    (out / "done.txt").write_text(str(x))
    return x


@hydra.main(version_base="1.3", config_path=None, config_name="sweep_app")
def task(cfg: DictConfig) -> int:
    return run_command(cfg, prepare, execute)


main = entry(task, check=prepare)

if __name__ == "__main__":
    main()
