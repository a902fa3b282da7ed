"""What ``omsd top`` shows, made from a subscription's messages (:mod:`omsd.control.watch`).

Issue 18: "boards, axes with the same columns [position, encoder, velocity, motion, done,
limits, home, queue space], a sparkline or bar of position within the travel, the last events,
the traffic rate". :class:`View` keeps it, bounded whatever the run's length: the boards' states
(the subscription's, merged), the last :data:`EVENTS` events, per board the traffic counts of
the last :data:`WINDOW` seconds, per axis the lowest and highest position seen. :func:`plain`
writes it as text (one snapshot, when standard output is not a terminal), :func:`screen` as a
rich renderable for the live view.

The bar places the carriage (``physical``: steps from where it was at power-up, which is where
the limit switches are measured from; ``LP`` moves the counter, not the carriage) between the
limit switches of the board's configuration, ``[board.axes.X] negative_limit`` and
``positive_limit``; for an axis whose configuration leaves them far away (the defaults), between
the lowest and the highest position seen since ``omsd top`` started.
"""

from __future__ import annotations

import time
from collections import deque
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rich.console import RenderableType

EVENTS = 50
"""Events kept (the screen shows as many of the last as fit)."""

WINDOW = 1.0
"""Seconds the traffic rate is counted over."""

BAR = 10
"""Characters of the position bar, its ends included."""

COLUMNS = ("axis", "position", "encoder", "velocity", "motion", "done", "limits", "home", "queue")


class Meter:
    """Bytes in and out of one board in the last :data:`WINDOW` seconds, from the running
    totals the ``state`` messages carry (which start at 0 with the subscription)."""

    def __init__(self, now: float) -> None:
        self.samples: deque[tuple[float, int, int]] = deque([(now, 0, 0)])

    def add(self, now: float, total_in: int, total_out: int) -> None:
        self.samples.append((now, total_in, total_out))
        self._trim(now)

    def _trim(self, now: float) -> None:
        """Keep one sample at or before the window's start: the totals then."""
        samples = self.samples
        while len(samples) >= 2 and samples[1][0] <= now - WINDOW:
            samples.popleft()

    def rate(self, now: float) -> tuple[float, float]:
        """Bytes a second in and out, over the last :data:`WINDOW` seconds."""
        self._trim(now)
        _, in0, out0 = self.samples[0]
        _, in1, out1 = self.samples[-1]
        return (in1 - in0) / WINDOW, (out1 - out0) / WINDOW


class View:
    """The boards as the subscription shows them. ``states`` is the subscription's (merged as
    its messages are read); :meth:`apply` takes each message."""

    def __init__(
        self,
        snapshot: dict[str, Any],
        states: dict[str, dict[str, Any]],
        where: str,
        select: str | None = None,
        now: float | None = None,
    ) -> None:
        now = time.monotonic() if now is None else now
        self.where = where
        self.rate = float(snapshot.get("rate", 0.0))
        self.boards: list[dict[str, Any]] = list(snapshot["boards"])
        self.names: list[str] = [str(b["name"]) for b in self.boards]
        self.states = states
        self.events: deque[dict[str, Any]] = deque(maxlen=EVENTS)
        self.meters = {name: Meter(now) for name in self.names}
        self.dropped: dict[str, int] = {}
        self.seen: dict[tuple[str, str], list[float]] = {}
        self.selected = self.names.index(select) if select in self.names else 0
        self.paused = False
        for name in self.names:
            self._see(name)

    @property
    def board(self) -> str:
        return self.names[self.selected]

    def apply(self, message: dict[str, Any], now: float) -> None:
        kind = message.get("kind")
        if kind == "event":
            self.events.append(message["event"])
        elif kind == "state":
            for name in message.get("boards", {}):
                if name in self.states:
                    self._see(name)
            for name, counts in message.get("traffic", {}).items():
                if name in self.meters:
                    self.meters[name].add(now, counts["in"], counts["out"])
            self.dropped = message.get("dropped", self.dropped)

    def _see(self, name: str) -> None:
        for letter, axis in self.states[name]["axes"].items():
            where = axis.get("physical")
            if where is None:
                continue
            seen = self.seen.setdefault((name, letter), [where, where])
            seen[0] = min(seen[0], where)
            seen[1] = max(seen[1], where)

    def key(self, key: str) -> bool:
        """A key from :func:`omsd.top.keys`; False for ``quit``."""
        if key == "quit":
            return False
        if key == "pause":
            self.paused = not self.paused
        elif key == "next":
            self.selected = (self.selected + 1) % len(self.names)
        elif key == "previous":
            self.selected = (self.selected - 1) % len(self.names)
        elif key.isdigit() and 1 <= int(key) <= len(self.names):
            self.selected = int(key) - 1
        return True

    def busy(self, now: float) -> bool:
        """Whether a traffic rate is still to fall to 0 (the screen is drawn again for it)."""
        return any(m.rate(now) != (0.0, 0.0) for m in self.meters.values())

    def span(self, name: str, letter: str) -> tuple[float, float] | None:
        """The travel the bar spans: the configured limit switches, else the range seen."""
        entry = self.boards[self.names.index(name)]
        limits = entry.get("travel", {}).get(letter)
        if limits is not None:
            return float(limits[0]), float(limits[1])
        seen = self.seen.get((name, letter))
        if seen is None or seen[1] <= seen[0]:
            return None
        return seen[0], seen[1]


# -- cells ---------------------------------------------------------------------------------------


def bar(
    where: float, span: tuple[float, float] | None, width: int = BAR, ascii: bool = False
) -> str:
    """The carriage between the ends of ``span``: ``[---#------]`` (``ascii``) or
    ``├──●───────┤``; blank dashes when there is no span."""
    left, right, line, mark = ("[", "]", "-", "#") if ascii else ("├", "┤", "─", "●")
    inner = width - 2
    if span is None:
        return left + line * inner + right
    lo, hi = span
    at = 0 if hi <= lo else round((min(max(where, lo), hi) - lo) / (hi - lo) * (inner - 1))
    return left + line * at + mark + line * (inner - 1 - at) + right


def _number(x: float) -> str:
    return f"{x:,.0f}" if abs(x) >= 1e5 else f"{x:g}"


def cells(axis: dict[str, Any]) -> list[str]:
    """The columns of ``omsd ctl``'s axis table."""
    on = [s for s, key in (("+", "limit_positive"), ("-", "limit_negative")) if axis[key]]
    return [
        str(axis["position"]),
        "-" if axis["encoder"] is None else str(axis["encoder"]),
        f"{axis['velocity']:.6g}",
        axis["motion"],
        "yes" if axis["done"] else "no",
        " ".join(on) if on else "none",
        "yes" if axis["home"] else "no",
        f"{axis['queue_free']} free",
    ]


def travel_label(span: tuple[float, float] | None, configured: bool) -> str:
    if span is None:
        return ""
    return f"{_number(span[0])}..{_number(span[1])}" + ("" if configured else " seen")


def rate_text(bytes_per_second: float) -> str:
    if bytes_per_second >= 10_000:
        return f"{bytes_per_second / 1024:,.0f} KiB/s"
    return f"{bytes_per_second:,.0f} B/s"


def clients(state: dict[str, Any]) -> str:
    return ", ".join(state.get("clients", [])) or "none"


def clients_brief(state: dict[str, Any], width: int = 28) -> str:
    """The first client and how many more, in at most ``width`` characters."""
    labels: list[str] = state.get("clients", [])
    if not labels:
        return "none"
    more = f" +{len(labels) - 1}" if len(labels) > 1 else ""
    first = (
        labels[0]
        if len(labels[0]) + len(more) <= width
        else labels[0][: width - len(more) - 1] + "…"
    )
    return first + more


def endpoints(entry: dict[str, Any]) -> str:
    return ", ".join(f"{e['kind']} {e['address']}" for e in entry["endpoints"]) or "no endpoint"


def event_line(event: dict[str, Any]) -> str:
    stamp = time.strftime("%H:%M:%S", time.localtime(event["t"]))
    return f"{stamp}.{int(event['t'] * 1000) % 1000:03d}  {event['board']}  {event['text']}"


def moving(state: dict[str, Any]) -> str:
    letters = "".join(a for a, axis in state["axes"].items() if axis["moving"])
    return f"moving {letters}" if letters else "idle"


# -- as text: one snapshot -----------------------------------------------------------------------


def align(rows: list[list[str]], right: frozenset[int] = frozenset(), gap: int = 2) -> list[str]:
    """Rows of cells as lines, each column as wide as its widest cell (``right``: the columns
    aligned to the right)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [
        (" " * gap)
        .join(
            cell.rjust(w) if i in right else cell.ljust(w)
            for i, (cell, w) in enumerate(zip(row, widths, strict=True))
        )
        .rstrip()
        for row in rows
    ]


def plain(view: View, only: str | None = None) -> str:
    """The boards as aligned text, for a pipe or a file."""
    count = f"{len(view.names)} board{'s' * (len(view.names) != 1)}"
    out = [f"omsd top: {count} ({', '.join(view.names)})"]
    for entry in view.boards:
        name = entry["name"]
        if only is not None and name != only:
            continue
        state = view.states[name]
        out += [
            "",
            f"{name}  {entry['model']}  {entry['link']}  {endpoints(entry)}",
            f"clients: {clients(state)}",
        ]
        rows = [[*COLUMNS, "travel"]]
        for letter, axis in state["axes"].items():
            span = view.span(name, letter)
            configured = letter in entry.get("travel", {})
            where = f"{bar(axis['physical'], span, ascii=True)} {travel_label(span, configured)}"
            rows.append([letter, *cells(axis), where if configured else "-"])
        out += align(rows)
    return "\n".join(out)


# -- as a screen: the live view ------------------------------------------------------------------

_BOARD_COLUMNS = ("#", "board", "model", "link", "axes", "in", "out", "clients")


def screen(view: View, now: float, width: int, height: int) -> RenderableType:
    """The live view for a terminal of ``width`` columns and ``height`` lines: at 80 columns
    every column fits, whatever its values, but the travel's ends, shown from 100. The columns
    are laid out here, and rich given lines of text: a rich ``Table`` measures every cell at
    every frame, several times the cost."""
    from rich.console import Group
    from rich.text import Text

    def line(text: str, style: str | None = None) -> Text:
        return Text(text, style=style or "", no_wrap=True, overflow="ellipsis")

    head = line(f"omsd top  {view.rate:g} looks/s", "bold")
    if view.paused:
        head.append("  PAUSED (p resumes)", style="bold yellow")
    head.append(f"  {view.where}")  # last: a long path is what the screen's edge cuts
    out = [head, line("")]
    rows = [list(_BOARD_COLUMNS)]
    for i, entry in enumerate(view.boards):
        name = entry["name"]
        state = view.states[name]
        rate_in, rate_out = view.meters[name].rate(now)
        rows.append(
            [
                str(i + 1),
                name,
                entry["model"],
                entry["link"],
                moving(state),
                rate_text(rate_in),
                rate_text(rate_out),
                clients_brief(state, max(8, width - 62)),
            ]
        )
    lines = align(rows, frozenset({0, 5, 6}))
    out += [line(lines[0], "bold"), line("─" * min(width, max(map(len, lines))))]
    for i, text in enumerate(lines[1:]):
        out.append(line(text, "reverse" if i == view.selected else None))
    name = view.board
    entry = view.boards[view.selected]
    state = view.states[name]
    out += [
        line(""),
        line(f"{name}  {entry['model']}  {entry['link']}  {endpoints(entry)}", "bold"),
    ]
    wide = width >= 100
    rows = [[*COLUMNS, "travel"] + ([""] if wide else [])]
    styles = []
    for letter, axis in state["axes"].items():
        span = view.span(name, letter)
        row = [letter, *cells(axis)[:-1], str(axis["queue_free"]), bar(axis["physical"], span)]
        if wide:
            row.append(travel_label(span, letter in entry.get("travel", {})))
        rows.append(row)
        styles.append("bold" if axis["moving"] else None)
    lines = align(rows, frozenset({1, 2, 3}), gap=2 if wide else 1)
    out += [line(lines[0], "bold"), line("─" * min(width, max(map(len, lines))))]
    out += [line(text, style) for text, style in zip(lines[1:], styles, strict=True)]
    # the lines so far, a blank, "last events" and the events, the keys
    room = height - len(out) - 3
    shown = list(view.events)[-room:] if room > 0 else []
    events = line("last events", "bold")
    if not shown:
        events.append("  (none yet)" if not view.events else "  (no room)")
    out += [line(""), events, *(line(event_line(e)) for e in shown)]
    keys = line("1-9, Tab, arrows: board   p: pause   q: quit", "dim")
    dropped = {k: v for k, v in view.dropped.items() if v}
    if dropped:
        keys.append("   dropped: " + ", ".join(f"{v} {k}" for k, v in dropped.items()))
    out.append(keys)
    return Group(*out)


__all__ = ["EVENTS", "Meter", "View", "align", "bar", "plain", "screen"]
