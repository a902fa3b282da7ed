"""The web dashboard's cost (issue 18): the page open in a real browser on a daemon whose 8
boards move.

"With the page open and 8 boards moving, the daemon's CPU rises by <= 2 % of a core (a bench
row); the RP latency row does not move", and "the dashboard can be left open for an hour with
bounded memory on both sides (measured and stated)".

The daemon and its load are :mod:`bench.watch`'s (8 PC48-8 boards, every axis moving, each
board polled 10 times a second and given a move with a done event every 0.7 s), with the
dashboard on a free port. The page is the real one in Debian's headless Chromium driven by
selenium (as tests/web/test_browser.py drives it), showing the first board: its axis table, its
8 plots and its traffic tail live.

* CPU rise: the daemon's CPU over a window with the page open, less its CPU over a window as
  long without it (the same load, just before). Target: <= 2 % of a core.
* Memory: the daemon's resident memory and the page's JavaScript heap
  (``performance.memory.usedJSHeapSize`` after a full collection, ``window.gc()`` with V8's
  ``--expose-gc``: what the page holds) at the start and the end of
  the window with the page open, after a warm-up; and the browser's own (every process of its
  profile, VmRSS). Bounded shows as no growth.

Without Chromium, chromedriver or selenium the rows say so. ``python -m bench.web --minutes 60``
runs the page-open window for as long, printing the figures every few minutes: the hour of the
issue, measured.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench import procs
from bench.settings import Settings
from bench.table import Row, Target, skipped
from bench.watch import BOARDS, MODEL, Load

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
PREFIX = "dashboard open, 8 boards moving"
NAMES = (
    f"{PREFIX}: daemon CPU rise with the page open",
    f"{PREFIX}: daemon memory growth with the page open",
    f"{PREFIX}: the page's JavaScript heap growth",
)


def unavailable() -> str | None:
    """Why the browser cannot be driven here, or None."""
    for path in (CHROMIUM, CHROMEDRIVER):
        if not os.access(path, os.X_OK):
            return f"no {path} (Debian's chromium and chromium-driver)"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "no selenium (pip install -e '.[test]')"
    return None


def start_daemon(directory: Path) -> tuple[procs.Server, int]:
    stamp = time.monotonic_ns()
    port = procs.free_port()
    lines = ['[log]\nview = "off"\n', "[control]\nsocket = false\n"]
    lines.append(f'[web]\nlisten = "127.0.0.1:{port}"\n')
    for i in range(BOARDS):
        lines.append(f'[[board]]\nname = "b{i + 1}"\nmodel = "{MODEL}"\ntcp = "127.0.0.1:0"\n')
    config = directory / f"web-{stamp}.toml"
    config.write_text("".join(lines))
    return procs.Server("omsd", ["--config", str(config)], BOARDS, name="omsd"), port


class Browser:
    """Headless Chromium on the dashboard (selenium), with a profile of its own so that its
    processes can be found."""

    def __init__(self, url: str, directory: Path) -> None:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        self.profile = Path(tempfile.mkdtemp(prefix="omsd-bench-chromium-", dir=directory))
        options = webdriver.ChromeOptions()
        options.binary_location = CHROMIUM
        for argument in (
            "--headless=new",
            "--no-sandbox",
            "--disable-dev-shm-usage",
            "--enable-precise-memory-info",
            "--js-flags=--expose-gc",
            "--window-size=1280,900",
            f"--user-data-dir={self.profile}",
        ):
            options.add_argument(argument)
        self.driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
        self.driver.get(url)

    def live(self, timeout: float = procs.TIMEOUT) -> None:
        deadline = time.monotonic() + timeout
        while self.driver.find_element("id", "status").text != "live":
            if time.monotonic() > deadline:
                raise RuntimeError("the page never went live")
            time.sleep(0.05)

    def heap(self) -> int:
        """The page's JavaScript heap in use after a full collection, bytes: what the page
        holds, not how far the collector has let garbage pile up."""
        used: Any = self.driver.execute_script(
            "window.gc(); return performance.memory.usedJSHeapSize"
        )
        return int(used)

    def updates(self) -> int:
        count: Any = self.driver.execute_script("return window.omsdDashboard.updates")
        return int(count)

    def pids(self) -> list[int]:
        found = []
        marker = f"--user-data-dir={self.profile}".encode()
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                with contextlib.suppress(OSError), open(f"/proc/{entry}/cmdline", "rb") as f:
                    if marker in f.read():
                        found.append(int(entry))
        return found

    def rss_kib(self) -> int:
        total = 0
        for pid in self.pids():
            with contextlib.suppress(OSError, RuntimeError):
                total += procs.rss_kib(pid)
        return total

    def cpu(self) -> float:
        total = 0.0
        for pid in self.pids():
            with contextlib.suppress(OSError, RuntimeError):
                total += procs.cpu_exact(pid)
        return total

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.driver.quit()
        shutil.rmtree(self.profile, ignore_errors=True)


@dataclass
class Sample:
    t: float
    cpu: float
    rss: int
    heap: int = 0
    browser_rss: int = 0
    browser_cpu: float = 0.0
    updates: int = 0


def sample(omsd: procs.Server, browser: Browser | None = None) -> Sample:
    if browser is None:
        return Sample(time.monotonic(), omsd.cpu(), omsd.rss_kib())
    return Sample(
        time.monotonic(),
        omsd.cpu(),
        omsd.rss_kib(),
        browser.heap(),
        browser.rss_kib(),
        browser.cpu(),
        browser.updates(),
    )


async def measure(settings: Settings, omsd: procs.Server, url: str, directory: Path) -> list[Row]:
    window = settings.watch_seconds
    load = Load(omsd)
    await load.start()
    try:
        await asyncio.sleep(window / 10)
        a0 = sample(omsd)
        await asyncio.sleep(window)
        a1 = sample(omsd)
        browser = await asyncio.to_thread(Browser, url, directory)
        try:
            await asyncio.to_thread(browser.live)
            await asyncio.sleep(max(1.0, window / 5))  # its first screens
            b0 = await asyncio.to_thread(sample, omsd, browser)
            await asyncio.sleep(window)
            b1 = await asyncio.to_thread(sample, omsd, browser)
        finally:
            await asyncio.to_thread(browser.close)
    finally:
        await load.stop()
    span = b1.t - b0.t
    without = 100.0 * (a1.cpu - a0.cpu) / (a1.t - a0.t)
    with_page = 100.0 * (b1.cpu - b0.cpu) / span
    rate = (b1.updates - b0.updates) / span
    browser_cpu = 100.0 * (b1.browser_cpu - b0.browser_cpu) / span
    polls = f"{BOARDS} boards polled 10 times a second, a move every 0.7 s on each"
    return [
        Row(
            NAMES[0],
            "% core",
            with_page - without,
            without,
            Target("figure", "<=", 2.0, "% core"),
            f"{polls}; daemon {with_page:.2f} % core with the page open in headless Chromium"
            f" and {without:.2f} % without, over {window:.1f} s each; the page applied"
            f" {rate:.1f} state messages a second; the browser itself {browser_cpu:.1f} % core",
            compare=False,
        ),
        Row(
            NAMES[1],
            "KiB",
            float(b1.rss - b0.rss),
            float(a1.rss - a0.rss),
            Target("figure", "<=", 512.0, "KiB"),
            f"VmRSS {b0.rss:,} -> {b1.rss:,} KiB over {window:.1f} s with the page open"
            f" (without: {a0.rss:,} -> {a1.rss:,} KiB); python -m bench.web --minutes 60 for"
            " the hour",
            compare=False,
        ),
        Row(
            NAMES[2],
            "KiB",
            (b1.heap - b0.heap) / 1024,
            b0.heap / 1024,
            None,  # the first minute fills the plots' 60 s windows: the hour shows the plateau
            f"usedJSHeapSize {b0.heap / 1024:,.0f} -> {b1.heap / 1024:,.0f} KiB over"
            f" {window:.1f} s (the baseline is where it started; the plots' windows fill for"
            f" their first minute); the browser's processes {b0.browser_rss:,} ->"
            f" {b1.browser_rss:,} KiB",
            compare=False,
        ),
    ]


def run(settings: Settings, directory: Path) -> list[Row]:
    reason = unavailable()
    if reason is not None:
        units = ("% core", "KiB", "KiB")
        targets = (Target("figure", "<=", 2.0, "% core"), Target("figure", "<=", 512.0, "KiB"))
        return [
            skipped(name, unit, targets[i] if i < 2 else None, reason)
            for i, (name, unit) in enumerate(zip(NAMES, units, strict=True))
        ]
    omsd, port = start_daemon(directory)
    with omsd:
        return asyncio.run(measure(settings, omsd, f"http://127.0.0.1:{port}/", directory))


# -- the hour ------------------------------------------------------------------------------------


async def long_run(minutes: float, every: float, directory: Path) -> None:
    omsd, port = start_daemon(directory)
    with omsd:
        load = Load(omsd)
        await load.start()
        browser = await asyncio.to_thread(Browser, f"http://127.0.0.1:{port}/", directory)
        try:
            await asyncio.to_thread(browser.live)
            print(
                f"the dashboard open in headless Chromium on {BOARDS} moving, polled boards for"
                f" {minutes:g} min; KiB, and % of a core over each interval",
                flush=True,
            )
            print(
                "minute  daemon_rss  daemon_cpu  page_heap  browser_rss  browser_cpu"
                "  updates_per_s",
                flush=True,
            )
            start = time.monotonic()
            last = first = await asyncio.to_thread(sample, omsd, browser)
            k = 0
            while time.monotonic() - start < minutes * 60:
                k += 1
                await asyncio.sleep(max(0.0, start + k * every * 60 - time.monotonic()))
                now = await asyncio.to_thread(sample, omsd, browser)
                span = now.t - last.t
                browser_cpu = 100 * (now.browser_cpu - last.browser_cpu) / span
                print(
                    f"{(now.t - start) / 60:6.1f}  {now.rss:10,}"
                    f"  {100 * (now.cpu - last.cpu) / span:10.2f}  {now.heap // 1024:9,}"
                    f"  {now.browser_rss:11,}  {browser_cpu:11.2f}"
                    f"  {(now.updates - last.updates) / span:13.1f}",
                    flush=True,
                )
                last = now
            print(
                f"growth from minute 0 to {(last.t - start) / 60:.1f}: daemon"
                f" {last.rss - first.rss:+,} KiB, page heap"
                f" {(last.heap - first.heap) // 1024:+,} KiB, browser"
                f" {last.browser_rss - first.browser_rss:+,} KiB",
                flush=True,
            )
        finally:
            await asyncio.to_thread(browser.close)
            await load.stop()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.web", description=__doc__)
    parser.add_argument("--minutes", type=float, default=60.0, help="how long (default 60)")
    parser.add_argument("--every", type=float, default=5.0, help="minutes between two lines")
    options = parser.parse_args(argv)
    reason = unavailable()
    if reason is not None:
        print(f"python -m bench.web: {reason}", file=sys.stderr)
        return 2
    procs.pin()
    with tempfile.TemporaryDirectory(prefix="omsd-web-") as tmp:
        asyncio.run(long_run(options.minutes, options.every, Path(tmp)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
