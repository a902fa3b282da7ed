"""Board personalities, as data (``shared/design/ARCHITECTURE.md``: "PC48-2 … PCIX-400 are rows,
not subclasses full of ``if model ==``")."""

from __future__ import annotations

from dataclasses import replace

from omsd.models.pc46 import PC46_MODELS
from omsd.models.pc48 import PC48_MODELS
from omsd.models.pcix import PCIX_MODELS
from omsd.models.spec import CommandSpec, Model
from omsd.models.vs4 import VS4_MODELS

MODELS: dict[str, Model] = {
    m.name: m for m in (*PC48_MODELS, *PC46_MODELS, *VS4_MODELS, *PCIX_MODELS)
}


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


def variant(
    model: Model,
    encoders: str | None = None,
    serial: str | None = None,
    firmware: str | None = None,
    max_queries: bool | None = None,
) -> Model:
    """The same product as fitted and labelled in one installation: which axes have encoders
    (``""`` for none; a VS4 may be ordered without), the serial number WY reports, the firmware
    revision."""
    if encoders is not None:
        unknown = set(encoders) - set(model.axes)
        if unknown:
            raise ValueError(f"{model.name} has no axis {''.join(sorted(unknown))}")
        model = replace(model, encoder_axes="".join(a for a in model.axes if a in encoders))
    if serial is not None:
        model = replace(model, serial=serial)
    if firmware is not None:
        model = replace(model, firmware=firmware)
    if max_queries is not None:
        model = replace(model, max_queries=max_queries and model.dialect == "pcix")
    return model


__all__ = ["MODELS", "CommandSpec", "Model", "UnknownModel", "get_model", "variant"]
