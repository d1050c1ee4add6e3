"""Train the wear surrogate: ``python train.py case=3`` (see ``python train.py --help``).

``case`` is a plain key of the train config (``conf/train/train.yaml``): 1-5 for one operating
case of thesis Table 11, ``all`` for one network of the five.
"""

from __future__ import annotations

from physics.interrupt import deferred, install_at_start

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import hydra  # noqa: E402
from omegaconf import DictConfig  # noqa: E402

from physics.command import entry, run_command  # noqa: E402
from surrogate import settings  # noqa: E402

settings.register()


def prepare(cfg: DictConfig):
    """The settings that need no data and no Lightning first (refused before the slow imports),
    then a fine-tune's network and the settings it would not honour (torch alone: about 2 s),
    then the data's settings (the table or dataset read and the split planned, without
    Lightning), then the whole run's checks (:func:`surrogate.training.prepare`, whose import
    loads Lightning: about 4 s more)."""
    settings.check_run(cfg)
    with deferred():  # a signal during an import is raised after it
        from surrogate import fine_tune
    init = fine_tune.network(cfg)
    fine_tune.check_honoured(cfg, init)
    with deferred():
        from surrogate import wear_data
    wear_data.check_data(cfg.data if init is None else fine_tune.read_as(cfg.data, init))
    with deferred():
        from surrogate import training
    return training.prepare(cfg)


def fit(job):
    from surrogate import training  # imported by prepare

    return training.fit(job)


def kept(job) -> str:
    from surrogate import training  # imported by prepare

    return training.kept(job)


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.train", config_name="train")
def task(cfg: DictConfig) -> float:
    return run_command(cfg, prepare, fit, kept)


main = entry(task, check="surrogate.training:prepare", quick=settings.check_run)


if __name__ == "__main__":
    main()
