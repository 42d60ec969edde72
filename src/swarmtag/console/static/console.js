// swarmtag console: the floor, the tag table, KPIs and operator writes, from /api/events.
// One page for every source (/api/floor says which): a live simulation, real tags (no floor),
// or a replay (play/pause, a time slider and a speed; a file without poses has no floor).
// Plain JavaScript, no build step. The page's cookie (set by the token URL) authenticates;
// every write carries the X-Swarmtag-Console header the server requires with the cookie.
"use strict";

const RAMP = ["#2c7bb6", "#4a98c5", "#74b3d3", "#abd9e9", "#d6eef0",
  "#ffffbf", "#fed98e", "#fdae61", "#ec6b3e", "#d7191c"];
const view = { floor: null, state: null, selected: null, sortKey: "urgency", sortUp: false,
  filter: "", history: [], sliding: false, version: 0 };
const $ = (id) => document.getElementById(id);

function show(message, kind) {
  const el = $("message");
  el.textContent = message;
  el.className = kind;
}

async function api(path, options) {
  const response = await fetch(path, Object.assign({ credentials: "same-origin" }, options));
  const body = response.headers.get("content-type")?.includes("json") ? await response.json() : null;
  return { ok: response.ok, status: response.status, body };
}

async function write(field, value) {
  if (view.selected === null) { show("select a tag first", "error"); return; }
  const marker = view.selected;
  const answer = await api(`/api/tags/${marker}/${field}`, {
    method: "POST",
    headers: { "Content-Type": "application/json", "X-Swarmtag-Console": "1" },
    body: JSON.stringify({ [field]: value }),
  });
  if (answer.ok) {
    show(`tag ${marker}: ${field} set to ${value} (counter ${answer.body.counter})`, "done");
    refreshEink();
  } else {
    show(`tag ${marker}: ${answer.body ? answer.body.error : "HTTP " + answer.status}`, "error");
  }
}

// ---- the floor ---------------------------------------------------------------------------
function scale() {
  const canvas = $("floor");
  const f = view.floor;
  const s = Math.min(canvas.width / f.arena, canvas.height / f.height);
  return { s, h: f.height };
}

function drawStill(ctx, f, s) {
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, ctx.canvas.width, ctx.canvas.height);
  if (f.floor_text) {
    const lines = f.floor_text.split("\n");
    lines.forEach((line, row) => {
      [...line].forEach((ch, col) => {
        const colour = ch === "#" ? "#555" : ch === "P" ? "#cfe8cf" : /[0-9]/.test(ch) ? "#f6d6b8" : null;
        if (!colour) return;
        ctx.fillStyle = colour;
        ctx.fillRect(col * f.floor_cell * s, row * f.floor_cell * s, f.floor_cell * s + 1, f.floor_cell * s + 1);
        if (/[0-9]/.test(ch)) { ctx.fillStyle = "#555"; ctx.font = "10px sans-serif";
          ctx.fillText(ch, (col + 0.3) * f.floor_cell * s, (row + 0.8) * f.floor_cell * s); }
      });
    });
    return;
  }
  ctx.fillStyle = "#cfe8cf";
  ctx.fillRect(0, 0, f.pickup_right * s, f.height * s);
  ctx.fillStyle = "#f6d6b8";
  ctx.fillRect(f.dropoff_left * s, 0, (f.arena - f.dropoff_left) * s, f.height * s);
  ctx.fillStyle = "#555";
  ctx.font = "12px sans-serif";
  ctx.fillText("pick-up", 4, 14);
  ctx.fillText("drop-off", f.dropoff_left * s + 4, 14);
}

let still = null;  // the floor's still picture, drawn once per canvas size

function stillPicture(canvas, f, s) {
  if (!still || still.width !== canvas.width || still.height !== canvas.height) {
    still = document.createElement("canvas");
    still.width = canvas.width; still.height = canvas.height;
    drawStill(still.getContext("2d"), f, s);
  }
  return still;
}

function drawFloor() {
  if (!view.floor || !view.state || view.floor.kind === "none") return;
  const canvas = $("floor");
  const ctx = canvas.getContext("2d");
  const f = view.floor;
  const { s, h } = scale();
  const X = (x) => x * s;
  const Y = (y) => (h - y) * s;
  ctx.drawImage(stillPicture(canvas, f, s), 0, 0);
  const tags = new Map(view.state.tags.map((t) => [t.marker, t]));
  ctx.setLineDash([4, 4]);
  ctx.strokeStyle = "#777";
  for (const r of view.state.robots) {
    const t = r.target === null ? null : tags.get(r.target);
    if (t && t.carried_by !== r.id) {
      ctx.beginPath(); ctx.moveTo(X(r.x), Y(r.y)); ctx.lineTo(X(t.x), Y(t.y)); ctx.stroke();
    }
  }
  ctx.setLineDash([]);
  const half = Math.max(5, (f.carrier_size * s) / 2);
  const drawn = [];
  ctx.font = `bold ${Math.round(half * 1.2)}px sans-serif`;
  ctx.textAlign = "center"; ctx.textBaseline = "middle";
  for (const t of view.state.tags) {
    if (!t.present || t.x === null) continue;
    ctx.fillStyle = t.status === "idle" ? "#bbb" : RAMP[t.urgency];
    ctx.fillRect(X(t.x) - half, Y(t.y) - half, 2 * half, 2 * half);
    ctx.lineWidth = t.marker === view.selected ? 3 : 1;
    ctx.strokeStyle = t.marker === view.selected ? "#000" : t.overdue ? "#b00" : "#333";
    ctx.strokeRect(X(t.x) - half, Y(t.y) - half, 2 * half, 2 * half);
    ctx.fillStyle = t.urgency >= 7 || t.urgency <= 1 ? "#fff" : "#000";
    ctx.fillText(String(t.urgency), X(t.x), Y(t.y));
    drawn.push(`${t.marker}:${t.urgency}`);
  }
  ctx.lineWidth = 1;
  const radius = Math.max(4, f.robot_radius * s);
  for (const r of view.state.robots) {
    ctx.beginPath(); ctx.arc(X(r.x), Y(r.y), radius, 0, 2 * Math.PI);
    ctx.fillStyle = r.mode === "broken" ? "#900" : "#24323f"; ctx.fill();
    ctx.beginPath(); ctx.moveTo(X(r.x), Y(r.y));
    ctx.lineTo(X(r.x + r.hx * f.robot_radius * 1.6), Y(r.y + r.hy * f.robot_radius * 1.6));
    ctx.strokeStyle = "#fff"; ctx.stroke();
  }
  ctx.textAlign = "start"; ctx.textBaseline = "alphabetic";
  canvas.dataset.urgencies = drawn.join(",");  // what was drawn, for tests and tools
}

function pickOnFloor(event) {
  if (!view.floor || !view.state) return;
  const canvas = $("floor");
  const box = canvas.getBoundingClientRect();
  const { s, h } = scale();
  const x = ((event.clientX - box.left) * canvas.width / box.width) / s;
  const y = h - ((event.clientY - box.top) * canvas.height / box.height) / s;
  let best = null; let bestD = Infinity;
  for (const t of view.state.tags) {
    if (!t.present || t.x === null) continue;
    const d = Math.hypot(t.x - x, t.y - y);
    if (d < bestD) { best = t; bestD = d; }
  }
  if (best && bestD < Math.max(view.floor.carrier_size, 12 / s)) select(best.marker);
}

// ---- the table, the alerts, the selection ----------------------------------------------
const COLUMNS = ["marker", "urgency", "status", "destination", "last-heard", "carried-by", "waited"];
const ALERTS_SHOWN = 20;  // the longest waits; the rest are counted
const WINDOW_EXTRA = 10;  // rows made beyond each edge of the table's box
const table = { rows: new Map(), order: "", alerts: null, rowPx: 0 };  // marker -> { tr, cells, texts }

function cellTexts(t) {
  return [t.marker, t.urgency, t.status, t.destination, t.last_heard,
    t.carried_by === null ? "" : "robot " + t.carried_by,
    t.delivered_at === null ? t.waited : "delivered"]
    .map((v) => (v === null || v === undefined ? "–" : String(v)));
}

// A tag's row, made once and then only its changed cells rewritten: with a thousand tags
// ten times a second, rebuilding every row would keep the browser from keeping up.
function rowOf(t) {
  let row = table.rows.get(t.marker);
  if (!row) {
    const tr = document.createElement("tr");
    tr.dataset.marker = t.marker;
    const cells = COLUMNS.map((name) => {
      const td = document.createElement("td"); td.className = name; tr.appendChild(td); return td;
    });
    row = { tr, cells, texts: COLUMNS.map(() => null) };
    table.rows.set(t.marker, row);
  }
  cellTexts(t).forEach((text, i) => {
    if (row.texts[i] !== text) { row.cells[i].textContent = text; row.texts[i] = text; }
  });
  row.tr.classList.toggle("selected", t.marker === view.selected);
  row.tr.classList.toggle("overdue", Boolean(t.overdue));
  return row.tr;
}

function drawTable() {
  const body = document.querySelector("#tags tbody");
  const needle = view.filter.trim().toLowerCase();
  const rows = view.state.tags.filter((t) => !needle ||
    [t.marker, t.status, t.destination, t.carried_by ?? ""].join(" ").toLowerCase().includes(needle));
  const k = view.sortKey;
  rows.sort((a, b) => {
    const va = a[k] ?? -Infinity; const vb = b[k] ?? -Infinity;
    const order = va < vb ? -1 : va > vb ? 1 : a.marker - b.marker;
    return view.sortUp ? order : -order;
  });
  if (table.rows.size > view.state.tags.length) {  // forget the rows of tags gone
    const present = new Set(view.state.tags.map((t) => t.marker));
    for (const [marker, row] of table.rows) {
      if (!present.has(marker)) { row.tr.remove(); table.rows.delete(marker); }
    }
  }
  // Only the rows in (and just beyond) the box are in the page; two padding rows stand for
  // the rest, so that a thousand tags cost the layout of a few dozen rows.
  const box = $("table-box");
  const px = table.rowPx || 24;
  const head = document.querySelector("#tags thead").offsetHeight;
  const first = Math.max(0, Math.floor((box.scrollTop - head) / px) - WINDOW_EXTRA);
  const shown = rows.slice(first, first + Math.ceil(box.clientHeight / px) + 2 * WINDOW_EXTRA);
  const trs = shown.map(rowOf);
  const order = `${first}/${rows.length}:` + shown.map((t) => t.marker).join(",");
  if (order !== table.order) {
    table.order = order;
    $("pad-top").style.height = `${first * px}px`;
    $("pad-bottom").style.height = `${(rows.length - first - shown.length) * px}px`;
    body.replaceChildren($("pad-top"), ...trs, $("pad-bottom"));
    if (!table.rowPx && trs.length) table.rowPx = trs[0].getBoundingClientRect().height || 24;
  }
  const count = $("tag-count");
  count.dataset.total = String(view.state.tags.length);
  count.textContent = needle ? `${rows.length} of ${view.state.tags.length} tags` : `${rows.length} tags`;
  document.querySelectorAll("#tags th").forEach((th) => {
    th.classList.toggle("sorted-up", th.dataset.key === k && view.sortUp);
    th.classList.toggle("sorted-down", th.dataset.key === k && !view.sortUp);
  });
  const overdue = view.state.tags.filter((t) => t.overdue).sort((a, b) => b.waited - a.waited);
  const lines = overdue.slice(0, ALERTS_SHOWN).map((t) =>
    [t.marker, `carrier ${t.marker}: waiting ${Math.round(t.waited)} s (urgency ${t.urgency})`]);
  if (overdue.length > ALERTS_SHOWN) lines.push([null, `and ${overdue.length - ALERTS_SHOWN} more`]);
  const key = lines.map(([, text]) => text).join("\n");
  if (key !== table.alerts) {
    table.alerts = key;
    $("alerts").replaceChildren(...lines.map(([marker, text]) => {
      const li = document.createElement("li");
      if (marker !== null) li.dataset.marker = marker;
      li.textContent = text;
      return li;
    }));
    if (!lines.length) $("alerts").textContent = "none";
  }
  const current = view.state.tags.find((t) => t.marker === view.selected);
  document.querySelectorAll("#urgency-buttons button").forEach((b) =>
    b.classList.toggle("current", current !== undefined && Number(b.dataset.urgency) === current.urgency));
}

function refreshEink() {
  if (view.selected === null) return;
  const img = $("eink");
  img.src = `/api/tags/${view.selected}/eink?at=${Date.now()}`;
  img.hidden = false;
}

function select(marker) {
  view.selected = marker;
  $("selected-marker").textContent = String(marker);
  show("", "");
  refreshEink();
  if (view.state) { drawTable(); drawFloor(); }
}

// ---- KPIs -----------------------------------------------------------------------------------
function fmt(value, unit) { return value === null ? "–" : `${value}${unit}`; }

function kpiRows(k) {
  if (k.kind === "scan") {
    return [["tags", "tags in range", k.tags], ["awaiting", "awaiting pickup", k.awaiting_pickup],
      ["picked", "picked up", k.picked_up], ["idle", "idle", k.idle],
      ["urgency", "mean / max urgency", k.mean_urgency === null ? "–" : `${k.mean_urgency} / ${k.max_urgency}`],
      ["adverts", "adverts (foreign, malformed)", `${k.adverts} (${k.foreign}, ${k.malformed})`],
      ["writes", "writes accepted", k.writes]];
  }
  return [["deliveries", "deliveries", `${k.deliveries} (${k.runs} run${k.runs === 1 ? "" : "s"})`],
    ["p95", "P95 latency", fmt(k.p95_latency, " s")], ["mean", "mean latency", fmt(k.mean_latency, " s")],
    ["pa", "PA", k.pa === null ? "–" : k.pa.toFixed(3)], ["throughput", "throughput", fmt(k.throughput, " / 100 s")]];
}

function showKpis(k) {
  const list = $("kpi-list");
  list.replaceChildren(...kpiRows(k).flatMap(([id, label, value]) => {
    const dt = document.createElement("dt"); dt.textContent = label;
    const dd = document.createElement("dd"); dd.id = `kpi-${id}`; dd.textContent = String(value);
    return [dt, dd];
  }));
  const series = k.kind === "scan" ? k.tags : k.deliveries;
  view.history.push(series);
  if (view.history.length > 120) view.history.shift();
  const c = $("sparkline"); const ctx = c.getContext("2d");
  ctx.clearRect(0, 0, c.width, c.height);
  const lo = Math.min(...view.history); const hi = Math.max(...view.history, lo + 1);
  ctx.beginPath();
  view.history.forEach((v, i) => {
    const x = (i / Math.max(1, view.history.length - 1)) * (c.width - 2) + 1;
    const y = c.height - 2 - ((v - lo) / (hi - lo)) * (c.height - 4);
    if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
  });
  ctx.strokeStyle = "#2c7bb6"; ctx.stroke();
}

// ---- replay ---------------------------------------------------------------------------------
async function control(change) {
  const answer = await api("/api/replay", {
    method: "POST",
    headers: { "Content-Type": "application/json", "X-Swarmtag-Console": "1" },
    body: JSON.stringify(change),
  });
  if (!answer.ok) { show(answer.body ? answer.body.error : "HTTP " + answer.status, "error"); return; }
  view.version = Math.max(view.version, answer.body.version);  // older events are stale now
  showReplay(answer.body);
  const state = await api("/api/state");  // show the new moment now, paused or not
  if (state.ok) showState(state.body);
}

function showReplay(r) {
  $("replay-play").textContent = r.playing ? "pause" : "play";
  $("replay-play").dataset.playing = String(r.playing);
  $("replay-play").disabled = false;  // enabled once the page knows whether it plays
  const slider = $("replay-slider");
  slider.max = String(r.duration);
  if (!view.sliding) slider.value = String(r.position);
  $("replay-position").textContent = `${r.position.toFixed(1)} / ${r.duration.toFixed(1)} s`;
  const speed = $("replay-speed");
  if (document.activeElement !== speed) speed.value = String(r.speed);
}

function startReplay() {
  $("replay-controls").hidden = false;
  $("replay-play").addEventListener("click", () =>
    control({ playing: $("replay-play").dataset.playing !== "true" }));
  const slider = $("replay-slider");
  slider.addEventListener("input", () => { view.sliding = true; });
  slider.addEventListener("change", () => { view.sliding = false; control({ time: Number(slider.value) }); });
  $("replay-speed").addEventListener("change", (e) => control({ speed: Number(e.target.value) }));
}

// States arrive ten times a second; the page draws the latest one at its next frame, so a
// slow machine skips states rather than falling behind.
let drawing = false;

function showState(state) {
  if (view.floor.source === "replay") {
    // A state older than one already shown is stale: an answer to an earlier control can
    // arrive after the stream has brought the next control's moment.
    if (state.replay.version < view.version) return;
    view.version = state.replay.version;
  }
  view.state = state;
  redraw();
}

function redraw() {
  if (drawing || !view.state) return;
  drawing = true;
  requestAnimationFrame(() => { drawing = false; drawState(); });
}

function drawState() {
  const s = view.state;
  const source = view.floor.source;
  if (source === "replay" && s.replay.version < view.version) return;  // a control came since
  if (source === "replay") {
    const r = s.replay;
    $("clock").textContent = `${view.floor.file} · ${r.condition} run ${s.run} (${r.segment + 1} of ${r.segments}) · t = ${s.time.toFixed(1)} s`;
    showReplay(r);
  } else if (source === "scan") {
    $("clock").textContent = `${s.tags.length} tag${s.tags.length === 1 ? "" : "s"} in range · ` +
      (s.radio ? `radio: ${s.radio}` : `listening ${s.time.toFixed(0)} s`);
  } else {
    $("clock").textContent = `run ${s.run} · t = ${s.time.toFixed(1)} s · ${view.floor.speed}× real time`;
  }
  drawFloor(); drawTable();
}

// ---- start ----------------------------------------------------------------------------------
async function start() {
  const floor = await api("/api/floor");
  if (!floor.ok) { $("clock").textContent = "not authorised: open the URL the server printed"; return; }
  view.floor = floor.body;
  const canvas = $("floor");
  $("source").textContent = view.floor.source;
  if (view.floor.kind === "none") {
    canvas.hidden = true;
    document.querySelector("#floor-panel .legend").hidden = true;
    $("floor-note").hidden = false;
    $("floor-note").textContent = view.floor.why;
  } else {
    canvas.height = Math.round(canvas.width * view.floor.height / view.floor.arena);
  }
  if (view.floor.source === "replay") startReplay();
  const buttons = $("urgency-buttons");
  for (let u = 0; u <= 9; u++) {
    const b = document.createElement("button");
    b.type = "button"; b.textContent = String(u); b.dataset.urgency = String(u);
    b.style.background = RAMP[u]; b.style.color = u >= 7 || u <= 1 ? "#fff" : "#000";
    b.addEventListener("click", () => write("urgency", u));
    buttons.appendChild(b);
  }
  $("destination-select").replaceChildren(...view.floor.destinations.map((d) => new Option(String(d), String(d))));
  $("status-apply").addEventListener("click", () => write("status", $("status-select").value));
  $("destination-apply").addEventListener("click", () => write("destination", Number($("destination-select").value)));
  $("filter").addEventListener("input", (e) => { view.filter = e.target.value; if (view.state) drawTable(); });
  document.querySelectorAll("#tags th").forEach((th) => th.addEventListener("click", () => {
    if (view.sortKey === th.dataset.key) view.sortUp = !view.sortUp;
    else { view.sortKey = th.dataset.key; view.sortUp = true; }
    drawTable();
  }));
  document.querySelector("#tags tbody").addEventListener("click", (e) => {
    const tr = e.target.closest("tr[data-marker]"); if (tr) select(Number(tr.dataset.marker));
  });
  $("table-box").addEventListener("scroll", redraw, { passive: true });
  canvas.addEventListener("click", pickOnFloor);
  const events = new EventSource("/api/events");
  events.addEventListener("open", () => { $("link").textContent = "live"; $("link").className = "ok"; });
  events.addEventListener("error", () => { $("link").textContent = "offline"; $("link").className = "bad"; });
  events.addEventListener("state", (e) => showState(JSON.parse(e.data)));
  events.addEventListener("kpis", (e) => showKpis(JSON.parse(e.data)));
}

start();
