"""The web dashboard in a real browser (issue 18): Debian's chromium, driven by Selenium.

A daemon with two boards (``xy``, a PC48-4E whose X has limit switches at -30000 and +30000,
and ``crate``, a PCIX-004) serves the page with ``--web-control`` and a token; the tests load
it headless and check what a person would see: the boards listed, the axis table and the plot
following a move made over TCP within a second, a limit switch closed from the page stopping a
jog (and the board saying so to its client), the traffic tail with its framing marks, pause
and filter, and a read-only daemon showing no buttons and refusing a forged operation. Every
test ends with the browser's console free of errors and warnings.

Skipped when chromium or chromedriver is missing, unless ``OMSD_NEED_CHROMIUM=1`` (then the
module fails). The screenshot taken mid-move goes to ``$OMSD_ARTIFACTS/dashboard.png``
(default ``build/artifacts/``), and to ``docs/dashboard.png`` with ``OMSD_WRITE_SCREENSHOT=1``.
"""

from __future__ import annotations

import os
import re
import shutil
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from daemon.process import Conn, Daemon, Omsd, wait_for

from omsd.control.client import Control
from omsd.telemetry.lines import visible

ROOT = Path(__file__).resolve().parent.parent.parent
CHROMIUM = Path(os.environ.get("OMSD_CHROMIUM", "/usr/bin/chromium"))
CHROMEDRIVER = Path(os.environ.get("OMSD_CHROMEDRIVER", "/usr/bin/chromedriver"))


def _missing() -> list[str]:
    missing = [str(path) for path in (CHROMIUM, CHROMEDRIVER) if not path.exists()]
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("the selenium package")
    return missing


if _missing():
    _REASON = (
        f"the browser test needs {', '.join(_missing())} (Debian: apt install chromium"
        " chromium-driver; pip install selenium)"
    )
    if os.environ.get("OMSD_NEED_CHROMIUM") == "1":
        pytest.fail(f"OMSD_NEED_CHROMIUM=1 but {_REASON}", pytrace=False)
    pytest.skip(_REASON, allow_module_level=True)

from selenium import webdriver  # noqa: E402
from selenium.common.exceptions import StaleElementReferenceException  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402
from selenium.webdriver.remote.webelement import WebElement  # noqa: E402

WITHIN = 1.0
"""Seconds the page has to show what happened on a board (issue 18: live, >= 10 updates/s)."""

TOKEN = "browser-test-token-0123456789"

BOARDS = """\
[[board]]
name = "xy"
model = "PC48-4E"
tcp = "127.0.0.1:0"

[board.axes.X]
negative_limit = -30000
positive_limit = 30000
home_low = 0
home_high = 100

[[board]]
name = "crate"
model = "PCIX-004"
tcp = "127.0.0.1:0"
"""


@dataclass
class Dashboard:
    """A daemon serving the page: its address, and a control client for setting up."""

    daemon: Daemon
    url: str
    control: Control | None = None

    def board(self, name: str) -> Conn:
        return self.daemon.connect(name)


def start(omsd: Omsd, directory: Path, *, control: bool) -> Dashboard:
    """A daemon with the two boards and the dashboard on a free port (read from its log)."""
    socket = directory / ("ctl.sock" if control else "ctl-ro.sock")
    web = f'[web]\ntoken = "{TOKEN}"\n' if control else ""
    config = f'[control]\nsocket = "{socket}"\n\n{web}\n{BOARDS}'
    args = ["--web", "127.0.0.1:0"] + (["--web-control"] if control else [])
    daemon = omsd(*args, config=config, expect=2)
    found: list[str] = []

    def announced() -> bool:
        found[:] = re.findall(r"web dashboard (http://127\.0\.0\.1:\d+/)", daemon.stderr)
        return bool(found)

    assert wait_for(announced), f"no dashboard address in {daemon.stderr!r}"
    url = found[0] + (f"?token={TOKEN}" if control else "")
    return Dashboard(daemon, url, Control(socket, timeout=10.0) if control else None)


# -- fixtures -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def daemons(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Omsd]:
    starter = Omsd(tmp_path_factory.mktemp("web"))
    try:
        yield starter
    finally:
        starter.close()


@pytest.fixture(scope="module")
def dashboard(daemons: Omsd) -> Iterator[Dashboard]:
    """The daemon with --web-control (and a token the page must pass on to its socket)."""
    served = start(daemons, daemons.directory, control=True)
    try:
        yield served
    finally:
        assert served.control is not None
        served.control.close()


@pytest.fixture(scope="module")
def driver() -> Iterator[WebDriver]:
    """One headless chromium for the module, its page 1280x900."""
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    browser = webdriver.Chrome(options=options, service=Service(str(CHROMEDRIVER)))
    try:
        browser.set_window_size(1280, 900)
        chrome = browser.execute_script("return window.outerHeight - window.innerHeight")
        browser.set_window_size(1280, 900 + int(chrome))
        yield browser
    finally:
        browser.quit()


@pytest.fixture(autouse=True)
def clean_console(driver: WebDriver) -> Iterator[None]:
    """Every test ends with no error and no warning in the browser's console."""
    driver.get_log("browser")  # what an earlier test left
    yield
    bad = [e for e in driver.get_log("browser") if e["level"] in ("SEVERE", "WARNING")]
    assert not bad, f"the browser's console: {bad}"


# -- helpers --------------------------------------------------------------------------------------


def within(condition: Callable[[], object], timeout: float, what: str) -> float:
    """Seconds until ``condition()`` holds; fails naming ``what`` after ``timeout``. An element
    the page removed between being found and being read (the traffic tail drops its oldest
    lines as new ones come) is "not yet": the condition is asked again."""

    def holds() -> bool:
        try:
            return bool(condition())
        except StaleElementReferenceException:
            return False

    begun = time.monotonic()
    assert wait_for(holds, timeout), f"not within {timeout} s: {what}"
    return time.monotonic() - begun


def open_page(driver: WebDriver, url: str) -> None:
    driver.get(url)
    within(lambda: status(driver) == "live", 10.0, "#status says live")


def status(driver: WebDriver) -> str:
    return str(driver.execute_script("return document.querySelector('#status').textContent"))


def cell(driver: WebDriver, axis: str, field: str) -> str:
    text = driver.execute_script(
        "const td = document.querySelector(`#axes tr[data-axis='${arguments[0]}']"
        " td[data-field='${arguments[1]}']`); return td && td.textContent",
        axis,
        field,
    )
    return str(text)


def dash(driver: WebDriver, expression: str, *args: Any) -> Any:
    """``expression`` evaluated with ``d`` = window.omsdDashboard."""
    return driver.execute_script(f"const d = window.omsdDashboard; return {expression};", *args)


def select_board(driver: WebDriver, name: str) -> None:
    driver.find_element(By.CSS_SELECTOR, f'#boards [data-board="{name}"]').click()
    within(lambda: dash(driver, "d.live") == name, WITHIN, f"{name} selected and live")


def park_x(dashboard: Dashboard) -> None:
    """X of xy at rest at 0 (inside its limits), its switches following the carriage."""
    ctl = dashboard.control
    assert ctl is not None
    for direction in (1, -1):
        ctl.set_limit("X", direction, None, board="xy")

    def parked() -> bool:
        x = ctl.state("xy")["axes"]["X"]
        return bool(x["position"] == 0 and not x["moving"])

    if not parked():
        with dashboard.board("xy") as conn:
            conn.send(b"AX ST\r")
            assert wait_for(lambda: not ctl.state("xy")["axes"]["X"]["moving"])
            conn.send(b"AX VL200000 MA0 GO\r")
            assert wait_for(parked), ctl.state("xy")["axes"]["X"]


def axis_status(conn: Conn) -> str:
    """X's RA reply: direction, done, limit, home (``PNLN``). Lines before it that are not
    four such letters (the driver link's ``@`` after a limit) are passed over."""
    conn.send(b"AX RA\r")
    for _ in range(10):
        line = conn.read_until(b"\n").strip(b"\r\n")
        if re.fullmatch(rb"[PM][DN][LN][HN]", line):
            return line.decode()
    raise AssertionError("no RA reply among 10 lines")


def board_field(driver: WebDriver, board: str, field: str) -> str:
    """A field of a board's entry in the list: model, link, endpoints, clients, traffic."""
    selector = f'#boards [data-board="{board}"] [data-field="{field}"]'
    return str(driver.find_element(By.CSS_SELECTOR, selector).text)


def traffic_lines(driver: WebDriver, kind: str = "") -> list[WebElement]:
    """The traffic tail's lines; ``kind`` ".in" or ".out" for one direction."""
    return list(driver.find_elements(By.CSS_SELECTOR, f"#traffic .traffic-line{kind}"))


def data_colour(driver: WebDriver, kind: str) -> str:
    """The colour of the data of the last line of one direction."""
    data = traffic_lines(driver, kind)[-1].find_element(By.CSS_SELECTOR, ".data")
    return str(data.value_of_css_property("color"))


def displayed(elements: list[WebElement]) -> list[WebElement]:
    return [e for e in elements if e.is_displayed()]


def save_screenshot(driver: WebDriver) -> None:
    """The page mid-move: build/artifacts/dashboard.png ($OMSD_ARTIFACTS), and the README's
    docs/dashboard.png with OMSD_WRITE_SCREENSHOT=1."""
    artifacts = Path(os.environ.get("OMSD_ARTIFACTS") or ROOT / "build" / "artifacts")
    artifacts.mkdir(parents=True, exist_ok=True)
    png = driver.get_screenshot_as_png()
    (artifacts / "dashboard.png").write_bytes(png)
    if os.environ.get("OMSD_WRITE_SCREENSHOT") == "1":
        shutil.copyfile(artifacts / "dashboard.png", ROOT / "docs" / "dashboard.png")


# -- the tests ------------------------------------------------------------------------------------


def test_the_page_lists_every_board_with_its_model_link_and_endpoints(
    driver: WebDriver, dashboard: Dashboard
) -> None:
    open_page(driver, dashboard.url)

    for endpoint in dashboard.daemon.endpoints:
        assert board_field(driver, endpoint.board, "model") == endpoint.model
        assert board_field(driver, endpoint.board, "link") == endpoint.link
        endpoints = board_field(driver, endpoint.board, "endpoints")
        assert f"{endpoint.kind} {endpoint.address}" in endpoints
        assert board_field(driver, endpoint.board, "clients") == "clients: none"
    assert len(driver.find_elements(By.CSS_SELECTOR, "#boards [data-board]")) == 2
    assert sorted(dash(driver, "Object.keys(d.boards)")) == ["crate", "xy"]
    assert driver.find_element(By.CSS_SELECTOR, "#version").text == "v0.1.0"
    assert driver.find_element(By.CSS_SELECTOR, "#mode").text == "control"

    # the first board is shown; another is a click away, its axes and plots with it
    assert dash(driver, "d.selected") == "xy"
    assert cell(driver, "X", "encoder") == "0"  # a PC48-4E has encoders
    select_board(driver, "crate")
    rows = driver.find_elements(By.CSS_SELECTOR, "#axes tr[data-axis]")
    assert [r.get_attribute("data-axis") for r in rows] == ["X", "Y", "Z", "T"]
    assert cell(driver, "X", "encoder") == "–"  # a PCIX-004 has no encoders
    assert cell(driver, "X", "queue_free").isdigit()
    for letter in "XYZT":
        assert driver.find_element(By.CSS_SELECTOR, f"#plot-{letter} canvas").is_displayed()
    assert "crate" in driver.find_element(By.CSS_SELECTOR, "#traffic-board").text
    select_board(driver, "xy")
    assert "selected" in (
        driver.find_element(By.CSS_SELECTOR, '#boards [data-board="xy"]').get_attribute("class")
        or ""
    )


def test_a_move_shows_in_the_table_and_the_plot_within_a_second(
    driver: WebDriver, dashboard: Dashboard
) -> None:
    park_x(dashboard)
    open_page(driver, dashboard.url)
    within(lambda: cell(driver, "X", "position") == "0", WITHIN, "X at 0 in the table")
    points = dash(driver, "d.points('xy', 'X')")
    assert points >= 1

    with dashboard.board("xy") as conn:
        conn.send(b"AY VL12000 MR-12000 GO AX VL20000 MR25000 GO\r")
        sent = time.monotonic()
        within(lambda: cell(driver, "X", "position") not in ("0", "None"), WITHIN, "position")
        within(lambda: dash(driver, "d.points('xy', 'X')") > points, WITHIN, "new plot points")
        within(lambda: dash(driver, "d.lastPoint('xy', 'X').position") > 0, WITHIN, "plot moved")
        assert time.monotonic() - sent < WITHIN
        # live: at least 10 state messages a second while X moves
        before = dash(driver, "d.updates")
        time.sleep(0.5)
        assert dash(driver, "d.updates") - before >= 5
        assert cell(driver, "X", "motion") == "move"
        assert int(cell(driver, "X", "velocity")) > 0

        assert dashboard.control is not None
        dashboard.control.wait_idle(board="xy")
        within(lambda: cell(driver, "X", "position") == "25000", WITHIN, "X at 25000")
        assert cell(driver, "X", "velocity") == "0"
        # idle: nothing more comes
        time.sleep(0.2)
        quiet = dash(driver, "d.updates")
        time.sleep(1.0)
        assert dash(driver, "d.updates") == quiet
        assert conn.quiet(0.05) == b""

        # and back: the picture of the page mid-move, a minute's plot with both moves
        conn.send(b"AX VL40000 MR-25000 GO\r")
        within(lambda: int(cell(driver, "X", "velocity")) < 0, WITHIN, "X on its way back")
        time.sleep(0.3)
        save_screenshot(driver)
        assert wait_for(lambda: dash(driver, "d.boards.xy.axes.X.position") == 0)


def test_a_limit_closed_from_the_page_stops_a_jog(driver: WebDriver, dashboard: Dashboard) -> None:
    park_x(dashboard)
    open_page(driver, dashboard.url)
    limit = driver.find_element(
        By.CSS_SELECTOR, 'button[data-op="limit"][data-axis="X"][data-direction="1"]'
    )

    with dashboard.board("xy") as conn:
        conn.send(b"AX VL5000 JG5000\r")
        within(lambda: cell(driver, "X", "velocity") == "5000", WITHIN, "X jogging")
        limit.click()
        clicked = time.monotonic()
        within(lambda: cell(driver, "X", "velocity") == "0", WITHIN, "X stopped")
        within(lambda: cell(driver, "X", "limit_positive") == "yes", WITHIN, "limit shown")
        assert time.monotonic() - clicked < WITHIN
        assert dash(driver, "d.boards.xy.axes.X.moving") is False
        assert "active" in (limit.get_attribute("class") or "")
        assert axis_status(conn)[2] == "L"

        limit.click()  # and open again: the switch follows the carriage
        within(lambda: cell(driver, "X", "limit_positive") == "no", WITHIN, "limit open")
        assert axis_status(conn)[2] == "N"
    assert driver.find_element(By.CSS_SELECTOR, "#error").text == ""
    events = driver.find_element(By.CSS_SELECTOR, "#events").text
    assert "limit X+" in events


def test_the_traffic_tail_shows_framing_marks_pauses_and_filters(
    driver: WebDriver, dashboard: Dashboard
) -> None:
    open_page(driver, dashboard.url)

    def shown(kind: str, text: str) -> bool:
        return any(text in line.text for line in traffic_lines(driver, kind))

    with dashboard.board("xy") as conn:
        reply = axis_status(conn)
        within(lambda: shown(".out", reply), WITHIN, "RA's reply in the tail")
        sent = [line.text for line in traffic_lines(driver, ".in")]
        assert any(re.search(r" <- AX RA<CR>$", text) for text in sent), sent
        out = [line.text for line in traffic_lines(driver, ".out") if reply in line.text]
        assert re.search(rf" -> {reply}<LF>$", out[0]), out
        marks = driver.find_elements(By.CSS_SELECTOR, "#traffic .traffic-line.in .mark")
        assert "<CR>" in [mark.text for mark in marks]
        assert data_colour(driver, ".in") != data_colour(driver, ".out")

        # paused: nothing is appended, what was skipped is counted
        count = len(traffic_lines(driver))
        pause = driver.find_element(By.CSS_SELECTOR, "#traffic-pause")
        pause.click()
        assert pause.text == "resume"
        conn.send(b"AX RP\r")
        conn.read_until(b"\n")
        skipped = driver.find_element(By.CSS_SELECTOR, "#traffic-skipped")

        def counted() -> bool:
            found = re.fullmatch(r"paused: (\d+) skipped", skipped.text)
            return found is not None and int(found.group(1)) >= 2  # the command and its reply

        within(counted, WITHIN, "the skipped chunks counted")
        assert len(traffic_lines(driver)) == count
        pause.click()
        assert skipped.text == ""
        conn.send(b"AX RP\r")
        conn.read_until(b"\n")
        within(lambda: shown(".in", "AX RP"), WITHIN, "traffic again after resume")

    # the filter hides what does not match (case-insensitive)
    search = driver.find_element(By.CSS_SELECTOR, "#traffic-filter")
    search.send_keys("ax rp")
    matching = displayed(traffic_lines(driver))
    assert matching
    assert all("ax rp" in line.text.lower() for line in matching)
    assert not displayed([line for line in traffic_lines(driver) if "RA" in line.text])
    search.clear()
    search.send_keys(" ")  # an input event, and a filter of only spaces is no filter
    assert len(displayed(traffic_lines(driver))) == len(traffic_lines(driver))


def test_the_traffic_tail_and_the_events_stay_bounded(
    driver: WebDriver, dashboard: Dashboard
) -> None:
    """At most 500 traffic lines and 100 events in the page, the newest kept."""
    open_page(driver, dashboard.url)
    with dashboard.board("xy") as conn:
        for _ in range(150):
            assert conn.ask(b"PL\r") == b"#"  # not a command: an error event each
        for _ in range(250):
            conn.ask(b"AX RP\r")
        status = conn.ask(b"AX RA\r").decode()  # the last: its reply is the newest line

    def last_line() -> str:
        lines = traffic_lines(driver)
        return str(lines[-1].text) if lines else ""

    within(lambda: last_line().endswith(f"-> {status}<LF>"), 5.0, "the last reply in the tail")
    assert len(traffic_lines(driver)) == 500
    events = driver.find_elements(By.CSS_SELECTOR, "#events li")
    assert len(events) == 100
    assert "xy" in events[0].text


def test_the_framing_marks_are_the_plain_views(driver: WebDriver, dashboard: Dashboard) -> None:
    """visible() ported to the page gives what omsd.telemetry.lines.visible gives, byte by byte."""
    open_page(driver, dashboard.url)
    every = bytes(range(256))
    assert dash(driver, "d.visible(arguments[0])", every.decode("latin-1")) == visible(every)


def click(driver: WebDriver, selector: str) -> None:
    driver.find_element(By.CSS_SELECTOR, selector).click()


def fill(driver: WebDriver, selector: str, value: str) -> None:
    field = driver.find_element(By.CSS_SELECTOR, selector)
    field.clear()
    field.send_keys(value)


def test_every_button_does_what_omsd_ctl_does(driver: WebDriver, dashboard: Dashboard) -> None:
    """The issue's list: a home switch, an input, a slip, a stall, the cable, the board's time
    (pause, step, scale, resume) and a reset, each from its button, each seen in the state the
    control API gives (the limit switches: the test above)."""
    ctl = dashboard.control
    assert ctl is not None
    open_page(driver, dashboard.url)
    select_board(driver, "xy")
    park_x(dashboard)

    def state() -> dict[str, Any]:
        return ctl.state("xy")

    def shows(selector: str, mark: str) -> bool:
        classes = driver.find_element(By.CSS_SELECTOR, selector).get_attribute("class")
        return mark in (classes or "").split()

    home = 'button[data-op="home"][data-axis="X"]'
    # the page has seen X parked at 0, in its home window (0...100): the switch reads closed
    # there, so the click forces it open
    within(
        lambda: dash(driver, "[d.boards.xy.axes.X.position, d.boards.xy.axes.X.home]") == [0, True],
        WITHIN,
        "the page shows X at 0 on its home switch",
    )
    click(driver, home)
    within(lambda: state()["world"]["home"] == {"X": False}, WITHIN, "home forced open")
    within(lambda: shows(home, "forced"), WITHIN, "the page shows the switch forced")
    click(driver, home)  # a forced switch: the click lets it follow the carriage again
    within(lambda: state()["world"]["home"] == {}, WITHIN, "home following the carriage")
    fill(driver, "#input-bit", "3")
    click(driver, 'button[data-op="input"][data-high="false"]')
    within(lambda: state()["world"]["inputs"] == {"3": False}, WITHIN, "input 3 driven low")
    click(driver, 'button[data-op="input"][data-high="null"]')
    within(lambda: state()["world"]["inputs"] == {}, WITHIN, "input 3 released")
    fill(driver, "#slip-steps", "25")
    before = state()["axes"]["Y"]["physical"]
    click(driver, 'button[data-op="slip"][data-axis="Y"]')
    within(lambda: state()["axes"]["Y"]["physical"] == before + 25, WITHIN, "Y slipped 25")
    click(driver, 'button[data-op="stall"][data-axis="Z"]')
    within(lambda: state()["world"]["stalled"] == ["Z"], WITHIN, "Z stalled")
    stall = 'button[data-op="stall"][data-axis="Z"]'
    within(lambda: shows(stall, "active"), WITHIN, "the stall button shows it")
    click(driver, 'button[data-op="stall"][data-axis="Z"]')
    within(lambda: state()["world"]["stalled"] == [], WITHIN, "Z running again")
    click(driver, 'button[data-op="cable"]')
    within(lambda: state()["faults"]["cable"] is False, WITHIN, "cable cut")
    within(lambda: dash(driver, "d.boards.xy.faults.cable") is False, WITHIN, "shown cut")
    click(driver, 'button[data-op="cable"]')
    within(lambda: state()["faults"]["cable"] is True, WITHIN, "cable restored")
    click(driver, 'button[data-op="time"][data-action="pause"]')
    within(lambda: state()["clock"]["paused"] is True, WITHIN, "time paused")
    paused_at = state()["time"]
    fill(driver, "#time-step", "0.5")
    click(driver, 'button[data-op="time"][data-action="step"]')
    within(lambda: abs(state()["time"] - paused_at - 0.5) < 1e-6, WITHIN, "stepped 0.5 s")
    fill(driver, "#time-scale", "2")
    click(driver, 'button[data-op="time"][data-action="scale"]')
    within(lambda: state()["clock"].get("scale") == 2.0, WITHIN, "time scaled by 2")
    fill(driver, "#time-scale", "1")
    click(driver, 'button[data-op="time"][data-action="scale"]')
    click(driver, 'button[data-op="time"][data-action="resume"]')
    within(lambda: state()["clock"]["paused"] is False, WITHIN, "time running again")
    within(lambda: state()["clock"].get("scale") == 1.0, WITHIN, "time at its own pace")
    with dashboard.board("xy") as conn:
        conn.send(b"AY LP40\r")  # something a reset forgets
        within(lambda: state()["axes"]["Y"]["position"] == 40, 5.0, "Y's counter at 40")
    click(driver, 'button[data-op="reset"]')
    within(lambda: state()["axes"]["Y"]["position"] == 0, WITHIN, "the board reset")
    assert "not connected" not in driver.find_element(By.CSS_SELECTOR, "#error").text


def test_a_read_only_dashboard_has_no_buttons_and_refuses_operations(
    driver: WebDriver, daemons: Omsd
) -> None:
    served = start(daemons, daemons.directory, control=False)
    open_page(driver, served.url)
    assert driver.find_element(By.CSS_SELECTOR, "#mode").text == "read-only"
    assert driver.find_elements(By.CSS_SELECTOR, "#axes tr[data-axis]")
    assert not displayed(driver.find_elements(By.CSS_SELECTOR, "button[data-op]"))

    reply = driver.execute_async_script(
        """
        const done = arguments[arguments.length - 1];
        const url = new URL("/ws", location.href);
        url.protocol = "ws:";
        const socket = new WebSocket(url.href);
        socket.onmessage = (event) => {
          for (const line of event.data.split("\\n").filter((l) => l.trim())) {
            const message = JSON.parse(line);
            if (message.kind === "hello") {
              socket.send(JSON.stringify({id: 7, op: "limit", board: "xy", axis: "X",
                                          direction: 1, active: true}));
            } else if (message.id === 7) {
              socket.close();
              done(message);
            }
          }
        };
        """
    )
    assert reply["ok"] is False
    assert "not allowed" in reply["error"]
    with served.board("xy") as conn:
        assert axis_status(conn)[2] == "N"


# -- the README's two ways -------------------------------------------------------------------------


def served_dashboard(daemon: Daemon) -> str:
    found: list[str] = []

    def announced() -> bool:
        found[:] = re.findall(r"web dashboard (http://127\.0\.0\.1:\d+/)", daemon.stderr)
        return bool(found)

    assert wait_for(announced), f"no dashboard address in {daemon.stderr!r}"
    return found[0]


def listed(driver: WebDriver) -> dict[str, str]:
    """Each board the page lists, with its model."""
    names = [
        e.get_attribute("data-board") or ""
        for e in driver.find_elements(By.CSS_SELECTOR, "#boards [data-board]")
    ]
    return {name: board_field(driver, name, "model") for name in names}


def test_the_default_board_as_the_readme_serves_it(driver: WebDriver, daemons: Omsd) -> None:
    """``omsd --web 127.0.0.1:8048``: the built-in default board, read-only (on free ports
    here, with no pty)."""
    daemon = daemons("--web", "127.0.0.1:0", "--tcp", "127.0.0.1:0", expect=1)
    try:
        url = served_dashboard(daemon)
        assert wait_for(lambda: "(read-only)" in daemon.stderr), daemon.stderr
        open_page(driver, url)
        assert listed(driver) == {"board1": "PC48-4E"}
        assert not displayed(driver.find_elements(By.CSS_SELECTOR, "button[data-op]"))
        conn = daemon.connect("board1")
        try:
            conn.send(b"AX MR2000 GO\r")
            within(lambda: cell(driver, "X", "position") == "2000", 5.0, "X at 2000 on the page")
        finally:
            conn.close()
    finally:
        driver.get("about:blank")  # before the daemon goes: no reconnecting page left
        assert daemon.stop() == 0


def test_the_example_configuration_as_the_readme_serves_it(
    driver: WebDriver, daemons: Omsd, tmp_path: Path
) -> None:
    """``omsd --config config/omsd.toml --web 8048 --web-control``: its four boards, with the
    buttons (a copy of config/ with its TCP ports made free ones, so that nothing else that
    runs is in the way)."""
    copy = tmp_path / "config"
    shutil.copytree(ROOT / "config", copy)
    text = (copy / "omsd.toml").read_text()
    text = re.sub(r"\b700\d\b", "0", text)
    (copy / "omsd.toml").write_text(text)
    daemon = daemons(
        "--config", str(copy / "omsd.toml"), "--web", "127.0.0.1:0", "--web-control", expect=8
    )
    try:
        open_page(driver, served_dashboard(daemon))
        assert listed(driver) == {
            "xy": "PC48-4E",
            "slits": "PC48-8",
            "crate1": "VS4-040",
            "servo4": "PCIX-400",
        }
        select_board(driver, "crate1")
        rows = driver.find_elements(By.CSS_SELECTOR, "#axes tr[data-axis]")
        assert [r.get_attribute("data-axis") for r in rows] == ["X", "Y", "Z", "T"]
        assert displayed(driver.find_elements(By.CSS_SELECTOR, 'button[data-op="limit"]'))
    finally:
        driver.get("about:blank")
        assert daemon.stop() == 0
