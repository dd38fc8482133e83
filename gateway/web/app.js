// asi-lift's live view: draws the snapshots the rig thread publishes over /ws and sends the
// page's commands back (README, "Live view in the browser"). No libraries, no build step.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);

let socket = null;
let nextId = 1;
let shaftKey = "";
// The cabin's height as drawn, mm.
const CABIN_MM = 240;
let shaftParts = null;
let history = [];
let last = null;
const pending = new Map();

// ----- connection ------------------------------------------------------------------------

function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  socket = new WebSocket(`${proto}//${location.host}/ws`);
  socket.onopen = () => setConn(true, "live");
  socket.onclose = () => {
    setConn(false, last && last.run.ended ? "run ended" : "disconnected – retrying");
    if (!(last && last.run.ended)) setTimeout(connect, 1000);
  };
  socket.onmessage = (ev) => {
    let msg;
    try {
      msg = JSON.parse(ev.data);
    } catch (e) {
      return;
    }
    if (msg.type === "view") render(msg);
    else if (msg.type === "history") history = msg.points || [];
    else if (msg.type === "reply") answered(msg);
  };
}

function setConn(ok, text) {
  const c = $("conn");
  c.textContent = text;
  c.classList.toggle("off", !ok);
}

function send(command, what) {
  if (!socket || socket.readyState !== WebSocket.OPEN) {
    say(false, `${what}: not connected`);
    return;
  }
  const id = nextId++;
  pending.set(id, what);
  socket.send(JSON.stringify({ id, command }));
}

function answered(msg) {
  const what = pending.get(msg.id) || "message";
  pending.delete(msg.id);
  if (msg.ok && msg.note) say("note", `${what}: ${msg.note}`);
  else if (msg.ok) say(true, `${what}: done`);
  else say(false, `${what}: ${msg.error}`);
  // A refused speed: the select shows the run's speed again.
  if (!msg.ok && what.startsWith("speed")) showSpeed(shownSpeed, true);
}

let sayTimer = null;
// `ok`: true (done), false (an error) or "note" (done, with something to read).
function say(ok, text) {
  const m = $("message");
  m.textContent = text;
  const kind = ok === "note" ? "note" : ok ? "ok" : "error";
  m.className = "message " + kind;
  clearTimeout(sayTimer);
  sayTimer = setTimeout(() => { m.className = "message"; }, kind === "ok" ? 2500 : 10000);
}

// ----- controls --------------------------------------------------------------------------

function press(key) {
  send({ press: key }, `press ${key}`);
}

// The run's controls. The page sends the state it wants ({"pause": true}), not a toggle,
// so that two clicks or two browsers never undo each other by surprise.
let paused = false;
let shownSpeed = null;
let restartArmed = null;

// Shows the run's speed `s` ("1", "0.5", "max") in the select, adding it if the command
// line gave one the list lacks.
function showSpeed(s, force) {
  if (s === null || (s === shownSpeed && !force)) return;
  shownSpeed = s;
  const sel = $("speed-select");
  if (![...sel.options].some((o) => o.value === s)) {
    const o = document.createElement("option");
    o.value = s;
    o.textContent = `${s}×`;
    sel.append(o);
  }
  sel.value = s;
}

function disarmRestart() {
  clearTimeout(restartArmed);
  restartArmed = null;
  const b = $("btn-restart");
  b.classList.remove("armed");
  b.textContent = "⟲ restart";
}

function wireControls() {
  $("btn-pause").onclick = () =>
    send({ pause: !paused }, paused ? "resume" : "pause");
  $("speed-select").onchange = (ev) => {
    const v = ev.target.value;
    send({ speed: v === "max" ? "max" : Number(v) }, `speed ${v}`);
  };
  // Restart discards the run so far: the first click arms it, a second within 4 s does it.
  $("btn-restart").onclick = () => {
    if (restartArmed === null) {
      const b = $("btn-restart");
      b.classList.add("armed");
      b.textContent = "⟲ click again to restart";
      restartArmed = setTimeout(disarmRestart, 4000);
      return;
    }
    disarmRestart();
    send({ restart: true }, "restart");
  };
  document.body.addEventListener("click", (ev) => {
    const b = ev.target.closest("button");
    if (!b) return;
    if (b.dataset.press) press(b.dataset.press);
    else if (b.dataset.cmd) send(JSON.parse(b.dataset.cmd), b.textContent.trim());
  });
  $("btn-noise").onclick = () =>
    send({ line_noise: Number($("noise-rate").value) }, `line noise ${$("noise-rate").value}`);
  $("btn-power-fail").onclick = () =>
    send({ fault: { kind: "power-fail", duration: $("power-fail-for").value } }, "AS-i power fail");
  $("btn-link-drop").onclick = () =>
    send({ fault: { kind: "safe-link-drop", duration: $("link-drop-for").value } }, "safe-link drop");
  $("btn-vane").onclick = () =>
    send({ fault: { kind: $("vane-fault").value, sensor: $("vane-sensor").value } },
      `${$("vane-sensor").value} vane sensor ${$("vane-fault").value}`);
  $("btn-crank").onclick = () =>
    send({ crank_mm: Number($("crank-mm").value) }, `hand crank ${$("crank-mm").value} mm`);
}

function button(id, label, key, cls) {
  const b = document.createElement("button");
  b.id = id;
  b.textContent = label;
  b.dataset.press = key;
  if (cls) b.className = cls;
  return b;
}

// ----- the shaft -------------------------------------------------------------------------

function el(name, attrs, parent) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

// Builds the shaft once per geometry; later snapshots only move the cabin and light lamps.
function buildShaft(s) {
  const svg = $("shaft");
  svg.textContent = "";
  // The position is the cabin's floor; its roof is CABIN_MM above, so the top buffer, which
  // the cabin's floor meets at the top end, is drawn where the roof meets it.
  const top = s.end_mm[1] + CABIN_MM + 60;
  const bottom = s.end_mm[0] - 60;
  const y = (mm) => top - mm;
  svg.setAttribute("viewBox", `0 0 320 ${top - bottom}`);
  const W0 = 70, W1 = 250;
  el("rect", { x: W0, y: 0, width: W1 - W0, height: top - bottom, class: "shaft-bg" }, svg);
  // Mechanical ends (buffers).
  el("rect", { x: W0, y: y(s.end_mm[1] + CABIN_MM) - 30, width: W1 - W0, height: 30, class: "end" }, svg);
  el("rect", { x: W0, y: y(s.end_mm[0]), width: W1 - W0, height: 30, class: "end" }, svg);
  // Floors.
  s.levels_mm.forEach((mm, i) => {
    el("line", { x1: 20, x2: W1 + 40, y1: y(mm), y2: y(mm), class: "floor" }, svg);
    const t = el("text", { x: 8, y: y(mm) - 8, class: "floor-label" }, svg);
    t.textContent = `${i + 1}`;
  });
  // Vanes: the left sensor's track at x 95, the right one's at x 225.
  for (const v of s.vanes) {
    el("rect", { x: 88, y: y(v.left[1]), width: 14, height: Math.max(2, v.left[1] - v.left[0]), class: "vane" }, svg);
    el("rect", { x: 218, y: y(v.right[1]), width: 14, height: Math.max(2, v.right[1] - v.right[0]), class: "vane" }, svg);
  }
  // Overtravel sensors.
  const ot = s.trip_mm.map((mm) =>
    el("polygon", { points: `${W1},${y(mm)} ${W1 + 24},${y(mm) - 12} ${W1 + 24},${y(mm) + 12}`, class: "ot" }, svg));
  // The cabin: from its floor (the position) up CABIN_MM.
  const cabin = el("g", { id: "cabin" }, svg);
  const body = el("rect", { x: 106, y: -CABIN_MM, width: 108, height: CABIN_MM, class: "cabin" }, cabin);
  const door = el("rect", { x: 208, y: -200, width: 6, height: 200, class: "door" }, cabin);
  const load = el("text", { x: 160, y: -120, class: "cabin-text" }, cabin);
  const dir = el("text", { x: 160, y: -60, class: "cabin-text big" }, cabin);
  const sl = el("circle", { cx: 95, cy: 0, r: 9, class: "sensor" }, cabin);
  const sr = el("circle", { cx: 225, cy: 0, r: 9, class: "sensor" }, cabin);
  el("line", { x1: 95, x2: 225, y1: 0, y2: 0, class: "cabin-floor" }, cabin);
  shaftParts = { y, cabin, body, door, load, dir, sl, sr, ot };

  // Hall buttons and floor displays, top floor first.
  const floors = $("floors");
  floors.textContent = "";
  for (let f = s.floors; f >= 1; f--) {
    const row = document.createElement("div");
    row.className = "floor-row";
    const name = document.createElement("span");
    name.className = "floor-name";
    name.textContent = `floor ${f}`;
    const disp = document.createElement("span");
    disp.className = "display";
    disp.id = `display-floor-${f}`;
    disp.textContent = "–";
    row.append(name, disp);
    if (f < s.floors) row.append(button(`btn-hall-up-${f}`, "▲", `hall-up:${f}`, "hall"));
    if (f > 1) row.append(button(`btn-hall-down-${f}`, "▼", `hall-down:${f}`, "hall"));
    floors.append(row);
  }
  const cb = $("cabin-buttons");
  cb.textContent = "";
  for (let f = 1; f <= s.floors; f++) cb.append(button(`btn-cabin-${f}`, `${f}`, `cabin:${f}`, "cabin-btn"));
}

function drawShaft(v) {
  const p = shaftParts;
  const l = v.lift;
  p.cabin.setAttribute("transform", `translate(0 ${p.y(l.position_mm)})`);
  p.sl.classList.toggle("on", l.vane_left);
  p.sr.classList.toggle("on", l.vane_right);
  p.door.classList.toggle("open", !l.door_closed);
  p.body.classList.toggle("overloaded", l.load === "overloaded");
  p.load.textContent = l.load;
  p.dir.textContent = l.converter_run ? (l.converter_up ? "▲" : "▼") : "";
  p.ot[0].classList.toggle("tripped", !l.overtravel_bottom_free);
  p.ot[1].classList.toggle("tripped", !l.overtravel_top_free);
}

// ----- the rest of the page ---------------------------------------------------------------

function text(id, value) {
  const e = $(id);
  const s = value === null || value === undefined ? "–" : String(value);
  if (e && e.textContent !== s) e.textContent = s;
}

function lamp(id, on, onText, offText) {
  const e = $(id);
  e.classList.toggle("lit", !!on);
  text(id, on ? onText : offText);
}

function showDisplay(id, d) {
  const e = $(id);
  if (!e || !d) return;
  let s;
  if (d.state === "blank") s = "–";
  else if (d.state === "error") s = "ERR";
  else s = `${d.floor}${d.up ? " ▲" : ""}${d.down ? " ▼" : ""}${d.moving ? " ⇅" : ""}${d.fault ? " ⚠" : ""}`;
  if (e.textContent !== s) e.textContent = s;
  e.title = d.error || (d.moving ? "moving" : "");
  e.classList.toggle("fault", d.fault || d.state === "error");
}

function render(v) {
  last = v;
  const key = JSON.stringify(v.shaft);
  if (key !== shaftKey) {
    shaftKey = key;
    buildShaft(v.shaft);
  }
  drawShaft(v);
  text("sim-time", v.t_s.toFixed(2));
  paused = v.run.paused;
  $("paused").hidden = !paused;
  text("btn-pause", paused ? "▶ resume" : "‖ pause");
  $("btn-pause").classList.toggle("armed", paused);
  showSpeed(v.run.speed);
  for (const id of ["btn-pause", "speed-select", "btn-restart"]) $(id).disabled = v.run.ended;
  text("lag", v.run.lag_ms.toFixed(1));
  text("controller-owner", v.run.controller);
  const viol = $("violations");
  text("violations", `${v.violations} violation${v.violations === 1 ? "" : "s"}`);
  viol.classList.toggle("bad", v.violations > 0);
  text("last-violation", v.last_violation || "");
  if (v.run.ended) setConn(false, "run ended");

  const l = v.lift;
  text("position", l.position_mm.toFixed(1));
  text("cabin-level", l.level_floor === null ? "between floors" : l.level_floor);
  text("velocity", l.velocity_mm_s.toFixed(1));
  text("door", l.door_closed ? "closed" : "open");
  text("load", l.load);
  lamp("k1", l.k1, "closed", "open");
  lamp("k1-aux", l.k1_aux, "closed", "open");
  lamp("conv-run", l.converter_run, "run", "stop");
  text("conv-dir", l.converter_up ? "up" : "down");
  text("conv-hz", l.converter_hz.toFixed(2));
  text("setpoint", l.setpoint_ua);
  text("cranking", l.hand_cranking ? "turning" : "–");
  $("btn-crank").disabled = l.k1;
  const pressed = new Set(l.pressed);
  for (const b of document.querySelectorAll("button[data-press]")) {
    b.classList.toggle("pressed", pressed.has(b.dataset.press));
  }

  for (const d of v.displays) {
    showDisplay(d.id === "cabin" ? "display-cabin" : `display-floor-${d.id.split(" ")[1]}`, d);
  }

  const s = v.safety;
  text("group-state", s.group);
  text("group-errors", [s.fb_err && "FB_ERR", s.com_err && "COM_ERR", s.out_err && "OUT_ERR",
    s.logic_fault && "logic fault"].filter(Boolean).join(" "));
  text("estop-state", s.estop);
  text("mon-state", s.mon);
  lamp("estop-out", s.estop_out, "on", "off (STOP)");
  lamp("estop-del-out", s.estop_del_out, "on", "off");
  text("k1-cause", s.k1_open_cause || "–");
  text("stop-link", s.stop_link.length ? s.stop_link.join(", ") : "ok");

  const c = v.controller;
  document.getElementById("watch-panel").hidden = !c.program;
  if (c.external) {
    text("ctl-state", "outside controller");
    for (const id of ["ctl-init", "ctl-floor", "ctl-target", "fifo-cabin", "fifo-hall", "ctl-algo"]) text(id, "–");
  } else if (c.program) {
    text("ctl-state", c.stopped ? "PLC in STOP: " + c.stopped : "PLC in RUN");
    for (const id of ["ctl-init", "ctl-floor", "ctl-target", "fifo-cabin", "fifo-hall", "ctl-algo"]) text(id, "–");
    text("st-program", c.program);
    renderWatch(c.watch || [], c.watch_left_out);
  } else {
    text("ctl-state", c.state);
    text("ctl-init", c.initialised ? "yes" : "no");
    text("ctl-floor", c.floor);
    text("ctl-target", c.target);
    text("fifo-cabin", c.fifo_cabin.length ? c.fifo_cabin.join(" ") : "empty");
    text("fifo-hall", c.fifo_hall.length ? c.fifo_hall.join(" ") : "empty");
    text("ctl-algo", c.algorithm);
  }

  renderBus(v.bus);
  text("telegrams", v.bus.telegrams.join("\n"));
  text("log", v.log.join("\n"));

  // A restart: simulated time starts again, and so does the plot.
  if (history.length && v.t_s < history[history.length - 1][0]) history = [];
  history.push([v.t_s, l.position_mm, l.velocity_mm_s]);
  while (history.length && (history[0][0] < v.t_s - 30 || history.length > 2400)) history.shift();
  plot();
}

// The master's LEDs of seed 003 table 3.2, each a dot in its light (flashing where it flashes).
function renderLeds(leds) {
  const box = $("master-leds");
  if (!box || !leds) return;
  if (box.children.length !== leds.length) {
    box.textContent = "";
    for (const [name] of leds) {
      const span = document.createElement("span");
      span.id = `led-${name}`;
      box.append(span);
    }
  }
  const label = { pwr: "PWR", ok: "OK", sys: "SYS", asi: "AS-i", asi_active: "AS-i active", prg: "prg", prj: "prj mode" };
  leds.forEach(([name, light], i) => {
    const span = box.children[i];
    const s = `● ${label[name] || name}`;
    if (span.textContent !== s) span.textContent = s;
    span.className = `led led-${light}`;
    span.title = light.replace("_", " ");
  });
}

function renderBus(b) {
  text("bus-phase", b.phase);
  text("cycle", `${b.cycle_us[0]} (${b.cycle_us[1]}–${b.cycle_us[2]})`);
  text("supply", b.supply_v.toFixed(1));
  text("las", b.slaves.filter((s) => s.las).map((s) => s.addr).join(" ") || "empty");
  text("transactions", b.transactions);
  text("repeats", b.repeats);
  text("noise", b.line_noise);
  const tbody = $("slaves").tBodies[0];
  const known = new Set(b.slaves.map((s) => s.number));
  renderLeds(b.master_leds);
  const rows = b.slaves.map((s) => [s.addr, s.name, s.lds, s.las, s.lps, s.lpf, s.input, s.output, s.number, s.light, s.calls, s.repeats]);
  for (const n of b.lab_addresses) if (!known.has(n)) rows.push([`${n}`, "off line", false, false, false, false, "", "", n, null, 0, 0]);
  rows.sort((a, b) => a[8] - b[8]);
  while (tbody.rows.length > rows.length) tbody.deleteRow(-1);
  while (tbody.rows.length < rows.length) {
    const r = tbody.insertRow();
    for (let i = 0; i < 10; i++) r.insertCell();
  }
  rows.forEach((row, i) => {
    const tr = tbody.rows[i];
    tr.id = `slave-${row[0]}`;
    for (let k = 0; k < 8; k++) {
      const cell = tr.cells[k];
      const val = row[k];
      const s = typeof val === "boolean" ? (val ? "●" : "○") : val;
      if (cell.textContent !== s) cell.textContent = s;
      if (typeof val === "boolean") cell.className = val ? (k === 5 ? "bad" : "yes") : "no";
    }
    // The analyser's traffic light, with the calls and repeats behind it.
    const light = tr.cells[8];
    const lit = row[9] ? "●" : "–";
    if (light.textContent !== lit) light.textContent = lit;
    light.className = row[9] ? `light-${row[9]}` : "no";
    light.title = `${row[10]} calls, ${row[11]} repeats`;
    const n = row[8];
    const action = b.lab_addresses.includes(n) ? (row[3] || row[2] ? "offline" : "online") : "";
    const cell = tr.cells[9];
    if (cell.dataset.action !== action || cell.dataset.n !== `${n}`) {
      cell.dataset.action = action;
      cell.dataset.n = `${n}`;
      cell.textContent = "";
      if (action) {
        const btn = document.createElement("button");
        btn.id = `${action}-${n}`;
        btn.className = "small";
        btn.textContent = action === "offline" ? "take off line" : "put on line";
        btn.dataset.cmd = JSON.stringify({ fault: { kind: `slave-${action}`, slave: n } });
        cell.append(btn);
      }
    }
  });
  const head = $("errors").tHead.rows[0];
  const body = $("errors").tBodies[0].rows[0];
  if (head.cells.length !== b.errors.length) {
    head.textContent = "";
    body.textContent = "";
    for (const [k] of b.errors) {
      const th = document.createElement("th");
      th.textContent = k.replace("_", " ");
      head.append(th);
      body.insertCell();
    }
  }
  b.errors.forEach(([, n], i) => {
    if (body.cells[i].textContent !== `${n}`) body.cells[i].textContent = `${n}`;
    body.cells[i].className = n > 0 ? "bad" : "";
  });
}

// ----- the plot ----------------------------------------------------------------------------

function plot() {
  const cv = $("plot");
  const ratio = window.devicePixelRatio || 1;
  const w = cv.clientWidth, h = cv.clientHeight;
  if (cv.width !== Math.round(w * ratio) || cv.height !== Math.round(h * ratio)) {
    cv.width = Math.round(w * ratio);
    cv.height = Math.round(h * ratio);
  }
  const g = cv.getContext("2d");
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  g.clearRect(0, 0, w, h);
  if (!last || history.length < 2) return;
  const s = last.shaft;
  const t1 = last.t_s, t0 = t1 - 30;
  const pMin = s.end_mm[0], pMax = s.end_mm[1];
  const vMax = Math.max(100, ...history.map((p) => Math.abs(p[2])));
  const L = 42, R = 46, T = 8, B = 18;
  const x = (t) => L + ((t - t0) / 30) * (w - L - R);
  const yp = (mm) => T + (1 - (mm - pMin) / (pMax - pMin)) * (h - T - B);
  const yv = (v) => T + (1 - (v + vMax) / (2 * vMax)) * (h - T - B);
  g.font = "10px system-ui, sans-serif";
  g.lineWidth = 1;
  g.strokeStyle = "#ccd";
  g.fillStyle = "#667";
  for (const mm of s.levels_mm) {
    g.beginPath(); g.moveTo(L, yp(mm)); g.lineTo(w - R, yp(mm)); g.stroke();
    g.fillText(`${mm}`, 2, yp(mm) + 3);
  }
  g.fillText(`${Math.round(vMax)}`, w - R + 4, yv(vMax) + 8);
  g.fillText("0", w - R + 4, yv(0) + 3);
  g.fillText(`${-Math.round(vMax)}`, w - R + 4, yv(-vMax));
  g.fillText(`${t0.toFixed(0)} s`, L, h - 4);
  g.fillText(`${t1.toFixed(0)} s`, w - R - 30, h - 4);
  const line = (color, f) => {
    g.strokeStyle = color;
    g.lineWidth = 2;
    g.beginPath();
    history.forEach((p, i) => (i ? g.lineTo(x(p[0]), f(p)) : g.moveTo(x(p[0]), f(p))));
    g.stroke();
  };
  line("#2b6cb0", (p) => yp(p[1]));
  line("#dd6b20", (p) => yv(p[2]));
}

window.addEventListener("resize", plot);
wireControls();
connect();

// A Structured Text program's watch list: a row per variable, its value as a literal of its
// type. Rows are made once per variable and then only their text changes.
function renderWatch(watch, leftOut) {
  const body = document.getElementById("watch");
  while (body.rows.length > watch.length) body.deleteRow(-1);
  watch.forEach(([name, value], i) => {
    const row = body.rows[i] || body.insertRow();
    if (row.cells.length === 0) { row.insertCell(); row.insertCell(); }
    if (row.cells[0].textContent !== name) row.cells[0].textContent = name;
    if (row.cells[1].textContent !== value) row.cells[1].textContent = value;
  });
  const more = document.getElementById("watch-more");
  more.hidden = !leftOut;
  more.textContent = leftOut ? `and ${leftOut} more variables` : "";
}
