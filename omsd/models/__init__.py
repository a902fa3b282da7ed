"""Board personalities, as data (``shared/design/ARCHITECTURE.md``: "PC48-2 … PCIX-400 are rows,
not subclasses full of ``if model ==``").

Each family's rows are a module of their own, imported when a model is looked up that an earlier
family does not have, or when every model is listed: a daemon of PC48 boards never builds the
other families' tables (start-up, issue 16; tests/test_import_boundaries.py)."""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from dataclasses import replace

from omsd.models.spec import CommandSpec, Model

#: The families' modules and rows, in the order ``omsd models`` lists them.
_FAMILIES = (
    ("omsd.models.pc48", "PC48_MODELS"),
    ("omsd.models.pc46", "PC46_MODELS"),
    ("omsd.models.vs4", "VS4_MODELS"),
    ("omsd.models.pcix", "PCIX_MODELS"),
)


class _Models(Mapping[str, Model]):
    """Every model by name, in the order of :data:`_FAMILIES`; a family is imported when a name
    is looked up that the families before it do not have, or when the models are listed."""

    def __init__(self) -> None:
        self._models: dict[str, Model] = {}
        self._imported = 0  # families imported, in order

    def _import_next(self) -> bool:
        if self._imported == len(_FAMILIES):
            return False
        module, rows = _FAMILIES[self._imported]
        family: tuple[Model, ...] = getattr(importlib.import_module(module), rows)
        self._models.update((m.name, m) for m in family)
        self._imported += 1
        return True

    def __getitem__(self, name: str) -> Model:
        while name not in self._models:
            if not self._import_next():
                raise KeyError(name)
        return self._models[name]

    def _all(self) -> dict[str, Model]:
        while self._import_next():
            pass
        return self._models

    def __iter__(self) -> Iterator[str]:
        return iter(self._all())

    def __len__(self) -> int:
        return len(self._all())


MODELS: Mapping[str, Model] = _Models()


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
