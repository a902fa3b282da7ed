"""Board personalities, as data (``shared/design/ARCHITECTURE.md``: "PC48-2 … PCIX-400 are rows,
not subclasses full of ``if model ==``")."""

from __future__ import annotations

from omsd.models.pc48 import PC48_MODELS
from omsd.models.spec import CommandSpec, Model

MODELS: dict[str, Model] = {m.name: m for m in PC48_MODELS}


class UnknownModel(KeyError):
    def __str__(self) -> str:
        return f"unknown board model {self.args[0]!r}; known models: {', '.join(MODELS)}"


def get_model(name: str) -> Model:
    """Look a model up by name, case-insensitively (``pc48-4e`` is ``PC48-4E``)."""
    key = name.strip().upper()
    try:
        return MODELS[key]
    except KeyError:
        raise UnknownModel(name) from None


__all__ = ["MODELS", "CommandSpec", "Model", "UnknownModel", "get_model"]
