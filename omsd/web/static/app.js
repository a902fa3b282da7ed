/*
 * omsd web dashboard (issue 18): the page's whole behaviour, plain ES2020, no build step.
 *
 * It opens /ws (passing the page's ?token= on), reads the hello, subscribes to every board with
 * the selected board's traffic, keeps each board's state up to date exactly as
 * omsd.control.protocol.merge() does, and draws: the board list, the selected board's axis
 * table, one uPlot chart per axis (the last minute of position, carriage and velocity, with the
 * switches drawn on it), the traffic tail (framing marks as omsd.telemetry.lines.visible() makes
 * them) and the events. With hello.control true it shows buttons for what `omsd ctl` does.
 *
 * Every buffer is bounded: plot points to the last WINDOW seconds, traffic lines to MAX_TRAFFIC,
 * events to MAX_EVENTS. window.omsdDashboard exposes counters for the browser test.
 */
"use strict";

(() => {
  const WINDOW = 60; // seconds shown by the plots
  const RATE = 12; // state messages a second of the selected board (>= 10 while it moves)
  const OVERVIEW_RATE = 2; // of the other boards (their line in the list: what moves, clients)
  const MAX_TRAFFIC = 500; // traffic lines kept in the page
  const MAX_EVENTS = 100; // events kept in the page
  const PLOT_HEIGHT = 170;
  const FIELDS = [
    "position",
    "encoder",
    "velocity",
    "motion",
    "done",
    "limit_negative",
    "limit_positive",
    "home",
    "queue_free",
  ];
  const COLOURS = {
    position: "#5cc8ff",
    physical: "#9be27a",
    velocity: "#ffb454",
    limit: "#ff6b6b",
    home: "#c792ea",
    axis: "#a7b0bd",
    grid: "rgba(167, 176, 189, 0.12)",
  };

  // -- the framing marks: omsd.telemetry.lines.visible(), ported byte for byte ---------------

  const NAMED = { 0x0a: "<LF>", 0x0d: "<CR>" };

  function shownByte(byte) {
    if (byte >= 0x20 && byte < 0x7f) return String.fromCharCode(byte);
    if (byte in NAMED) return NAMED[byte];
    if (byte < 0x20) return "^" + String.fromCharCode(byte + 0x40);
    return "<" + byte.toString(16).toUpperCase().padStart(2, "0") + ">";
  }

  /** How each byte is shown, by its value. */
  const SHOWN = Array.from({ length: 256 }, (_, byte) => shownByte(byte));

  /** Show latin-1 text (one character per byte) so a person can read it, whatever it is. */
  function visible(data) {
    let out = "";
    for (let i = 0; i < data.length; i++) out += SHOWN[data.charCodeAt(i) & 0xff];
    return out;
  }

  /** Runs of printable text [text, false] and shown control bytes [mark, true]
   *  (omsd.telemetry.lines.pieces()): the marks are highlighted, as the rich view does. */
  function pieces(data) {
    const out = [];
    let start = 0;
    for (let i = 0; i < data.length; i++) {
      const byte = data.charCodeAt(i) & 0xff;
      if (byte >= 0x20 && byte < 0x7f) continue;
      if (start < i) out.push([data.slice(start, i), false]);
      out.push([SHOWN[byte], true]);
      start = i + 1;
    }
    if (start < data.length) out.push([data.slice(start), false]);
    return out;
  }

  // -- small helpers ----------------------------------------------------------------------------

  const $ = (selector) => document.querySelector(selector);

  /** An element with attributes (dataset via "data-*", class via "class") and children. */
  function el(tag, attrs = {}, ...children) {
    const node = document.createElement(tag);
    for (const [key, value] of Object.entries(attrs)) {
      if (value === undefined || value === null || value === false) continue;
      if (key === "class") node.className = value;
      else if (key === "text") node.textContent = value;
      else node.setAttribute(key, value === true ? "" : String(value));
    }
    for (const child of children) {
      if (child !== null && child !== undefined) node.append(child);
    }
    return node;
  }

  function setText(node, text) {
    if (node.textContent !== text) node.textContent = text;
  }

  /** Local time of day to the millisecond (truncated), as the plain view shows it. */
  function clockText(t) {
    const d = new Date(Math.floor(t * 1000));
    const two = (n) => String(n).padStart(2, "0");
    const ms = String(d.getMilliseconds()).padStart(3, "0");
    return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.${ms}`;
  }

  function bytes(n) {
    if (n < 10000) return `${n} B`;
    if (n < 10000000) return `${(n / 1024).toFixed(1)} KiB`;
    return `${(n / 1048576).toFixed(1)} MiB`;
  }

  function cell(field, value) {
    if (value === null || value === undefined) return "–";
    if (typeof value === "boolean") return value ? "yes" : "no";
    if (field === "velocity") return String(Math.round(value));
    if (typeof value === "number") return Number.isInteger(value) ? String(value) : value.toFixed(1);
    return String(value);
  }

  // -- the model ------------------------------------------------------------------------------

  const app = {
    socket: null,
    nextId: 1,
    pending: new Map(), // request id -> callback(reply)
    control: false,
    backoff: 500, // ms before the next reconnection
    // name -> {name, model, link, endpoints, switches, state, traffic: bytes {in, out} seen}
    boards: new Map(),
    order: [],
    selected: null,
    subscription: null, // {id, board}: the subscription in force (its traffic's board)
    switching: false, // an unsubscribe / subscribe is on its way
    skew: 0, // server wall clock minus ours, seconds
    updates: 0,
    series: new Map(), // "board/axis" -> {t, position, physical, velocity}
    plots: new Map(), // axis letter -> uPlot, for the selected board
    plotsDirty: false,
    frame: 0,
    trafficPaused: false,
    skipped: 0,
    filter: "",
  };

  const now = () => Date.now() / 1000 + app.skew;

  /** Apply one board's changes from a state message (omsd.control.protocol.merge()): fields
   *  replaced whole, axes merged axis by axis, field by field. */
  function merge(state, changes) {
    for (const [key, value] of Object.entries(changes)) {
      if (key === "axes") {
        state.axes = state.axes || {};
        for (const [letter, fields] of Object.entries(value)) {
          state.axes[letter] = Object.assign(state.axes[letter] || {}, fields);
        }
      } else {
        state[key] = value;
      }
    }
    return state;
  }

  // -- plot buffers ---------------------------------------------------------------------------

  function seriesOf(board, axis) {
    const key = `${board}/${axis}`;
    let series = app.series.get(key);
    if (!series) {
      series = { t: [], position: [], physical: [], velocity: [] };
      app.series.set(key, series);
    }
    return series;
  }

  /** A point per axis of `board` at server time `t`, from its merged state. After a quiet spell
   *  the previous values are held up to just before `t`, so a move starts where it started. */
  function addPoints(board, t) {
    const entry = app.boards.get(board);
    if (!entry || !entry.state.axes) return;
    for (const [letter, axis] of Object.entries(entry.state.axes)) {
      const s = seriesOf(board, letter);
      const n = s.t.length;
      if (n && t <= s.t[n - 1]) continue; // out of order (a resubscription's snapshot)
      if (n && t - s.t[n - 1] > 2 / RATE) {
        s.t.push(t - 1 / RATE);
        s.position.push(s.position[n - 1]);
        s.physical.push(s.physical[n - 1]);
        s.velocity.push(s.velocity[n - 1]);
      }
      s.t.push(t);
      s.position.push(axis.position);
      s.physical.push(axis.physical);
      s.velocity.push(axis.velocity);
    }
  }

  /** Drop the points older than the window (keeping one, so the line enters from the edge). */
  function trim() {
    const cutoff = now() - WINDOW;
    for (const s of app.series.values()) {
      let i = 0;
      while (i + 1 < s.t.length && s.t[i + 1] < cutoff) i++;
      if (i > 0) {
        for (const key of ["t", "position", "physical", "velocity"]) s[key].splice(0, i);
      }
    }
  }

  // -- the socket -----------------------------------------------------------------------------

  function connect() {
    const url = new URL("/ws", location.href);
    url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
    const token = new URLSearchParams(location.search).get("token");
    if (token !== null) url.searchParams.set("token", token);
    setStatus("connecting", "connecting");
    const socket = new WebSocket(url.href);
    app.socket = socket;
    socket.addEventListener("message", (event) => {
      if (typeof event.data !== "string") return;
      for (const line of event.data.split("\n")) {
        if (!line.trim()) continue;
        let message;
        try {
          message = JSON.parse(line);
        } catch (err) {
          showError(`bad message from the daemon: ${err.message}`);
          continue;
        }
        handle(message);
      }
    });
    socket.addEventListener("close", () => {
      if (app.socket !== socket) return;
      app.socket = null;
      app.subscription = null;
      app.switching = false;
      for (const callback of app.pending.values()) callback({ ok: false, error: "disconnected" });
      app.pending.clear();
      setStatus("disconnected", "down");
      setTimeout(connect, app.backoff);
      app.backoff = Math.min(app.backoff * 2, 10000);
    });
  }

  /** Send one request; `callback(reply)` gets its reply. Returns the request's id. */
  function request(body, callback) {
    const socket = app.socket;
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      showError("not connected");
      return null;
    }
    const id = app.nextId++;
    app.pending.set(id, callback || (() => {}));
    socket.send(JSON.stringify({ id, ...body }));
    return id;
  }

  function handle(message) {
    if (message.kind === "hello") {
      hello(message);
    } else if ("ok" in message && app.pending.has(message.id)) {
      const callback = app.pending.get(message.id);
      app.pending.delete(message.id);
      if (!message.ok) showError(message.error || "failed");
      callback(message);
    } else if ("ok" in message) {
      if (!message.ok) showError(message.error || "failed"); // a reply to no request (id null)
    } else if (!app.subscription || message.id !== app.subscription.id) {
      // what an ended subscription still had on the way: not ours any more
    } else if (message.kind === "state") {
      applyState(message);
    } else if (message.kind === "event") {
      addEvent(message.event);
    } else if (message.kind === "traffic") {
      addTraffic(message.traffic);
    }
  }

  function hello(message) {
    app.backoff = 500;
    app.control = Boolean(message.control);
    setText($("#version"), `v${message.version}`);
    setText($("#mode"), app.control ? "control" : "read-only");
    $("#controls").hidden = !app.control;
    for (const node of document.querySelectorAll(".control-only")) node.hidden = !app.control;
    app.order = message.boards.slice();
    if (!app.order.includes(app.selected)) app.selected = app.order[0] || null;
    subscribe();
  }

  /** Subscribe to every board, the selected one at RATE with its traffic, the others at
   *  OVERVIEW_RATE (what the daemon spends on the page is mostly its looks at the boards). */
  function subscribe() {
    const board = app.selected;
    app.switching = true;
    const body = { op: "subscribe", rate: OVERVIEW_RATE, traffic: false };
    if (board !== null) {
      body.traffic = board;
      body.rates = { [board]: RATE };
    }
    const id = request(body, (reply) => {
      app.switching = false;
      if (!reply.ok) return;
      app.subscription = { id, board };
      applySnapshot(reply.result);
      setStatus("live", "live");
      if (app.selected !== board) resubscribe(); // the choice changed while it was on its way
    });
  }

  /** The traffic's board changes: unsubscribe, then subscribe again. */
  function resubscribe() {
    if (app.switching || !app.subscription) return;
    app.switching = true;
    request({ op: "unsubscribe" }, () => {
      app.subscription = null;
      if (app.socket) subscribe();
    });
  }

  // -- state ----------------------------------------------------------------------------------

  function applySnapshot(snapshot) {
    app.skew = snapshot.t - Date.now() / 1000;
    const names = [];
    for (const board of snapshot.boards) {
      // the counts of a subscription start at 0: the page adds up those of the ones before
      const previous = app.boards.get(board.name);
      const seen = previous ? previous.traffic : { in: 0, out: 0 };
      app.boards.set(board.name, {
        name: board.name,
        model: board.model,
        link: board.link,
        endpoints: board.endpoints,
        switches: board.switches || {},
        state: board.state,
        traffic: { ...seen },
        trafficBefore: { ...seen },
      });
      names.push(board.name);
      addPoints(board.name, snapshot.t);
    }
    for (const name of [...app.boards.keys()]) {
      if (!names.includes(name)) app.boards.delete(name); // a daemon restarted with others
    }
    for (const key of [...app.series.keys()]) {
      if (!app.boards.has(key.slice(0, key.lastIndexOf("/")))) app.series.delete(key);
    }
    app.order = names;
    if (!names.includes(app.selected)) app.selected = names[0] || null;
    renderBoardList();
    renderSelected();
  }

  function applyState(message) {
    app.updates++;
    app.skew = message.t - Date.now() / 1000;
    for (const [name, changes] of Object.entries(message.boards || {})) {
      const entry = app.boards.get(name);
      if (!entry) continue;
      merge(entry.state, changes);
      addPoints(name, message.t);
      updateBoardItem(name);
      if (name === app.selected) {
        updateTable();
        updateBoardHead();
        app.plotsDirty = true;
      }
    }
    for (const [name, counts] of Object.entries(message.traffic || {})) {
      const entry = app.boards.get(name);
      if (entry) {
        entry.traffic = {
          in: entry.trafficBefore.in + counts.in,
          out: entry.trafficBefore.out + counts.out,
        };
        updateBoardItem(name);
      }
    }
    if (message.dropped) {
      const parts = Object.entries(message.dropped).filter(([, n]) => n > 0);
      setText($("#dropped"), `dropped: ${parts.map(([kind, n]) => `${n} ${kind}`).join(", ")}`);
    }
    schedulePlots();
  }

  // -- the page: status and errors ------------------------------------------------------------

  function setStatus(text, kind) {
    const node = $("#status");
    setText(node, text);
    node.className = `status ${kind}`;
  }

  function showError(text) {
    const node = $("#error");
    setText(node, `${clockText(Date.now() / 1000)} ${text}`);
    node.title = "click to clear";
  }

  // -- the board list -------------------------------------------------------------------------

  function renderBoardList() {
    const list = $("#boards");
    list.replaceChildren();
    for (const name of app.order) {
      const entry = app.boards.get(name);
      const endpoints = entry.endpoints.map((e) => `${e.kind} ${e.address}`).join("\n") || "none";
      const item = el(
        "li",
        { "data-board": name, class: name === app.selected ? "selected" : "", tabindex: 0 },
        el("div", { class: "board-name" },
          el("span", { class: "name", text: name }),
          el("span", { class: "model", "data-field": "model", text: entry.model }),
          el("span", { class: "link", "data-field": "link", text: entry.link })),
        el("div", { class: "endpoints", "data-field": "endpoints", text: endpoints }),
        el("div", { class: "clients", "data-field": "clients" }),
        el("div", { class: "counts", "data-field": "traffic" }),
      );
      list.append(item);
      updateBoardItem(name);
    }
  }

  function updateBoardItem(name) {
    const item = document.querySelector(`#boards li[data-board="${CSS.escape(name)}"]`);
    const entry = app.boards.get(name);
    if (!item || !entry) return;
    const clients = entry.state.clients || [];
    setText(item.querySelector('[data-field="clients"]'),
      clients.length ? `clients: ${clients.join(", ")}` : "clients: none");
    const moving = Object.entries(entry.state.axes || {})
      .filter(([, a]) => a.moving).map(([letter]) => letter);
    const faults = entry.state.faults || {};
    const clock = entry.state.clock || {};
    const notes = [`in ${bytes(entry.traffic.in)}`, `out ${bytes(entry.traffic.out)}`];
    if (moving.length) notes.push(`moving ${moving.join("")}`);
    if (faults.cable === false) notes.push("cable cut");
    if (clock.paused) notes.push("paused");
    setText(item.querySelector('[data-field="traffic"]'), notes.join(" · "));
    item.classList.toggle("moving", moving.length > 0);
    item.classList.toggle("faulty", faults.cable === false);
  }

  function select(name) {
    if (!app.boards.has(name) || name === app.selected) return;
    app.selected = name;
    for (const item of document.querySelectorAll("#boards li")) {
      item.classList.toggle("selected", item.dataset.board === name);
    }
    renderSelected();
    resubscribe();
  }

  // -- the selected board: head, controls, axis table -----------------------------------------

  function renderSelected() {
    const entry = app.boards.get(app.selected);
    const body = $("#axes");
    body.replaceChildren();
    clearTraffic();
    setText($("#traffic-board"), entry ? `of ${entry.name}` : "");
    if (!entry) {
      setText($("#board-title"), "No board");
      buildPlots(null);
      return;
    }
    setText($("#board-title"), `${entry.name}`);
    for (const letter of Object.keys(entry.state.axes || {})) {
      const row = el("tr", { "data-axis": letter }, el("th", { text: letter }));
      for (const field of FIELDS) {
        const numeric = ["position", "encoder", "velocity", "queue_free"].includes(field);
        row.append(el("td", { "data-field": field, class: numeric ? "num" : "" }));
      }
      if (app.control) row.append(el("td", { class: "actions" }, ...axisButtons(letter)));
      body.append(row);
    }
    updateTable();
    updateBoardHead();
    buildPlots(entry);
  }

  function axisButtons(letter) {
    const button = (text, attrs, title) =>
      el("button", { type: "button", "data-axis": letter, title, ...attrs, text });
    return [
      button("lim −", { "data-op": "limit", "data-direction": "-1" },
        "close / open the negative limit switch"),
      button("lim +", { "data-op": "limit", "data-direction": "1" },
        "close / open the positive limit switch"),
      button("home", { "data-op": "home" }, "close / open the home switch"),
      button("stall", { "data-op": "stall" }, "stall the motor / let it run again"),
      button("slip", { "data-op": "slip" }, "slip the carriage by the steps set above"),
    ];
  }

  function updateBoardHead() {
    const entry = app.boards.get(app.selected);
    if (!entry) return;
    const state = entry.state;
    const clock = state.clock || {};
    const faults = state.faults || {};
    const parts = [entry.model, entry.link];
    if (typeof state.time === "number") {
      // the board's clock counts from the machine's boot (monotonic); since power-up reads better
      const origin = state.clock && typeof state.clock.origin === "number" ? state.clock.origin : 0;
      parts.push(`${(state.time - origin).toFixed(2)} s since power-up`);
    }
    parts.push(clock.paused ? "clock paused" : `time ×${clock.scale ?? 1}`);
    if (faults.cable === false) parts.push("CABLE CUT");
    if (state.link && state.link.held) parts.push(`held: ${state.link.held.text}`);
    setText($("#board-info"), parts.join(" · "));
    const cable = document.querySelector('button[data-op="cable"]');
    setText(cable, faults.cable === false ? "restore cable" : "cut cable");
    cable.classList.toggle("active", faults.cable === false);
    const pause = document.querySelector('button[data-op="time"][data-action="pause"]');
    pause.classList.toggle("active", Boolean(clock.paused));
  }

  function updateTable() {
    const entry = app.boards.get(app.selected);
    if (!entry) return;
    for (const row of $("#axes").rows) {
      const letter = row.dataset.axis;
      const axis = (entry.state.axes || {})[letter] || {};
      for (const td of row.querySelectorAll("td[data-field]")) {
        const field = td.dataset.field;
        const value = axis[field];
        setText(td, cell(field, value));
        td.classList.toggle("on", value === true);
      }
      row.classList.toggle("moving", Boolean(axis.moving));
      const world = entry.state.world || {};
      for (const button of row.querySelectorAll("button[data-op]")) {
        const op = button.dataset.op;
        let active = false;
        let forced = false;
        if (op === "limit") {
          const positive = button.dataset.direction === "1";
          active = Boolean(axis[positive ? "limit_positive" : "limit_negative"]);
          forced = forcedSwitch(world, letter, op, Number(button.dataset.direction)) !== null;
        } else if (op === "home") {
          active = Boolean(axis.home);
          forced = forcedSwitch(world, letter, op, 0) !== null;
        } else if (op === "stall") {
          active = (world.stalled || []).includes(letter);
        }
        button.classList.toggle("active", active);
        button.classList.toggle("forced", forced);
      }
    }
  }

  // -- control --------------------------------------------------------------------------------

  function numberOf(selector, fallback) {
    const value = Number($(selector).value);
    return Number.isFinite(value) ? value : fallback;
  }

  /** How the daemon says a switch is forced (the state's ``world``, whoever forced it: this
   *  page, another, omsd ctl): true or false, or null when it follows the carriage. */
  function forcedSwitch(world, letter, op, direction) {
    if (op === "home") {
      const home = (world.home || {})[letter];
      return home === undefined ? null : home;
    }
    const pair = (world.limits || {})[letter] || [null, null];
    return pair[direction > 0 ? 1 : 0];
  }

  /** A switch button: a forced switch goes back to following the carriage (active null);
   *  one that follows it is forced to the other state (closed if open, open if closed). */
  function toggleSwitch(forced, current, send) {
    const active = forced !== null ? null : !current;
    send(active, () => updateTable());
  }

  function act(button) {
    if (!app.control) return;
    const board = app.selected;
    const entry = app.boards.get(board);
    if (!entry) return;
    const { op, axis } = button.dataset;
    const state = (entry.state.axes || {})[axis] || {};
    const done = () => updateTable();
    switch (op) {
      case "limit": {
        const direction = Number(button.dataset.direction);
        const field = direction > 0 ? "limit_positive" : "limit_negative";
        const forced = forcedSwitch(entry.state.world || {}, axis, op, direction);
        toggleSwitch(forced, Boolean(state[field]), (active, cb) =>
          request({ op: "limit", board, axis, direction, active }, cb));
        break;
      }
      case "home":
        toggleSwitch(forcedSwitch(entry.state.world || {}, axis, op, 0), Boolean(state.home),
          (active, cb) => request({ op: "home", board, axis, active }, cb));
        break;
      case "stall": {
        const stalled = !((entry.state.world || {}).stalled || []).includes(axis);
        request({ op: "stall", board, axis, stalled }, done);
        break;
      }
      case "slip":
        request({ op: "slip", board, axis, steps: numberOf("#slip-steps", 100) });
        break;
      case "input": {
        const high = JSON.parse(button.dataset.high); // "true", "false" or "null"
        request({ op: "input", board, bit: Math.trunc(numberOf("#input-bit", 0)), high });
        break;
      }
      case "cable":
        request({ op: "fault", board, cable: (entry.state.faults || {}).cable === false });
        break;
      case "reset":
        request({ op: "reset", board });
        break;
      case "time": {
        const action = button.dataset.action;
        const body = { op: "time", board, action };
        if (action === "step") body.seconds = numberOf("#time-step", 0.1);
        if (action === "scale") body.scale = numberOf("#time-scale", 1);
        request(body);
        break;
      }
      default:
        break;
    }
  }

  // -- plots ----------------------------------------------------------------------------------

  function switchesOf(board, axis) {
    const entry = app.boards.get(board);
    return (entry && entry.switches[axis]) || {};
  }

  /** The position scale: the data and the switches in view, with a margin. */
  function positionRange(board, axis, min, max) {
    const values = [];
    if (min !== null && min !== undefined) values.push(min, max);
    const sw = switchesOf(board, axis);
    for (const v of [...(sw.limits || []), ...(sw.home || [])]) values.push(v);
    if (!values.length) return [-1, 1];
    let lo = Math.min(...values);
    let hi = Math.max(...values);
    if (hi - lo < 1) {
      lo -= 1;
      hi += 1;
    }
    const pad = (hi - lo) * 0.08;
    return [lo - pad, hi + pad];
  }

  /** The velocity scale: symmetric about 0, up to a round number (1, 2 or 5 times a power of
   *  ten) at or above the fastest speed in view, so it has ticks besides 0. */
  function velocityRange(min, max) {
    const m = Math.max(Math.abs(min || 0), Math.abs(max || 0), 1);
    const power = 10 ** Math.floor(Math.log10(m));
    const round = [1, 2, 5, 10].map((k) => k * power).find((v) => v >= m);
    return [-round * 1.1, round * 1.1];
  }

  /** uPlot draw hook: the limit switches as lines, the home window as a band, labelled. */
  function drawSwitches(board, axis, u) {
    const sw = switchesOf(board, axis);
    const { ctx } = u;
    const { left, top, width, height } = u.bbox;
    const ratio = window.devicePixelRatio || 1;
    const y = (v) => u.valToPos(v, "pos", true);
    ctx.save();
    ctx.beginPath();
    ctx.rect(left, top, width, height);
    ctx.clip();
    ctx.font = `${Math.round(11 * ratio)}px system-ui, sans-serif`;
    ctx.textBaseline = "bottom";
    if (sw.home) {
      const [low, high] = sw.home;
      const y1 = y(high);
      const y0 = y(low);
      ctx.fillStyle = "rgba(199, 146, 234, 0.18)";
      ctx.fillRect(left, y1, width, Math.max(y0 - y1, ratio));
      ctx.strokeStyle = COLOURS.home;
      ctx.lineWidth = ratio;
      ctx.setLineDash([2 * ratio, 3 * ratio]);
      for (const yy of [y0, y1]) {
        ctx.beginPath();
        ctx.moveTo(left, yy);
        ctx.lineTo(left + width, yy);
        ctx.stroke();
      }
      // labelled above the band, or below it when it is at the top of the chart
      const above = y1 - 16 * ratio > top;
      ctx.fillStyle = COLOURS.home;
      ctx.textBaseline = above ? "bottom" : "top";
      ctx.fillText(`home ${low}…${high}`, left + width * 0.3, above ? y1 - 2 * ratio : y0 + 3 * ratio);
    }
    if (sw.limits) {
      ctx.strokeStyle = COLOURS.limit;
      ctx.fillStyle = COLOURS.limit;
      ctx.lineWidth = 1.5 * ratio;
      ctx.setLineDash([6 * ratio, 4 * ratio]);
      sw.limits.forEach((value, i) => {
        const yy = y(value);
        ctx.beginPath();
        ctx.moveTo(left, yy);
        ctx.lineTo(left + width, yy);
        ctx.stroke();
        // labelled on the side that faces the travel, so the margin never clips them
        const label = `${i === 0 ? "− limit" : "+ limit"} ${value}`;
        ctx.textBaseline = i === 0 ? "bottom" : "top";
        ctx.fillText(label, left + 6 * ratio, i === 0 ? yy - 3 * ratio : yy + 3 * ratio);
      });
    }
    ctx.restore();
  }

  function plotWidth() {
    const plots = $("#plots");
    const columns = getComputedStyle(plots).gridTemplateColumns.split(" ").length || 1;
    const gap = parseFloat(getComputedStyle(plots).columnGap) || 0;
    return Math.max(240, Math.floor((plots.clientWidth - gap * (columns - 1)) / columns));
  }

  function buildPlots(entry) {
    for (const plot of app.plots.values()) plot.destroy();
    app.plots.clear();
    const container = $("#plots");
    container.replaceChildren();
    if (!entry || typeof uPlot === "undefined") return;
    const board = entry.name;
    const axisStyle = {
      stroke: COLOURS.axis,
      grid: { stroke: COLOURS.grid, width: 1 },
      ticks: { stroke: COLOURS.grid, width: 1 },
      font: "11px system-ui, sans-serif",
    };
    for (const letter of Object.keys(entry.state.axes || {})) {
      const key = (name, text) => el("span", { class: `key key-${name}`, text });
      const box = el("div", { class: "plot", id: `plot-${letter}` },
        el("div", { class: "plot-title" },
          el("span", { class: "plot-axis", text: `${board} ${letter}` }),
          key("position", "position"), key("physical", "carriage"),
          key("velocity", "velocity →"), key("limit", "limits"), key("home", "home")));
      container.append(box);
      const options = {
        width: plotWidth(),
        height: PLOT_HEIGHT,
        cursor: { drag: { x: false, y: false }, points: { show: false } },
        legend: { show: false },
        scales: {
          x: { time: true, range: () => [now() - WINDOW, now()] },
          pos: { range: (u, min, max) => positionRange(board, letter, min, max) },
          vel: { range: (u, min, max) => velocityRange(min, max) },
        },
        axes: [
          { ...axisStyle, values: (u, splits) => splits.map((t) => clockText(t).slice(0, 8)) },
          { ...axisStyle, scale: "pos", size: 64 },
          { ...axisStyle, scale: "vel", side: 1, size: 64, grid: { show: false } },
        ],
        series: [
          {},
          { label: "position", scale: "pos", stroke: COLOURS.position, width: 1.5 },
          { label: "carriage", scale: "pos", stroke: COLOURS.physical, width: 1, dash: [5, 3] },
          { label: "velocity", scale: "vel", stroke: COLOURS.velocity, width: 1 },
        ],
        hooks: { draw: [(u) => drawSwitches(board, letter, u)] },
      };
      app.plots.set(letter, new uPlot(options, plotData(board, letter), box));
    }
  }

  /** A chart's data: the buffered points and, held to now, the last values (the server sends
   *  nothing while nothing changes, and the line must reach the right edge). */
  function plotData(board, axis) {
    const s = seriesOf(board, axis);
    const t = s.t.slice();
    const position = s.position.slice();
    const physical = s.physical.slice();
    const velocity = s.velocity.slice();
    const n = t.length;
    const end = now();
    if (n && t[n - 1] < end) {
      t.push(end);
      position.push(position[n - 1]);
      physical.push(physical[n - 1]);
      velocity.push(velocity[n - 1]);
    }
    return [t, position, physical, velocity];
  }

  function drawPlots() {
    app.frame = 0;
    app.plotsDirty = false;
    for (const [letter, plot] of app.plots) plot.setData(plotData(app.selected, letter));
  }

  function schedulePlots() {
    if (app.plotsDirty && !app.frame) app.frame = requestAnimationFrame(drawPlots);
  }

  function resizePlots() {
    if (!app.plots.size) return;
    const width = plotWidth();
    for (const plot of app.plots.values()) {
      if (plot.width !== width) plot.setSize({ width, height: PLOT_HEIGHT });
    }
  }

  // -- traffic --------------------------------------------------------------------------------

  function clearTraffic() {
    $("#traffic").replaceChildren();
    app.skipped = 0;
    showSkipped();
  }

  function showSkipped() {
    setText($("#traffic-skipped"), app.trafficPaused ? `paused: ${app.skipped} skipped` : "");
  }

  function appendLine(line) {
    const log = $("#traffic");
    const atBottom = log.scrollHeight - log.scrollTop - log.clientHeight < 24;
    line.hidden = !matches(line);
    log.append(line);
    while (log.childElementCount > MAX_TRAFFIC) log.firstElementChild.remove();
    if (atBottom) log.scrollTop = log.scrollHeight;
  }

  function addTraffic(record) {
    if (record.board !== app.selected) return; // the board before a switch, still on its way
    if (app.trafficPaused) {
      app.skipped++;
      showSkipped();
      return;
    }
    const incoming = record.dir === "in";
    const data = el("span", { class: "data" });
    for (const [text, mark] of pieces(record.data)) {
      data.append(mark ? el("span", { class: "mark", text }) : document.createTextNode(text));
    }
    const line = el("div", { class: `traffic-line ${incoming ? "in" : "out"}` },
      el("span", { class: "time", text: clockText(record.t) }),
      " ",
      el("span", { class: "endpoint", text: record.endpoint }),
      " ",
      el("span", { class: "arrow", text: incoming ? "<-" : "->" }),
      " ",
      data);
    line.searchText = line.textContent.toLowerCase();
    appendLine(line);
  }

  function matches(line) {
    return !app.filter || (line.searchText || line.textContent.toLowerCase()).includes(app.filter);
  }

  function applyFilter() {
    app.filter = $("#traffic-filter").value.trim().toLowerCase();
    for (const line of $("#traffic").children) line.hidden = !matches(line);
  }

  function togglePause() {
    app.trafficPaused = !app.trafficPaused;
    const button = $("#traffic-pause");
    setText(button, app.trafficPaused ? "resume" : "pause");
    button.classList.toggle("active", app.trafficPaused);
    if (!app.trafficPaused && app.skipped) {
      const gap = el("div", { class: "traffic-gap",
        text: `… ${app.skipped} chunk${app.skipped === 1 ? "" : "s"} skipped while paused` });
      gap.searchText = "";
      appendLine(gap);
    }
    app.skipped = 0;
    showSkipped();
  }

  // -- events ---------------------------------------------------------------------------------

  function addEvent(event) {
    const list = $("#events");
    const item = el("li", { class: `event kind-${event.kind}`, "data-board": event.board },
      el("span", { class: "time", text: clockText(event.t) }),
      " ",
      el("span", { class: "board", text: event.board }),
      " ",
      el("span", { class: "text", text: event.text }));
    list.prepend(item);
    while (list.childElementCount > MAX_EVENTS) list.lastElementChild.remove();
  }

  // -- wiring ---------------------------------------------------------------------------------

  function tick() {
    trim();
    if (app.plots.size) {
      app.plotsDirty = true;
      schedulePlots();
    }
  }

  function start() {
    document.addEventListener("click", (event) => {
      const target = event.target instanceof Element ? event.target : null;
      if (!target) return;
      const button = target.closest("button[data-op]");
      if (button) {
        act(button);
        return;
      }
      const item = target.closest("#boards li[data-board]");
      if (item) select(item.dataset.board);
    });
    $("#boards").addEventListener("keydown", (event) => {
      const item = event.target.closest && event.target.closest("li[data-board]");
      if (item && (event.key === "Enter" || event.key === " ")) {
        event.preventDefault();
        select(item.dataset.board);
      }
    });
    $("#traffic-pause").addEventListener("click", togglePause);
    $("#traffic-filter").addEventListener("input", applyFilter);
    $("#error").addEventListener("click", () => {
      setText($("#error"), "");
      $("#error").title = "";
    });
    if (typeof ResizeObserver !== "undefined") {
      new ResizeObserver(resizePlots).observe($("#plots"));
    }
    setInterval(tick, 1000);
    connect();
  }

  window.omsdDashboard = {
    get updates() {
      return app.updates;
    },
    get boards() {
      return Object.fromEntries([...app.boards].map(([name, entry]) => [name, entry.state]));
    },
    get selected() {
      return app.selected;
    },
    /** The board whose subscription is live (its snapshot shown), null while switching. */
    get live() {
      return app.subscription && !app.switching ? app.subscription.board : null;
    },
    points(board, axis) {
      const s = app.series.get(`${board}/${axis}`);
      return s ? s.t.length : 0;
    },
    lastPoint(board, axis) {
      const s = app.series.get(`${board}/${axis}`);
      if (!s || !s.t.length) return null;
      const i = s.t.length - 1;
      return { t: s.t[i], position: s.position[i], physical: s.physical[i], velocity: s.velocity[i] };
    },
    visible,
  };

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
