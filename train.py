"""Train the wear surrogate: ``python train.py case=3`` (see ``python train.py --help``).

Hydra takes a number after ``=`` as an integer and refuses integers as config-group choices, so
``case=3`` (and ``case=1,2,3``) is passed on as ``case='3'`` (``'1','2','3'``); nothing else of
the command line is touched.
"""

from __future__ import annotations

import re
import sys

import hydra
from omegaconf import DictConfig

_CASE = re.compile(r"^(\+{0,2}case=)([0-9]+(?:,[0-9]+)*)$")


def quote_case_choices(argv: list[str]) -> list[str]:
    """``case=3`` -> ``case='3'``, ``case=1,2`` -> ``case='1','2'``; other arguments unchanged."""
    out = []
    for arg in argv:
        m = _CASE.match(arg)
        out.append(m.group(1) + ",".join(f"'{c}'" for c in m.group(2).split(",")) if m else arg)
    return out


@hydra.main(version_base="1.3", config_path="conf", config_name="train")
def main(cfg: DictConfig) -> float:
    from surrogate.training import train  # after Hydra parsed the command line: fast --help

    return train(cfg)


if __name__ == "__main__":
    sys.argv = quote_case_choices(sys.argv)
    main()
