"""The example specs shipped with the package, for ``dlasweep init``.

Each is a TOML file of ``dlasweep/sweep/specs/``, package data of the wheel,
so a user who installed dlasweep with pip starts from one without a clone.
A spec's first line is a comment, its description in ``dlasweep init --list``.
Shipping another spec is copying its file there: nothing else lists them.
"""

from __future__ import annotations

from importlib import resources

SPECS = resources.files(__package__) / "specs"


def names() -> list:
    """The shipped specs' names (their files' names without ``.toml``), sorted."""
    return sorted(entry.name.removesuffix(".toml") for entry in SPECS.iterdir() if entry.name.endswith(".toml"))


def text(name: str) -> str:
    """The text of shipped spec ``name``; ``KeyError`` naming the choices when there is none of that name."""
    if name not in names():
        raise KeyError(f"{name!r} is not a shipped spec; choose one of {', '.join(names())}")
    return (SPECS / f"{name}.toml").read_text(encoding="utf-8")


def description(name: str) -> str:
    """The one-line description of shipped spec ``name``: its first line, a comment, without the ``#``."""
    first = text(name).partition("\n")[0]
    return first.removeprefix("#").strip() if first.startswith("#") else ""
