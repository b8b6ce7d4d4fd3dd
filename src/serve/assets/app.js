// BlockPuzzle's page: plain JavaScript against the JSON API of `blockpuzzle serve`.
"use strict";

const $ = (id) => document.getElementById(id);
const el = (tag, attrs = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "onclick") e.addEventListener("click", v);
    else if (k === "text") e.textContent = v;
    else e.setAttribute(k, v);
  }
  for (const k of kids) e.append(k);
  return e;
};
const COLOURS = ["grey", "red", "blue", "green"];

async function api(path, options) {
  const r = await fetch(path, options);
  let body;
  try { body = await r.json(); } catch (e) { body = { error: `${path}: answered ${r.status} without JSON` }; }
  if (!r.ok) throw new Error(body.error || `${path}: ${r.status}`);
  return body;
}

function showError(where, e) {
  where.textContent = String(e.message || e);
  where.className = "status bad";
}

// ---- tabs --------------------------------------------------------------------------------
function openTab(name) {
  for (const b of document.querySelectorAll("#tabs button")) b.classList.toggle("on", b.dataset.tab === name);
  for (const s of document.querySelectorAll("section.tab")) s.classList.toggle("on", s.id === name);
  const load = loaders[name];
  if (load && !load.done) { load.done = true; load(); }
}
document.querySelectorAll("#tabs button").forEach((b) => b.addEventListener("click", () => openTab(b.dataset.tab)));

// ---- stills: one at a time, so the render queue is never flooded ------------------------
const stillQueue = [];
let stillBusy = false;
function still(img, query) {
  stillQueue.push([img, query]);
  pumpStills();
}
async function pumpStills() {
  if (stillBusy) return;
  const next = stillQueue.shift();
  if (!next) return;
  stillBusy = true;
  const [img, query] = next;
  try {
    const r = await fetch(`/api/still?${query}&side=200`);
    if (r.ok) img.src = URL.createObjectURL(await r.blob());
    else img.alt = (await r.json()).error;
  } catch (e) { img.alt = String(e); }
  stillBusy = false;
  pumpStills();
}

// ---- the player --------------------------------------------------------------------------
let playing = null;
async function play(query, label, body) {
  if (playing) playing.abort();
  const ctrl = new AbortController();
  playing = ctrl;
  openTab("watch");
  const status = $("play-status");
  status.className = "status";
  status.textContent = `Starting ${label} ...`;
  $("play-step").textContent = "";
  $("play-outcome").textContent = "";
  const t0 = performance.now();
  const options = body === undefined ? { signal: ctrl.signal } : { method: "POST", body, signal: ctrl.signal };
  let r;
  try { r = await fetch(`/api/play?${query}`, options); } catch (e) { if (e.name !== "AbortError") showError(status, e); return null; }
  if (!r.ok) { showError(status, new Error((await r.json()).error)); return null; }
  const reader = r.body.getReader();
  const decoder = new TextDecoder();
  let buf = "", end = null, objects = [];
  for (;;) {
    let chunk;
    try { chunk = await reader.read(); } catch (e) { if (e.name !== "AbortError") showError(status, e); return null; }
    if (chunk.done) break;
    buf += decoder.decode(chunk.value, { stream: true });
    let nl;
    while ((nl = buf.indexOf("\n")) >= 0) {
      const line = JSON.parse(buf.slice(0, nl));
      buf = buf.slice(nl + 1);
      if (line.image) $("frame").src = line.image;
      if (line.type === "start") {
        objects = line.objects;
        status.textContent = `${line.task}, ${line.policy}, seed ${line.seed}, level ${line.level}` +
          (line.distribution ? ` (${line.distribution})` : "") + ` on MuJoCo ${line.engine}; first frame after ${((performance.now() - t0) / 1000).toFixed(1)} s`;
        const ul = $("play-objects");
        ul.replaceChildren(...objects.map((o) => el("li", { class: o.colour, text: `${o.name}: ${o.absent ? "absent" : o.colour}` })));
      } else if (line.type === "frame") {
        const touching = line.touching.map((p) => p.join("-")).join(", ");
        $("play-step").textContent = `step ${line.step}, reward ${line.reward}` + (touching ? `, touching: ${touching}` : "");
      } else if (line.type === "end") {
        end = line;
        const at = line.decided_at === null ? "" : ` at step ${line.decided_at}`;
        const why = line.contacts.length ? ` (contacts then: ${line.contacts.map((p) => p.join("-")).join(", ")})` : "";
        const o = $("play-outcome");
        o.textContent = `Outcome: ${line.outcome}${at}${why}; ${line.steps} steps, return ${line.return.toFixed(2)}`;
        o.className = `outcome ${line.outcome}`;
      } else if (line.type === "error") {
        showError(status, new Error(line.message));
      }
    }
  }
  if (playing === ctrl) playing = null;
  return end;
}

async function fillPlayer() {
  const [tasks, families, policies, files] = await Promise.all([
    api("/api/tasks"), api("/api/families"), api("/api/policies"), api("/api/files"),
  ]);
  const sel = $("play-task");
  const group = (label, opts) => el("optgroup", { label }, ...opts);
  sel.replaceChildren(
    group("built-in tasks", tasks.map((t) => el("option", { value: `task=${encodeURIComponent(t.id)}`, text: t.id }))),
    group("family draws", families.flatMap((f) => (f.draws || []).map((d) =>
      el("option", { value: `family=${encodeURIComponent(f.name)}&draw=${d.seed}`, text: `${f.name} draw ${d.seed}` })))),
    group("files", files.files.map((f) =>
      el("option", { value: `folder=${f.folder}&path=${encodeURIComponent(f.path)}`, text: f.path }))),
  );
  $("play-policy").replaceChildren(...policies.map((p) => el("option", { value: p, text: p })));
}

$("play-form").addEventListener("submit", (ev) => {
  ev.preventDefault();
  const q = [$("play-task").value, `policy=${encodeURIComponent($("play-policy").value)}`, `seed=${$("play-seed").value || 0}`];
  if ($("play-level").value !== "") q.push(`level=${$("play-level").value}`);
  if ($("play-dist").value !== "") q.push(`distribution=${encodeURIComponent($("play-dist").value)}`);
  play(q.join("&"), $("play-task").selectedOptions[0]?.textContent || "");
});

function watch(query, label) {
  $("play-task").value = query;
  play(`${query}&policy=solver&seed=0`, label);
}

// ---- gallery -----------------------------------------------------------------------------
async function loadGallery() {
  try {
    const tasks = await api("/api/tasks");
    $("task-grid").replaceChildren(...tasks.map((t) => {
      const img = el("img", { alt: t.id, width: 200, height: 200 });
      const q = `task=${encodeURIComponent(t.id)}`;
      still(img, q);
      return el("figure", { class: "card", onclick: () => watch(q, t.id) }, img, el("figcaption", {}, el("b", { text: t.id }), el("br"), t.summary || t.error));
    }));
    const families = await api("/api/families");
    $("family-grid").replaceChildren(...families.map((f) => el("div", { class: "family" },
      el("h3", { text: f.name }), el("p", { text: f.summary || f.error }),
      el("div", { class: "grid" }, ...(f.draws || []).map((d) => {
        const img = el("img", { alt: d.id || d.error, width: 200, height: 200 });
        const q = `family=${encodeURIComponent(f.name)}&draw=${d.seed}`;
        if (!d.error) still(img, q);
        return el("figure", { class: "card", onclick: () => watch(q, d.id) }, img, el("figcaption", { text: d.error || d.summary }));
      })))));
  } catch (e) { showError($("task-grid"), e); }
}

// ---- suites, zoo, leaderboard ------------------------------------------------------------
async function loadSuites() {
  try {
    const suites = await api("/api/suites");
    const rowOf = (s, sp, r, k) => el("tr", {},
      el("td", { text: r.task }), el("td", { text: r.summary }), el("td", { text: r.distribution ?? "" }),
      el("td", { text: r.level ?? "highest" }), el("td", { text: r.seed }), el("td", { text: r.episodes }),
      el("td", {}, el("button", {
        text: "watch",
        onclick: () => play(`suite=${encodeURIComponent(s.name)}&split=${sp.name}&row=${k}&policy=solver`, r.task),
      })));
    const splitOf = (s, sp) => el("div", {},
      el("h4", { text: `${sp.name} (${sp.rows.length} rows)` }),
      el("table", {},
        el("tr", {}, ...["task", "summary", "distribution", "level", "seed", "episodes", ""].map((h) => el("th", { text: h }))),
        ...sp.rows.map((r, k) => rowOf(s, sp, r, k))));
    $("suite-list").replaceChildren(...suites.map((s) => el("details", {},
      el("summary", {}, el("b", { text: s.name }), ` ${s.summary || s.error}`),
      ...(s.splits || []).map((sp) => splitOf(s, sp)))));
  } catch (e) { showError($("suite-list"), e); }
}

async function loadZoo() {
  try {
    const zoo = await api("/api/zoo");
    $("zoo-list").replaceChildren(...zoo.map((z) => el("details", {},
      el("summary", {}, el("b", { text: z.name }), ` ${z.error || z.description}`),
      el("p", { text: z.error ? "" : `trained on ${z.trained_on}; ${z.algo ?? ""}${z.solver ? ` of solver version ${z.solver}` : ""}; observation ${z.obs_mode ?? "flat"}; epoch ${z.epoch}` }),
      el("table", {}, el("tr", {}, ...["task", "distribution", "episodes", "success", "engine"].map((h) => el("th", { text: h }))),
        ...(z.evaluations || []).map((e) => el("tr", {}, el("td", { text: e.env }), el("td", { text: e.distribution }),
          el("td", { text: e.episodes }), el("td", { text: e.success_rate.toFixed(3) }), el("td", { text: e.mujoco ?? "" })))))));
  } catch (e) { showError($("zoo-list"), e); }
}

const fmt = (x) => (x === null || x === undefined ? "" : Number(x).toFixed(3));
function boardTable(board) {
  const cols = [["policy", (r) => r.policy], ["score", (r) => r.score], ["train", (r) => r.train], ["gap", (r) => r.gap], ["rows", (r) => r.rows / r.of]];
  let sortBy = 1, desc = true;
  const table = el("table", { class: "board" });
  const draw = () => {
    const rows = [...board.rows].sort((a, b) => {
      const x = cols[sortBy][1](a), y = cols[sortBy][1](b);
      const c = typeof x === "string" ? x.localeCompare(y) : (x ?? -1) - (y ?? -1);
      return desc ? -c : c;
    });
    table.replaceChildren(
      el("tr", {}, el("th", { text: "#" }), ...cols.map(([name], i) => el("th", { class: "sort", text: name + (i === sortBy ? (desc ? " ▼" : " ▲") : ""), onclick: () => { desc = i === sortBy ? !desc : true; sortBy = i; draw(); } })), el("th", { text: "" })),
      ...rows.map((r, k) => el("tr", {}, el("td", { text: k + 1 }), el("td", { text: r.policy }),
        el("td", { text: `${fmt(r.score)}${r.ci ? ` [${fmt(r.ci[0])}, ${fmt(r.ci[1])}]` : ""}` }), el("td", { text: fmt(r.train) }),
        el("td", { text: fmt(r.gap) }), el("td", { text: `${r.rows}/${r.of}` }),
        el("td", {}, r.failures.length ? el("button", { text: "watch failures", onclick: () => watchFailures(board, r) }) : "no failures"))));
  };
  draw();
  return table;
}

async function watchFailures(board, row) {
  const policies = await api("/api/policies");
  const baseline = { "baseline:scripted": "solver", "baseline:obs-hash": "obs-hash" }[row.policy];
  const label = baseline || policies.find((p) => p === row.policy || p === `zoo: ${row.policy}`);
  if (!label) { showError($("play-status"), new Error(`${row.policy} is not a policy this app was started with (--policy FILE)`)); openTab("watch"); return; }
  const worst = [...row.failures].sort((a, b) => a.successes / a.episodes - b.successes / b.episodes);
  for (const f of worst.slice(0, 5)) {
    for (let k = 0; k < f.episodes; k++) {
      const end = await play(`suite=${encodeURIComponent(board.suite)}&split=${f.split}&row=${f.row}&seed=${f.seed + k}&policy=${encodeURIComponent(label)}`, f.task);
      if (!end || end.outcome !== "success") return;
    }
  }
}

async function loadLeaderboard() {
  try {
    const lb = await api("/api/leaderboard");
    const parts = lb.boards.map((b) => el("div", { class: "board", "data-suite": b.suite, "data-engine": b.engine }, el("h3", { text: `${b.suite} on MuJoCo ${b.engine}` }), boardTable(b)));
    if (!lb.boards.length) parts.push(el("p", { text: `No suite results under ${lb.folders.join(", ") || "(no --results folder)"}.` }));
    for (const e of lb.errors) parts.push(el("p", { class: "status bad", text: e }));
    $("boards").replaceChildren(...parts);
  } catch (e) { showError($("boards"), e); }
}

// ---- files -------------------------------------------------------------------------------
async function loadFiles() {
  try {
    const files = await api("/api/files");
    $("file-list").replaceChildren(el("p", { text: `Folders: ${files.folders.join(", ")}` }),
      el("ul", {}, ...files.files.map((f) => el("li", {}, el("a", { href: "#", text: f.path, onclick: async (ev) => {
        ev.preventDefault();
        try {
          const r = await api(`/api/file?folder=${f.folder}&path=${encodeURIComponent(f.path)}`);
          $("file-view").textContent = (r.check.ok ? `valid ${r.check.kind} ${r.check.id}` : `INVALID: ${r.check.error}`) + "\n\n" + r.text;
        } catch (e) { $("file-view").textContent = String(e.message || e); }
      } })))));
  } catch (e) { showError($("file-list"), e); }
}

// ---- editor ------------------------------------------------------------------------------
const ed = { blocks: [], scene: null, drag: null };
const canvas = $("table");
function toCanvas(x, y) {
  const s = ed.scene;
  const [cx, cy] = s.table_center, [hx, hy] = s.table_half;
  const m = 20, w = canvas.width - 2 * m, h = canvas.height - 2 * m;
  // Screen up is +x (away from the robot); screen right is -y.
  return [m + ((cy + hy - y) / (2 * hy)) * w, m + ((cx + hx - x) / (2 * hx)) * h];
}
function fromCanvas(u, v) {
  const s = ed.scene;
  const [cx, cy] = s.table_center, [hx, hy] = s.table_half;
  const m = 20, w = canvas.width - 2 * m, h = canvas.height - 2 * m;
  return [cx + hx - ((v - m) / h) * 2 * hx, cy + hy - ((u - m) / w) * 2 * hy];
}
const scale = () => (canvas.width - 40) / (2 * ed.scene.table_half[1]);

function drawTable() {
  if (!ed.scene) return;
  const g = canvas.getContext("2d");
  const floor = $("ed-floor").value;
  g.fillStyle = floor === "none" ? "#ddd" : cssColour(floor, 0.35);
  g.fillRect(0, 0, canvas.width, canvas.height);
  g.fillStyle = cssColour($("ed-table").value, 0.6);
  g.fillRect(20, 20, canvas.width - 40, canvas.height - 40);
  const [gu, gv] = toCanvas(...ed.scene.gripper);
  g.strokeStyle = cssColour($("ed-gripper").value, 1);
  g.lineWidth = 3;
  g.beginPath(); g.moveTo(gu - 8, gv - 8); g.lineTo(gu + 8, gv + 8); g.moveTo(gu + 8, gv - 8); g.lineTo(gu - 8, gv + 8); g.stroke();
  for (const b of ed.blocks) {
    const [u, v] = toCanvas(b.x, b.y);
    const r = Math.max(3, b.size * scale());
    if (b.jitter > 0) { g.strokeStyle = "#555"; g.lineWidth = 1; g.beginPath(); g.arc(u, v, b.jitter * scale(), 0, 2 * Math.PI); g.stroke(); }
    g.fillStyle = cssColour(b.colour, 1);
    g.fillRect(u - r, v - r, 2 * r, 2 * r);
    g.fillStyle = "#000";
    g.fillText(b.name, u + r + 2, v);
  }
}
function cssColour(c, a) {
  const rgb = { red: [200, 40, 40], blue: [40, 80, 210], green: [40, 170, 60], grey: [150, 150, 150] }[c] || [150, 150, 150];
  return `rgba(${rgb.join(",")},${a})`;
}

const num = (v) => Number(v).toFixed(3).replace(/\.?0+$/, "") || "0";
function toml() {
  const family = $("ed-kind").value === "family";
  const q = (s) => JSON.stringify(String(s));
  const [cx, cy] = ed.scene.table_center;
  const lines = ["version = 1"];
  if (family) lines.push(`family = ${q($("ed-id").value.replace(/-v\d+$/, ""))}`);
  else lines.push(`id = ${q($("ed-id").value)}`);
  lines.push(`summary = ${q($("ed-summary").value)}`, `max_episode_steps = ${Number($("ed-steps").value)}`);
  const floor = $("ed-floor").value;
  if (family) {
    lines.push(`gripper = [${q($("ed-gripper").value)}]`, `table = [${q($("ed-table").value)}]`, `floor = [${q(floor)}]`, "",
      "[check]", `episodes = ${Number($("ed-check-episodes").value)}`, `min_solver_success = ${Number($("ed-check-success").value)}`,
      `max_candidates = ${Number($("ed-check-candidates").value)}`);
  } else {
    lines.push("", "[robot]", `gripper = ${q($("ed-gripper").value)}`, "", "[table]", `colour = ${q($("ed-table").value)}`);
    if (floor !== "none") lines.push("", "[floor]", `colour = ${q(floor)}`);
  }
  for (const b of ed.blocks) {
    lines.push("", family ? "[[blocks]]" : "[[objects]]", `name = ${q(b.name)}`, `colour = ${q(b.colour)}`);
    if (family) lines.push(`size = [${num(b.size)}, ${num(Math.max(b.size, b.sizeMax))}]`);
    else lines.push(`half_extents = [${num(b.size)}, ${num(b.size)}, ${num(b.size)}]`);
    if (family || b.countMin !== 1 || b.countMax !== 1) lines.push(`count = [${b.countMin}, ${b.countMax}]`);
    const start = [`around = "table"`, `offset = [${num(b.x - cx)}, ${num(b.y - cy)}]`];
    if (b.jitter > 0) start.push(`distance = [0, ${num(b.jitter)}]`, `density = "area"`);
    lines.push(`start = { ${start.join(", ")} }`);
  }
  return lines.join("\n") + "\n";
}

function refresh() {
  document.querySelectorAll(".family-only").forEach((e) => (e.style.display = $("ed-kind").value === "family" ? "" : "none"));
  const tbody = document.querySelector("#ed-blocks tbody");
  tbody.replaceChildren(...ed.blocks.map((b, i) => {
    const input = (key, attrs) => {
      const e = el("input", attrs);
      e.value = b[key];
      e.addEventListener("change", () => { b[key] = attrs.type === "number" ? Number(e.value) : e.value; update(); });
      return e;
    };
    const colour = el("select", {}, ...COLOURS.map((c) => el("option", { text: c })));
    colour.value = b.colour;
    colour.addEventListener("change", () => { b.colour = colour.value; update(); });
    return el("tr", {}, el("td", {}, input("name", { size: 8 })), el("td", {}, colour),
      el("td", {}, input("size", { type: "number", step: "0.005", min: "0.005", max: "0.1" })),
      el("td", { class: "family-only", style: $("ed-kind").value === "family" ? "" : "display:none" }, input("sizeMax", { type: "number", step: "0.005", min: "0.005", max: "0.1" })),
      el("td", {}, input("countMin", { type: "number", min: "0", max: "12" }), input("countMax", { type: "number", min: "0", max: "12" })),
      el("td", {}, input("jitter", { type: "number", step: "0.01", min: "0", max: "0.3" })),
      el("td", {}, el("button", { type: "button", text: "remove", onclick: () => { ed.blocks.splice(i, 1); refresh(); } })));
  }));
  update();
}

let checkTimer = null;
function update() {
  drawTable();
  const text = toml();
  $("ed-toml").value = text;
  clearTimeout(checkTimer);
  checkTimer = setTimeout(() => check(text, 0), 300);
}

async function check(text, samples) {
  const st = $("ed-status");
  try {
    const r = await api(`/api/check?samples=${samples}`, { method: "POST", body: text });
    st.className = r.ok ? "status good" : "status bad";
    st.textContent = r.ok ? `valid ${r.kind} ${r.id}` : `invalid: ${r.error}`;
    $("ed-report").textContent = (r.lines || []).join("\n") + (r.draws ? r.draws.map((d) => `draw ${d.seed}: ${d.error || `${d.id}: ${d.summary}`}`).join("\n") : "");
    return r;
  } catch (e) { showError(st, e); return null; }
}

function addBlock(name, colour, x, y) {
  ed.blocks.push({ name, colour, size: 0.025, sizeMax: 0.03, countMin: 1, countMax: 1, jitter: 0, x, y });
}

async function loadEditor() {
  try {
    ed.scene = await api("/api/scene");
  } catch (e) { showError($("ed-status"), e); return; }
  for (const id of ["ed-gripper", "ed-table"]) $(id).replaceChildren(...COLOURS.map((c) => el("option", { text: c })));
  const [cx, cy] = ed.scene.table_center;
  addBlock("blue", "blue", cx, cy - 0.05);
  addBlock("green", "green", cx + 0.12, cy + 0.08);
  for (const id of ["ed-kind", "ed-id", "ed-steps", "ed-summary", "ed-gripper", "ed-table", "ed-floor", "ed-check-episodes", "ed-check-success", "ed-check-candidates"]) {
    $(id).addEventListener("change", refresh);
  }
  refresh();
}

canvas.addEventListener("mousedown", (ev) => {
  if (!ed.scene) return;
  const [x, y] = fromCanvas(ev.offsetX, ev.offsetY);
  let best = null, bestD = 0.04;
  for (const b of ed.blocks) { const d = Math.hypot(b.x - x, b.y - y); if (d < bestD) { best = b; bestD = d; } }
  ed.drag = best;
});
canvas.addEventListener("mousemove", (ev) => {
  if (!ed.drag) return;
  const [x, y] = fromCanvas(ev.offsetX, ev.offsetY);
  const [cx, cy] = ed.scene.table_center, [hx, hy] = ed.scene.table_half;
  ed.drag.x = Math.min(cx + hx, Math.max(cx - hx, x));
  ed.drag.y = Math.min(cy + hy, Math.max(cy - hy, y));
  drawTable();
});
window.addEventListener("mouseup", () => { if (ed.drag) { ed.drag = null; update(); } });

$("ed-add").addEventListener("click", () => {
  const [cx, cy] = ed.scene.table_center;
  addBlock(`block${ed.blocks.length}`, "grey", cx + 0.1, cy - 0.15);
  refresh();
});
$("ed-check").addEventListener("click", () => check(toml(), 4));
$("ed-play").addEventListener("click", () => play("policy=solver&seed=0&draw=1", "the editor's task", toml()));
$("ed-save").addEventListener("click", async () => {
  const st = $("ed-status");
  try {
    const name = encodeURIComponent($("ed-name").value);
    const r = await api(`/api/save?name=${name}${$("ed-overwrite").checked ? "&overwrite=1" : ""}`, { method: "POST", body: toml() });
    st.className = "status good";
    st.textContent = `saved ${r.saved}`;
  } catch (e) { showError(st, e); }
});

// ---- start -------------------------------------------------------------------------------
const loaders = { gallery: loadGallery, watch: fillPlayer, suites: loadSuites, zoo: loadZoo, leaderboard: loadLeaderboard, editor: loadEditor, files: loadFiles };
api("/api/health").then((h) => { $("engine").textContent = `MuJoCo ${h.engine}`; }).catch((e) => showError($("engine"), e));
loaders.gallery.done = true;
loadGallery();
