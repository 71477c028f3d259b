// pygoby liaison: the four pages, fed by Server-Sent Events (/api/events) and JSON POSTs; over a
// recorded log (pygoby liaison --log), the log bar's controls (/api/log) and no Commander.
"use strict";

const page = (location.pathname.replace(/^\/+/, "") || "scope").split("/")[0];
const $ = (selector) => document.querySelector(selector);
const el = (tag, attrs = {}, ...children) => {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") node.className = v;
    else if (k.startsWith("data-")) node.setAttribute(k, v);
    else node[k] = v;
  }
  for (const child of children) node.append(child);
  return node;
};
const svg = (tag, attrs = {}) => {
  const node = document.createElementNS("http://www.w3.org/2000/svg", tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  return node;
};
const clock = (t) => new Date(t * 1000).toISOString().substring(11, 19);

async function post(body, url = "/api/commander") {
  // the token travels as the cookie the printed URL's ?token= left (HttpOnly: never seen here)
  const response = await fetch(url, {
    method: "POST",
    headers: { "Content-Type": "application/json", "X-Liaison": "1" },
    body: JSON.stringify(body),
  });
  if ((response.headers.get("content-type") || "").startsWith("application/json")) return response.json();
  return { ok: false, error: await response.text() };
}
// the token is kept as a cookie: take it out of the address bar (as Jupyter does)
if (new URLSearchParams(location.search).has("token")) history.replaceState(null, "", location.pathname);

// ------------------------------------------------------------------------------ live updates
let source = null;
function listen(extra = "") {
  if (source) source.close();
  source = new EventSource(`/api/events?page=${page}${extra}`);
  source.onmessage = (event) => {
    $("#status").textContent = logMode ? "replaying a log" : "live " + new Date().toLocaleTimeString();
    $("#status").classList.remove("bad");
    renderers[page](JSON.parse(event.data));
  };
  source.onerror = () => {
    $("#status").textContent = "disconnected (retrying)";
    $("#status").classList.add("bad");
  };
}

// ------------------------------------------------------------------------------ Scope
// The server sends every row once, then only the rows that changed: rows are updated in place
// (a click never lands on a row that is being replaced), ages worked out here from `now`.
let historyKey = "";
const scopeRows = new Map(); // key -> { tr, row, cells }
let scopeKeys = []; // sorted, as the table
function selectHistory(key) {
  const old = scopeRows.get(historyKey);
  if (old) old.tr.classList.remove("selected");
  historyKey = key;
  scopeRows.get(key).tr.classList.add("selected");
  $("#history-key").textContent = key;
  drawHistory();
}

function scopeRow(key) {
  const expander = el("button", { class: "expander", title: "show the whole value" }, "▸");
  const cells = {
    value: el("td", { class: "value" }), type: el("td", { class: "type" }), source: el("td", { class: "source" }),
    community: el("td", { class: "community" }), age: el("td", { class: "age" }), rate: el("td", { class: "rate" }),
  };
  const tr = el("tr", { "data-key": key }, el("td", { class: "key", title: key }, expander, el("span", {}, key)),
    cells.value, cells.type, cells.source, cells.community, cells.age, cells.rate);
  expander.onclick = () => { expander.textContent = tr.classList.toggle("expanded") ? "▾" : "▸"; };
  expander.onpointerdown = (event) => event.stopPropagation();
  // selected as the button goes down: a row that moves under a held button (a new variable
  // inserted above it) still gets the click
  tr.onpointerdown = (event) => {
    if (event.button === 0 && scopeRows.get(key).row.numeric) selectHistory(key);
  };
  return { tr, cells, row: null };
}

function setText(node, text) { if (node.textContent !== text) node.textContent = text; }

function renderScope(data) {
  const body = $("#scope-table tbody");
  if (data.full) { body.replaceChildren(); scopeRows.clear(); scopeKeys = []; }
  for (const key of data.removed) {
    const entry = scopeRows.get(key);
    if (!entry) continue;
    entry.tr.remove(); scopeRows.delete(key); scopeKeys.splice(scopeKeys.indexOf(key), 1);
  }
  for (const row of data.changed) {
    let entry = scopeRows.get(row.key);
    if (!entry) {
      entry = scopeRow(row.key);
      let [lo, hi] = [0, scopeKeys.length];
      while (lo < hi) { const mid = (lo + hi) >> 1; if (scopeKeys[mid] < row.key) lo = mid + 1; else hi = mid; }
      const next = lo < scopeKeys.length ? scopeRows.get(scopeKeys[lo]).tr : null;
      body.insertBefore(entry.tr, next);
      scopeKeys.splice(lo, 0, row.key); scopeRows.set(row.key, entry);
      if (row.key === historyKey) entry.tr.classList.add("selected");
    }
    entry.row = row;
    const c = entry.cells;
    setText(c.value, row.value); setText(c.type, row.type); setText(c.source, row.source);
    setText(c.community, row.community); setText(c.rate, row.rate.toFixed(2));
    entry.tr.classList.toggle("numeric", row.numeric);
  }
  for (const entry of scopeRows.values()) setText(entry.cells.age, Math.max(data.now - entry.row.time, 0).toFixed(1));
  $("#scope-count").textContent = `${data.count} variables`;
  if (historyKey && data.changed.some((row) => row.key === historyKey)) drawHistory();
}

async function drawHistory() {
  const response = await fetch(`/api/scope/history?key=${encodeURIComponent(historyKey)}`);
  const { points } = await response.json();
  const canvas = $("#history-canvas");
  const ctx = canvas.getContext("2d");
  const [w, h, pad] = [canvas.width, canvas.height, 36];
  ctx.clearRect(0, 0, w, h);
  if (points.length === 0) return;
  const ts = points.map((p) => p[0]), vs = points.map((p) => p[1]);
  let [t0, t1, v0, v1] = [Math.min(...ts), Math.max(...ts), Math.min(...vs), Math.max(...vs)];
  if (t1 === t0) t1 = t0 + 1;
  if (v1 === v0) { v0 -= 1; v1 += 1; }
  const x = (t) => pad + (t - t0) / (t1 - t0) * (w - 2 * pad);
  const y = (v) => h - pad + (v0 - v) / (v1 - v0) * (h - 2 * pad);
  ctx.strokeStyle = "#d7dde4"; ctx.fillStyle = "#6b7785"; ctx.font = "11px sans-serif";
  ctx.strokeRect(pad, pad, w - 2 * pad, h - 2 * pad);
  ctx.fillText(v1.toPrecision(6), 2, pad + 4); ctx.fillText(v0.toPrecision(6), 2, h - pad);
  ctx.fillText(clock(t0), pad, h - 8); ctx.fillText(clock(t1), w - pad - 48, h - 8);
  ctx.strokeStyle = "#e87722"; ctx.lineWidth = 2; ctx.beginPath();
  points.forEach(([t, v], i) => (i ? ctx.lineTo(x(t), y(v)) : ctx.moveTo(x(t), y(v))));
  ctx.stroke();
}

// ------------------------------------------------------------------------------ Commander
let current = "";
let modemIds = [];
function showMessage(text, error = false) {
  const box = $("#cmd-message");
  box.textContent = text;
  box.className = "message" + (error ? " error" : "");
}

function renderForm(fields) {
  const body = $("#cmd-form tbody");
  body.replaceChildren(...fields.map((f) => {
    let input;
    if (f.editable && (f.kind === "enum" || f.kind === "bool")) {
      const options = f.kind === "bool" ? ["true", "false"] : f.enum;
      input = el("select", { "data-field": f.name }, el("option", { value: "" }, ""),
        ...options.map((o) => el("option", { value: o, selected: o === f.value }, o)));
    } else {
      input = el("input", { "data-field": f.name, value: f.value, disabled: !f.editable, size: 22 });
    }
    const error = el("div", { class: "error" });
    input.addEventListener("input", async () => {
      const r = await post({ action: "check", type: current, field: f.name, text: input.value, partial: true });
      input.classList.toggle("invalid", !r.ok);
      error.textContent = r.ok ? "" : r.error;
    });
    input.addEventListener("change", async () => {
      const r = await post({ action: "set", type: current, field: f.name, text: input.value });
      input.classList.toggle("invalid", !r.ok);
      error.textContent = r.ok ? "" : r.error;
    });
    const specials = el("td", { class: "specials" });
    if (f.editable && (f.kind === "int" || f.kind === "float")) {
      specials.append(el("button", { title: "insert special: current time", onclick: () => special(f.name, "time") }, "t"));
      if (/lat|lon/i.test(f.name)) specials.append(el("button", { title: "insert special: local X,Y to longitude,latitude", onclick: () => special(f.name, "xy") }, "x,y"));
      if (modemIds.length) {
        const pick = el("select", { title: "insert special: modem id" }, el("option", { value: "" }, "id…"),
          ...modemIds.map(([id, name, type]) => el("option", { value: id }, `${id}: ${name} (${type})`)));
        pick.onchange = () => pick.value !== "" && special(f.name, "modem_id", pick.value);
        specials.append(pick);
      }
    }
    if (f.editable && f.kind === "string") specials.append(el("button", { title: "insert special: community", onclick: () => special(f.name, "community") }, "community"));
    return el("tr", { "data-field": f.name }, el("td", { class: "name" }, f.name),
      el("td", {}, input, error), specials, el("td", { class: "info" }, f.describe));
  }));
}

async function special(field, name, modemId) {
  const r = await post({ action: "special", type: current, field, special: name, modem_id: modemId });
  if (!r.ok) showMessage(r.error, true);
  if (r.fields) renderForm(r.fields);
}

async function commanderAction(action, extra = {}) {
  if (!current) { showMessage("choose a message first", true); return null; }
  const r = await post({ action, type: current, ...extra });
  if (!r.ok) { showMessage(r.error, true); return r; }
  if (r.fields) renderForm(r.fields);
  return r;
}

async function setupCommander() {
  const info = await (await fetch("/api/commander/types")).json();
  modemIds = info.modem_ids;
  const select = $("#cmd-type");
  // the configuration's commands; "show all" adds the other messages (telemetry)
  const offer = () => {
    const all = $("#cmd-all").checked;
    select.replaceChildren(el("option", { value: "" }, "(choose a message)"),
      ...info.types.filter((t) => all || t.command || t.name === current).map((t) =>
        el("option", { value: t.name, selected: t.name === current }, `${t.short}${t.ack ? " (ack)" : ""}${t.command ? "" : " (not a command)"}`)));
  };
  offer();
  $("#cmd-all").onchange = offer;
  select.onchange = async () => {
    current = select.value;
    $("#cmd-preview-text").hidden = true;
    showMessage("");
    if (current) await commanderAction("open");
    else $("#cmd-form tbody").replaceChildren();
  };
  $("#cmd-preview").onclick = async () => {
    const r = await commanderAction("preview");
    if (r && r.ok) {
      const box = $("#cmd-preview-text");
      box.hidden = false;
      box.textContent = "Preview (nothing published):\n" + r.preview.posts.join("\n") +
        (r.preview.warnings.length ? "\nWarnings: " + r.preview.warnings.join("; ") : "");
    }
  };
  $("#cmd-send").onclick = async () => {
    const r = await commanderAction("send");
    if (r && r.ok) showMessage(`sent #${r.record.id} at ${clock(r.record.time)}: ${r.record.posts.join(" | ")}`);
  };
  $("#cmd-clear").onclick = () => commanderAction("clear");
  $("#cmd-save").onclick = async () => {
    const r = await commanderAction("save", { path: $("#cmd-path").value });
    if (r && r.ok) showMessage("saved to " + $("#cmd-path").value);
  };
  $("#cmd-load").onclick = async () => {
    const r = await commanderAction("load", { path: $("#cmd-path").value });
    if (r && r.ok) showMessage("loaded " + $("#cmd-path").value + (r.warnings.length ? " (" + r.warnings.join("; ") + ")" : ""));
  };
}

function renderCommander(data) {
  $("#cmd-notices").replaceChildren(...data.notices.map((text) =>
    el("div", { class: "notice" + (text.includes(" expired ") ? " expired" : "") }, text)));
  $("#cmd-records tbody").replaceChildren(...data.records.map((r) =>
    el("tr", { "data-id": r.id }, el("td", {}, String(r.id)), el("td", {}, r.type), el("td", {}, clock(r.time)),
      el("td", { class: "status " + r.status.replace(" ", "-") }, r.status), el("td", { class: "value" }, r.text))));
}

// ------------------------------------------------------------------------------ Acomms
function renderAcomms(data) {
  $("#acomms-modem").textContent = data.modem_id;
  $("#acomms-drivers").replaceChildren(...data.drivers.map((text) =>
    el("div", { class: "driver" + (text.endsWith(": running") ? "" : " failed") }, text)));
  $("#acomms-queues tbody").replaceChildren(...data.queues.map((q) =>
    el("tr", { "data-queue": q.name }, el("td", {}, q.name), el("td", {}, q.dccl_id ?? "?"), el("td", { class: "size" }, String(q.size)),
      el("td", {}, q.ack ? "yes" : "no"), el("td", {}, String(q.ttl)), el("td", {}, String(q.value_base)),
      el("td", {}, q.priority.toFixed(2)), el("td", {}, String(q.sent)), el("td", {}, q.next ? "▶ next" : ""))));
  const mac = data.mac;
  $("#acomms-cycle").textContent = `${mac.slots.length} slots, ${mac.cycle_seconds} s` +
    (mac.into_slot !== null ? `, ${mac.into_slot} s into slot ${mac.current}` : "");
  $("#acomms-slots").replaceChildren(...mac.slots.map((s, i) =>
    el("div", { class: "slot" + (i === mac.current ? " current" : "") }, `${s.src}→${s.dest < 0 ? "any" : s.dest} ${s.type} r${s.rate} ${s.seconds}s`)));
  $("#acomms-tx tbody").replaceChildren(...data.tx.map((t) =>
    el("tr", {}, el("td", {}, clock(t.time)), el("td", {}, `${t.src}→${t.dest}`), el("td", {}, t.type), el("td", {}, String(t.rate)),
      el("td", {}, t.messages.join(", ")), el("td", {}, t.mode ?? ""))));
  $("#acomms-rx tbody").replaceChildren(...data.rx.map((r) =>
    el("tr", {}, el("td", {}, clock(r.time)), el("td", {}, `${r.src}→${r.dest}`), el("td", {}, r.type), el("td", {}, r.messages.join(", ")),
      el("td", {}, r.snr_in ?? ""), el("td", {}, r.snr_out ?? ""), el("td", {}, r.doppler ?? ""), el("td", {}, r.mse ?? ""),
      el("td", {}, r.bad_frames ?? ""))));
  $("#acomms-timeline").replaceChildren(...data.timeline.map((e) =>
    el("li", { class: e.kind }, `${clock(e.time)} ${e.text}`)));
}

// ------------------------------------------------------------------------------ Map
const COLOURS = ["#1565c0", "#e87722", "#2e7d32", "#6a1b9a", "#c62828", "#00838f"];
function renderMap(data) {
  const map = $("#map-svg");
  const [W, H, pad] = [900, 600, 50];
  const xs = [], ys = [];
  for (const n of data.nodes) { xs.push(n.x); ys.push(n.y); for (const [x, y] of n.track) { xs.push(x); ys.push(y); } }
  if (xs.length === 0) { map.replaceChildren(); $("#map-info").textContent = "no positions yet"; return; }
  let [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const span = Math.max(x1 - x0, y1 - y0, 50) * 1.15;
  const [cx, cy] = [(x0 + x1) / 2, (y0 + y1) / 2];
  const scale = Math.min(W - 2 * pad, H - 2 * pad) / span;
  const px = (x) => W / 2 + (x - cx) * scale, py = (y) => H / 2 - (y - cy) * scale;
  const children = [];
  const step = Math.pow(10, Math.floor(Math.log10(span / 2)));
  // the picture keeps its aspect in a window of any shape, so the grid reaches well beyond the
  // 900 x 600 box to every edge of the window
  for (let g = Math.ceil((cx - 3 * span) / step) * step; g <= cx + 3 * span; g += step) {
    children.push(svg("line", { class: "gridline", x1: px(g), x2: px(g), y1: -2 * H, y2: 3 * H }));
  }
  for (let g = Math.ceil((cy - 3 * span) / step) * step; g <= cy + 3 * span; g += step) {
    children.push(svg("line", { class: "gridline", y1: py(g), y2: py(g), x1: -2 * W, x2: 3 * W }));
  }
  const where = Object.fromEntries(data.nodes.map((n) => [n.name, n]));
  for (const link of data.links) {
    const [a, b] = [where[link.from], where[link.to]];
    if (!a || !b) continue;
    const line = svg("line", { class: "link", x1: px(a.x), y1: py(a.y), x2: px(b.x), y2: py(b.y), "data-from": link.from, "data-to": link.to });
    line.append(svg("title")); line.firstChild.textContent = `${link.from} → ${link.to}, ${link.age} s ago`;
    children.push(line);
  }
  data.nodes.forEach((n, i) => {
    const colour = COLOURS[i % COLOURS.length];
    children.push(svg("polyline", { class: "track", stroke: colour, points: n.track.map(([x, y]) => `${px(x)},${py(y)}`).join(" ") }));
    const g = svg("g", { class: "node", "data-name": n.name, transform: `translate(${px(n.x)},${py(n.y)})` });
    const heading = n.heading ?? 0;
    g.append(svg("path", { d: "M0,-11 L7,8 L0,4 L-7,8 Z", fill: colour, transform: `rotate(${heading})` }));
    const label = svg("text", { x: 12, y: 4 }); label.textContent = `${n.name} (${n.x.toFixed(0)}, ${n.y.toFixed(0)})`;
    g.append(label);
    children.push(g);
  });
  const bar = step;
  children.push(svg("line", { x1: 20, x2: 20 + bar * scale, y1: H - 20, y2: H - 20, stroke: "#1d2733", "stroke-width": 3 }));
  const barLabel = svg("text", { x: 20, y: H - 28 }); barLabel.textContent = `${bar} m`; children.push(barLabel);
  map.replaceChildren(...children);
  $("#map-info").textContent = `${data.nodes.length} vehicles, ${data.links.length} links heard recently (local x/y about the datum; north up)`;
}

const renderers = { scope: renderScope, commander: renderCommander, acomms: renderAcomms, map: renderMap };

// ------------------------------------------------------------------------------ log replay
// The server owns the replay (time, play/pause, speed); the bar shows its status four times a
// second and posts the controls. The slider is left alone while it is being dragged.
let logMode = false;
let sliding = false;
function renderLog(s) {
  const slider = $("#log-slider");
  slider.max = String(s.duration);
  if (!sliding) slider.value = String(s.target);
  const shown = sliding ? Number(slider.value) : s.time;
  setText($("#log-time"), `${shown.toFixed(1)} / ${s.duration.toFixed(1)} s  ${clock(s.log_start + shown)} UTC` +
    (s.caught_up || sliding ? "" : "  (seeking…)"));
  $("#log-time").dataset.time = String(s.time);
  setText($("#log-play"), s.playing ? "❚❚ Pause" : "▶ Play");
  $("#log-play").dataset.playing = String(s.playing);
  $("#log-speed").value = String(s.speed);
}

async function logControl(body) {
  const r = await post(body, "/api/log");
  if (r.ok) renderLog(r);
  else { $("#status").textContent = r.error; $("#status").classList.add("bad"); }
}

async function setupLog() {
  const response = await fetch("/api/log");
  const s = response.ok ? await response.json() : { replaying: false };
  if (!s.replaying) return false;
  logMode = true;
  $("#log-bar").hidden = false;
  $("#log-file").textContent = `${s.file}: ${s.entries} entries` + (s.bad_lines ? `, ${s.bad_lines} damaged lines skipped` : "");
  $("#log-speed").replaceChildren(...s.speeds.map((v) => el("option", { value: String(v) }, `${v}×`)));
  document.querySelector('nav a[data-page="commander"]').hidden = true;
  const slider = $("#log-slider");
  slider.addEventListener("input", () => { sliding = true; });
  slider.addEventListener("change", async () => {
    await logControl({ action: "seek", time: Number(slider.value) });
    sliding = false;
  });
  $("#log-play").onclick = () => logControl({ action: $("#log-play").dataset.playing === "true" ? "pause" : "play" });
  $("#log-speed").onchange = () => logControl({ action: "speed", speed: Number($("#log-speed").value) });
  renderLog(s);
  setInterval(async () => {
    const r = await fetch("/api/log");
    if (r.ok) renderLog(await r.json());
  }, 250);
  return true;
}

// ------------------------------------------------------------------------------ start
document.querySelectorAll("nav a").forEach((a) => a.classList.toggle("active", a.dataset.page === page));
const section = document.getElementById(`page-${page}`);
if (section) section.hidden = false;
if (page === "scope") {
  let timer = null;
  $("#scope-filter").addEventListener("input", () => {
    clearTimeout(timer);
    timer = setTimeout(() => listen("&filter=" + encodeURIComponent($("#scope-filter").value)), 250);
  });
}
(async () => {
  const replaying = await setupLog();
  if (replaying && page === "commander") {
    // nothing to send to: the page says why instead of offering a form that cannot work
    $("#cmd-log-note").hidden = false;
    for (const part of section.querySelectorAll(".toolbar, .split, #cmd-message")) part.hidden = true;
    return;
  }
  if (page === "commander") setupCommander();
  if (renderers[page]) listen();
})();
