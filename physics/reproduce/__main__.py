"""``python -m physics.reproduce``: the thesis tables and figures (schema
:class:`physics.reproduce.thesis.ReproduceConfig`, choices ``conf/reproduce/reproduce.yaml``)."""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import install_at_start

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import hydra
from omegaconf import DictConfig

from physics.command import entry, register_schema, run_command
from physics.reproduce.thesis import ReproduceConfig, interrupted_note, prepare, run

register_schema("reproduce_schema", ReproduceConfig)


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.reproduce",
            config_name="reproduce")
def task(cfg: DictConfig) -> None:
    run_command(cfg, prepare, run, kept=interrupted_note)


main = entry(task, check=prepare)


if __name__ == "__main__":
    main()
