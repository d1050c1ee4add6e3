"""The commands and Python snippets of README.md, as a user would copy them."""

from __future__ import annotations

import re
from pathlib import Path

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
