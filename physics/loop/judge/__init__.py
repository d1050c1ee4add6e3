"""Stage 3 of the loop, the decisions: the adoption rule a candidate effect must pass
(``adoption``: the null test), spectral lines no declared order explains (``lines``) and the
verdict (``verdict``: an effect named, an unexplained residual or nothing). The search decides
with it; the report only writes what was decided."""

from __future__ import annotations

from physics.exports import lazy_exports

_SOURCES = {
    "physics.loop.judge.adoption": ("null_test", "holds", "first_passing"),
    "physics.loop.judge.lines": ("unexplained_lines",),
    "physics.loop.judge.verdict": ("VERDICTS", "judge"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
