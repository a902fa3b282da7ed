"""The result table: figure, baseline, ratio, target, verdict, one row per measured figure."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Target:
    """``on`` is ``"ratio"`` (figure / baseline) or ``"figure"`` (the figure itself, in its unit);
    ``op`` is ``"<="`` or ``">="``."""

    on: str
    op: str
    limit: float
    unit: str = ""

    def met(self, row: Row) -> bool | None:
        value = row.ratio if self.on == "ratio" else row.figure
        if value is None or math.isnan(value):
            return None
        return value <= self.limit if self.op == "<=" else value >= self.limit

    def __str__(self) -> str:
        what = "ratio" if self.on == "ratio" else "figure"
        unit = f" {self.unit}" if self.unit else ("x" if self.on == "ratio" else "")
        return f"{what} {self.op} {_number(self.limit)}{unit}"


@dataclass(frozen=True)
class Row:
    name: str
    unit: str
    figure: float | None
    baseline: float | None = None
    target: Target | None = None
    note: str = ""
    compare: bool = True  # False: figure and baseline are themselves ratios; no ratio column
    skipped: str = ""  # why this row could not be measured here (not a failure: said, not hidden)

    @property
    def ratio(self) -> float | None:
        if not self.compare or self.figure is None or not self.baseline:
            return None
        return self.figure / self.baseline

    @property
    def verdict(self) -> str:
        if self.skipped:
            return "not measured"
        if self.figure is None:
            return "NOT MEASURED"
        if self.target is None:
            return "info"
        met = self.target.met(self)
        if met is None:
            return "NOT MEASURED"
        return "ok" if met else "MISSED"


def failed(name: str, unit: str, target: Target | None, error: BaseException) -> Row:
    """A row whose measurement raised."""
    return Row(name, unit, None, None, target, f"error: {type(error).__name__}: {error}")


def skipped(name: str, unit: str, target: Target | None, reason: str) -> Row:
    """A row that cannot be measured on this machine or in this run, and says why."""
    return Row(name, unit, None, None, target, f"not measured: {reason}", skipped=reason)


def _number(x: float) -> str:
    if x == 0.0:
        return "0"
    if abs(x) >= 1000:
        return f"{x:,.0f}"
    if abs(x) >= 100:
        return f"{x:.0f}"
    if abs(x) >= 10:
        return f"{x:.1f}"
    if abs(x) >= 1:
        return f"{x:.2f}"
    if abs(x) >= 0.01:
        return f"{x:.3f}"
    return f"{x:.2g}"


def _value(x: float | None, unit: str) -> str:
    if x is None:
        return "—"
    return f"{_number(x)} {unit}".rstrip()


def render(rows: list[Row]) -> str:
    """A Markdown table (readable as it is on a terminal), notes as a list after it."""
    head = ("benchmark", "figure", "baseline", "ratio", "target", "verdict")
    body = [
        (
            r.name,
            _value(r.figure, r.unit),
            _value(r.baseline, r.unit),
            "—" if r.ratio is None else f"{_number(r.ratio)}x",
            "—" if r.target is None else str(r.target),
            r.verdict,
        )
        for r in rows
    ]
    widths = [max(len(line[i]) for line in [head, *body]) for i in range(len(head))]

    def line(cells: tuple[str, ...]) -> str:
        return "| " + " | ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)) + " |"

    out = [line(head), "| " + " | ".join("-" * w for w in widths) + " |"]
    out += [line(cells) for cells in body]
    notes = [f"- {r.name}: {r.note}" for r in rows if r.note]
    if notes:
        out += ["", *notes]
    return "\n".join(out)
