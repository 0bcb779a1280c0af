// petrel console: plain JavaScript over the console's JSON API and WebSocket (no build step).
"use strict";

const token = new URLSearchParams(location.search).get("token");
const headers = token ? { Authorization: "Bearer " + token } : {};
const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";
let agent = null;
let socket = null;
let gridVersion = null;
let grid = null;
const rows = new Map(); // property key -> its table row

async function api(path, options = {}) {
  const response = await fetch(path, { ...options, headers: { ...headers, ...(options.headers || {}) } });
  const body = await response.json().catch(() => ({ error: response.statusText }));
  if (!response.ok) throw new Error(body.error || response.statusText);
  return body;
}

function agentPath(rest) {
  return "/api/agents/" + encodeURIComponent(agent) + rest;
}

function el(tag, attrs = {}, text) {
  const node = tag.startsWith("svg:") ? document.createElementNS(SVG, tag.slice(4)) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function setStatus(text, bad) {
  $("status").textContent = text;
  $("status").className = "status" + (bad ? " error" : "");
}

// ---- modules -------------------------------------------------------------------------------
function showModules(modules) {
  const body = $("modules").tBodies[0];
  body.replaceChildren(...modules.map((m) => {
    const tr = el("tr", { "data-module": m.name });
    const cells = [m.name, m.type, m.status, m.steps, m.steps_per_s.toFixed(1), m.mean_step_us.toFixed(1),
      m.last_step_us.toFixed(1), m.restarts, m.failures, m.dropped];
    cells.forEach((c, i) => tr.append(el("td", i === 2 && c === "failed" ? { class: "failed" } : {}, String(c))));
    return tr;
  }));
}

// ---- properties ----------------------------------------------------------------------------
async function loadProperties() {
  const { properties } = await api(agentPath("/properties"));
  rows.clear();
  const body = $("properties").tBodies[0];
  body.replaceChildren(...properties.map((p) => {
    const tr = el("tr", { "data-key": p.key });
    tr.append(el("td", {}, p.key), el("td", {}, p.kind), el("td", {}, p.type), el("td", { class: "value" }, ""));
    const edit = el("td");
    if (p.writable) {
      const input = el("input", { class: "edit", "data-key": p.key, placeholder: "RON value" });
      const button = el("button", { "data-key": p.key }, "set");
      const note = el("span", { class: "note" });
      const submit = () => setProperty(p.key, input.value, note);
      button.addEventListener("click", submit);
      input.addEventListener("keydown", (e) => { if (e.key === "Enter") submit(); });
      edit.append(input, button, note);
    }
    tr.append(edit);
    rows.set(p.key, tr);
    return tr;
  }));
  applyFilter();
}

async function setProperty(key, value, note) {
  note.textContent = "…";
  note.className = "note";
  try {
    const v = await api(agentPath("/set"), {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ key, value }),
    });
    note.textContent = "✓ " + v.text;
    note.className = "note ok";
  } catch (e) {
    note.textContent = e.message;
    note.className = "note error";
  }
}

function applyFilter() {
  const f = $("filter").value.trim();
  for (const [key, tr] of rows) tr.hidden = f !== "" && !key.includes(f);
}

function showValues(values) {
  for (const v of values) {
    const tr = rows.get(v.key);
    if (!tr) continue;
    const cell = tr.querySelector("td.value");
    cell.textContent = v.text;
    cell.title = v.json !== undefined ? JSON.stringify(v.json) : v.text;
    cell.dataset.version = v.version;
    cell.classList.add("changed");
    setTimeout(() => cell.classList.remove("changed"), 300);
  }
}

function connect() {
  if (socket) socket.close();
  const q = new URLSearchParams({ agent });
  if (token) q.set("token", token);
  const s = new WebSocket(`ws://${location.host}/api/ws?${q}`);
  socket = s;
  s.onopen = () => { setStatus("live"); s.send(JSON.stringify({ watch: "all" })); };
  // The console closes the socket of an agent that left: attach again when it is back.
  s.onclose = () => {
    // An agent already shown as left keeps saying so.
    if (socket !== s || agentState !== "live") return;
    setStatus("disconnected", true);
    agentState = "disconnected";
  };
  s.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    if (msg.values) showValues(msg.values);
  };
}

// ---- link graph ----------------------------------------------------------------------------
function moduleOf(key) { return key.startsWith("petrel://") ? key.split("/")[2] + ":" + key.split("/")[3] : key.split("/")[0]; }

function drawGraph(g) {
  const svg = $("graph");
  svg.replaceChildren(arrowHead());
  const names = [...new Set([...g.modules.filter((m) => !m.startsWith("_")), ...g.links.map((l) => moduleOf(l.to))])];
  const w = +svg.getAttribute("width"), h = +svg.getAttribute("height");
  const pos = new Map(names.map((n, i) => {
    const a = (2 * Math.PI * i) / Math.max(names.length, 1);
    return [n, [w / 2 + (w / 2 - 90) * Math.cos(a), h / 2 + (h / 2 - 30) * Math.sin(a)]];
  }));
  const seen = new Set();
  for (const l of g.links) {
    const from = pos.get(moduleOf(l.to)), to = pos.get(moduleOf(l.from));
    const id = moduleOf(l.to) + ">" + moduleOf(l.from);
    if (!from || !to || seen.has(id)) continue;
    seen.add(id);
    svg.append(el("svg:line", { x1: from[0], y1: from[1], x2: to[0], y2: to[1], stroke: l.queue ? "#1d3557" : "#888",
      "stroke-width": l.queue ? 2.5 : 1, "marker-end": "url(#arrow)" }));
  }
  for (const [n, [x, y]] of pos) {
    svg.append(el("svg:rect", { x: x - 60, y: y - 11, width: 120, height: 22, rx: 4, fill: "#e8eef7", stroke: "#1d3557" }));
    svg.append(el("svg:text", { x, y: y + 4, "text-anchor": "middle" }, n));
  }
}

function arrowHead() {
  const defs = el("svg:defs");
  const marker = el("svg:marker", { id: "arrow", viewBox: "0 0 10 10", refX: 30, refY: 5, markerWidth: 6, markerHeight: 6, orient: "auto" });
  marker.append(el("svg:path", { d: "M0,0 L10,5 L0,10 z", fill: "#555" }));
  defs.append(marker);
  return defs;
}

// ---- plan ----------------------------------------------------------------------------------
function drawPlan(plan) {
  $("plan-section").hidden = false;
  $("plan-result").textContent = `${plan.module}: ${plan.result} (${plan.fired} fired; running: ${plan.running || "-"})`;
  const svg = $("plan");
  svg.replaceChildren(arrowHead());
  // Layers: a breadth-first walk from the initially marked places, place → transition → place.
  const depth = new Map();
  const start = plan.places.map((p, i) => [p, i]).filter(([p]) => p.role === "init").map(([, i]) => i);
  let frontier = start.length ? start : [0];
  frontier.forEach((i) => depth.set("p" + i, 0));
  for (let d = 0; frontier.length && d < 200; d += 2) {
    const next = [];
    plan.transitions.forEach((t, ti) => {
      if (t.inputs.some((i) => frontier.includes(i)) && !depth.has("t" + ti)) {
        depth.set("t" + ti, d + 1);
        t.outputs.forEach((o) => { if (!depth.has("p" + o)) { depth.set("p" + o, d + 2); next.push(o); } });
      }
    });
    frontier = next;
  }
  const columns = new Map();
  const pos = new Map();
  const place = (id) => { const d = depth.has(id) ? depth.get(id) : 0; const row = columns.get(d) || 0; columns.set(d, row + 1); pos.set(id, [30 + d * 55, 25 + row * 40]); };
  plan.places.forEach((_, i) => place("p" + i));
  plan.transitions.forEach((_, i) => place("t" + i));
  const width = Math.max(...[...pos.values()].map(([x]) => x)) + 80, height = Math.max(...[...pos.values()].map(([, y]) => y)) + 30;
  svg.setAttribute("viewBox", `0 0 ${Math.max(width, 200)} ${Math.max(height, 100)}`);
  plan.transitions.forEach((t, ti) => {
    const [tx, ty] = pos.get("t" + ti);
    t.inputs.forEach((i) => { const [x, y] = pos.get("p" + i); svg.append(el("svg:line", { x1: x, y1: y, x2: tx, y2: ty, stroke: "#999" })); });
    t.outputs.forEach((o) => { const [x, y] = pos.get("p" + o); svg.append(el("svg:line", { x1: tx, y1: ty, x2: x, y2: y, stroke: "#999" })); });
  });
  const recent = new Set((plan.firings.at(-1) || { transitions: [] }).transitions);
  plan.transitions.forEach((t, ti) => {
    const [x, y] = pos.get("t" + ti);
    svg.append(el("svg:rect", { x: x - 4, y: y - 10, width: 8, height: 20, fill: recent.has(t.label) ? "#e76f51" : "#333" }, ""));
    svg.append(el("svg:title", {}, t.label));
  });
  const tokens = new Map(plan.marking.map((m) => [m.place, m.tokens]));
  plan.places.forEach((p, i) => {
    const [x, y] = pos.get("p" + i);
    const n = tokens.get(p.label) || 0;
    const c = el("svg:circle", { cx: x, cy: y, r: 10, fill: n ? "#2a9d8f" : "#fff", stroke: p.role === "goal" ? "#2a7d2a" : p.role === "fail" ? "#b00020" : "#333", "stroke-width": 2, "data-place": p.label });
    c.append(el("svg:title", {}, p.label));
    svg.append(c);
    if (n > 1) svg.append(el("svg:text", { x, y: y + 4, "text-anchor": "middle", fill: "#fff" }, String(n)));
    svg.append(el("svg:text", { x: x + 12, y: y - 8 }, p.label.length > 18 ? p.label.slice(0, 17) + "…" : p.label));
  });
  $("firings").replaceChildren(...plan.firings.slice(-30).reverse().map((f) =>
    el("li", {}, `${f.time_s.toFixed(1)}s #${f.fired} ${f.transitions.join(", ") || "?"} → ${f.marking}`)));
}

// ---- map and camera ------------------------------------------------------------------------
function bytes(b64) { const s = atob(b64); const a = new Uint8Array(s.length); for (let i = 0; i < s.length; i++) a[i] = s.charCodeAt(i); return a; }

function gridImage(g) {
  const canvas = document.createElement("canvas");
  canvas.width = g.width; canvas.height = g.height;
  const ctx = canvas.getContext("2d");
  const img = ctx.createImageData(g.width, g.height);
  const cells = bytes(g.cells);
  for (let row = 0; row < g.height; row++) for (let col = 0; col < g.width; col++) {
    const c = cells[row * g.width + col];
    const v = c === 255 ? 205 : 255 - Math.round((Math.min(c, 100) * 255) / 100);
    const o = ((g.height - 1 - row) * g.width + col) * 4; // row 0 is the bottom (y up)
    img.data.set([v, v, v, 255], o);
  }
  ctx.putImageData(img, 0, 0);
  return canvas;
}

function drawMap(m) {
  if (m.grid) { grid = m.grid; grid.image = gridImage(m.grid); }
  if (m.grid_version !== undefined) gridVersion = m.grid_version;
  const canvas = $("map"), ctx = canvas.getContext("2d");
  ctx.fillStyle = "#ddd"; ctx.fillRect(0, 0, canvas.width, canvas.height);
  if (!grid) return;
  const scale = Math.min(canvas.width / grid.width, canvas.height / grid.height);
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(grid.image, 0, 0, grid.width * scale, grid.height * scale);
  const px = (p) => [((p.x - grid.origin.x) / grid.resolution) * scale, (grid.height - (p.y - grid.origin.y) / grid.resolution) * scale];
  const dot = (p, color, r) => { const [x, y] = px(p); ctx.fillStyle = color; ctx.beginPath(); ctx.arc(x, y, r, 0, 2 * Math.PI); ctx.fill(); };
  if (Array.isArray(m.path) && m.path.length) {
    ctx.strokeStyle = "#2a9d8f"; ctx.lineWidth = 2; ctx.beginPath();
    m.path.forEach((p, i) => { const [x, y] = px(p); i ? ctx.lineTo(x, y) : ctx.moveTo(x, y); }); ctx.stroke();
  }
  const pose = m.true_pose || m.pose;
  if (m.laser && pose) {
    ctx.fillStyle = "#e63946";
    m.laser.ranges.forEach((r, i) => {
      if (!(r < m.laser.range_max)) return;
      const a = pose.theta + m.laser.angle_min + i * m.laser.angle_increment;
      const [x, y] = px({ x: pose.x + r * Math.cos(a), y: pose.y + r * Math.sin(a) });
      ctx.fillRect(x - 1, y - 1, 2, 2);
    });
  }
  (m.goals || []).forEach((g) => dot(g, "#f4a261", 5));
  (m.victims || []).forEach((v) => dot(v, "#2a7d2a", 6));
  if (m.true_pose) dot(m.true_pose, "#888", 5);
  if (m.pose) {
    dot(m.pose, "#1d3557", 6);
    const [x, y] = px(m.pose);
    ctx.strokeStyle = "#1d3557"; ctx.beginPath(); ctx.moveTo(x, y);
    ctx.lineTo(x + 14 * Math.cos(m.pose.theta), y - 14 * Math.sin(m.pose.theta)); ctx.stroke();
  }
}

function drawCamera(image) {
  const canvas = $("camera");
  // No camera, or no frame yet (a queue's default item is an empty image).
  if (!image || !image.width || !image.height) { canvas.hidden = true; return; }
  canvas.hidden = false;
  canvas.width = image.width; canvas.height = image.height;
  const ctx = canvas.getContext("2d");
  const img = ctx.createImageData(image.width, image.height);
  const px = bytes(image.data);
  for (let i = 0; i < image.width * image.height; i++) img.data.set([px[i], px[i], px[i], 255], i * 4);
  ctx.putImageData(img, 0, 0);
}

// ---- feeds ---------------------------------------------------------------------------------
function feed(id, items, line) {
  $(id).replaceChildren(...items.slice(-50).reverse().map((i) => el("li", {}, line(i))));
}

// Agents come and go (`petrel console`): the list is redrawn when it changes, an agent that
// left is shown so, and one that comes back is attached to again.
let shownAgents = "";
let agentState = null;

function showAgents(agents) {
  const text = agents.map((a) => a.name + ":" + a.state).join(",");
  if (text === shownAgents) return;
  shownAgents = text;
  $("agent").replaceChildren(...agents.map((a) =>
    el("option", { value: a.name, "data-state": a.state }, a.state === "live" ? a.name : `${a.name} (${a.state})`)));
  if (agent) $("agent").value = agent;
}

async function refresh() {
  try {
    const { agents } = await api("/api/agents");
    showAgents(agents);
    const first = agents.find((a) => a.state === "live");
    if (agent === null && first) return choose(first.name);
    const me = agents.find((a) => a.name === agent);
    if (!me) return;
    const before = agentState;
    agentState = me.state;
    if (me.state !== "live") {
      setStatus(`agent ${agent} ${me.state}`, true);
      showModules([]);
      return;
    }
    if (before !== null && before !== "live") return choose(agent);
    showModules(me.modules);
    $("map-section").hidden = !me.map;
    const [events, contexts, logs, plans] = await Promise.all([
      api(agentPath("/events")), api(agentPath("/contexts")), api("/api/logs"), api(agentPath("/plans"))]);
    feed("events", events.events, (e) => `${e.time_s.toFixed(2)}s ${e.module} ${e.kind}: ${e.reason}`);
    $("active").textContent = Object.entries(contexts.active).map(([m, a]) => `${m}: ${a || "(none)"}`).join("; ") || "no context manager";
    feed("switches", contexts.switches, (s) => {
      const c = s.change || {};
      return c.context === undefined ? `${s.module}: ${JSON.stringify(c)}`
        : `${Number(c.time_s).toFixed(2)}s ${s.module}: ${c.context} ${c.active ? "on" : "off"}`;
    });
    $("log").textContent = logs.lines.slice(-200).map((l) =>
      `${new Date(l.unix_ms).toISOString().slice(11, 23)} ${l.level} ${l.target}: ${l.message}`).join("\n");
    if (plans.plans.length) drawPlan(plans.plans[0]);
  } catch (e) {
    setStatus(e.message, true);
  }
}

async function refreshMap() {
  if ($("map-section").hidden) return;
  try {
    const q = gridVersion === null ? "" : "?grid_version=" + gridVersion;
    drawMap(await api(agentPath("/map" + q)));
    drawCamera((await api(agentPath("/camera"))).image);
  } catch (e) {
    setStatus(e.message, true);
  }
}

async function choose(name) {
  agent = name;
  agentState = "live";
  grid = null; gridVersion = null;
  await loadProperties();
  drawGraph(await api(agentPath("/graph")));
  connect();
  await refresh();
}

async function main() {
  try {
    const { agents } = await api("/api/agents");
    showAgents(agents);
    $("agent").addEventListener("change", (e) => choose(e.target.value));
    $("filter").addEventListener("input", applyFilter);
    const first = agents.find((a) => a.state === "live");
    if (first) await choose(first.name);
    else setStatus("waiting for agents…");
    setInterval(refresh, 1000);
    setInterval(refreshMap, 500);
  } catch (e) {
    setStatus(e.message, true);
  }
}

main();
