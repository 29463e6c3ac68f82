// The study page: instructions, practice and recorded similarity queries, the scenario, practice
// and recorded preference queries. Every recorded answer is POSTed with its response time; the
// server commits it before replying, and a reload resumes at the next unanswered query.
const params = new URLSearchParams(location.search);
const P = params.get("p"), T = params.get("t");
const $ = (id) => document.getElementById(id);
let THREE = null, OrbitControls = null;
try {
  THREE = await import("/vendor/three/build/three.module.js");
  ({ OrbitControls } = await import("/vendor/three/examples/jsm/controls/OrbitControls.js"));
} catch (e) {
  console.warn("three.js unavailable, drawing 2-D projections", e);
}

async function api(path, opts) {
  const r = await fetch(path, opts);
  const body = await r.json().catch(() => ({ error: `HTTP ${r.status}` }));
  if (!r.ok) throw new Error(body.error || `HTTP ${r.status}`);
  return body;
}
const q = `p=${encodeURIComponent(P)}&t=${encodeURIComponent(T)}`;
const trajCache = new Map();
async function trajectory(id) {
  if (!trajCache.has(id)) trajCache.set(id, api(`/api/trajectory?${q}&id=${id}`));
  return trajCache.get(id);
}

const COLORS = ["#1f77b4", "#d62728", "#2ca02c"];
const animators = [];

function drawGrid(canvas, t, color) {
  const ctx = canvas.getContext("2d"), s = canvas.width / 5;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#ddd";
  for (let i = 0; i <= 5; i++) {
    ctx.beginPath(); ctx.moveTo(i * s, 0); ctx.lineTo(i * s, 5 * s); ctx.stroke();
    ctx.beginPath(); ctx.moveTo(0, i * s); ctx.lineTo(5 * s, i * s); ctx.stroke();
  }
  const cx = (x) => (x + 0.5) * s, cy = (y) => (4.5 - y) * s;
  for (const o of t.objects) {
    ctx.fillStyle = o.name === "laptop" ? "#f28e2b" : "#333";
    ctx.fillRect(cx(o.pos[0]) - s / 4, cy(o.pos[1]) - s / 4, s / 2, s / 2);
  }
  ctx.strokeStyle = color; ctx.lineWidth = 4; ctx.beginPath();
  t.points.forEach(([x, y], i) => (i ? ctx.lineTo(cx(x), cy(y)) : ctx.moveTo(cx(x), cy(y))));
  ctx.stroke();
  const [ex, ey] = t.points[t.points.length - 1], a = (t.angle * Math.PI) / 180;
  ctx.beginPath(); ctx.moveTo(cx(ex), cy(ey)); ctx.lineTo(cx(ex) + Math.cos(a) * s * 0.6, cy(ey) - Math.sin(a) * s * 0.6);
  ctx.stroke();
}

// The arm views share one camera: every panel renders the same viewpoint, so a participant
// compares the trajectories as seen from one place. Orbiting any panel moves them all; the view
// buttons put the camera at fixed top and side views (or back to the default).
const VIEWS = {
  default: { pos: [2.0, 1.5, 1.55], target: [0, -0.3, 0.35] },
  top: { pos: [0.0, -0.3001, 2.4], target: [0, -0.3, 0.0] },
  side: { pos: [2.3, -0.3, 0.45], target: [0, -0.3, 0.35] },
};
const shared = { camera: null, panels: [], loop: false };

function panelSize() {  // three panels side by side on a laptop screen
  const w = Math.max(220, Math.min(340, Math.floor((window.innerWidth - 90) / 3)));
  return [w, Math.round(w * 0.85)];
}

function sharedCamera() {
  if (!shared.camera) {
    const [w, h] = panelSize();
    shared.camera = new THREE.PerspectiveCamera(45, w / h, 0.01, 20);
    shared.camera.up.set(0, 0, 1);
    setView("default");
  }
  return shared.camera;
}

function setView(name) {
  const v = VIEWS[name], cam = shared.camera;
  cam.position.set(...v.pos);
  for (const p of shared.panels) { p.controls.target.set(...v.target); p.controls.update(); }
  cam.lookAt(...v.target);
  shared.view = name;
}

// One link of the arm: a cylinder from a to b (re-posed every frame of a replay).
function poseLink(mesh, a, b) {
  const dir = new THREE.Vector3().subVectors(b, a), len = dir.length();
  mesh.visible = len > 1e-4;
  if (!mesh.visible) return;
  mesh.position.copy(a).addScaledVector(dir, 0.5);
  mesh.scale.set(1, len, 1);
  mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir.normalize());
}

function drawJaco3D(container, t, color) {
  const [w, h] = panelSize();
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setSize(w, h);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  scene.add(new THREE.AmbientLight(0xffffff, 0.7));
  const sun = new THREE.DirectionalLight(0xffffff, 0.8);
  sun.position.set(1, 1, 2);
  scene.add(sun);
  const camera = sharedCamera();
  const controls = new OrbitControls(camera, renderer.domElement);  // drag to orbit: all panels
  controls.target.set(...VIEWS[shared.view || "default"].target);
  controls.addEventListener("change", () => { shared.view = "free"; });
  const table = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.MeshLambertMaterial({ color: 0xd8c3a5, side: THREE.DoubleSide }));
  table.position.set(0, -0.4, 0);
  scene.add(table);
  for (const o of t.objects) {
    const box = new THREE.Mesh(new THREE.BoxGeometry(0.34, 0.24, 0.02), new THREE.MeshLambertMaterial({ color: 0x333333 }));
    box.position.set(...o.pos);
    scene.add(box);
  }
  const pts = t.points.map((p) => new THREE.Vector3(...p));
  scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color })));
  const ball = new THREE.Mesh(new THREE.SphereGeometry(0.03), new THREE.MeshBasicMaterial({ color }));
  ball.position.copy(pts[0]);
  scene.add(ball);
  // The arm: its base and links as the server's forward kinematics posed them per waypoint.
  const poses = (t.arm || []).map((pose) => pose.map((q) => new THREE.Vector3(...q)));
  const links = [], joints = [];
  if (poses.length) {
    const linkMat = new THREE.MeshLambertMaterial({ color: 0x8a8f98 });
    const jointMat = new THREE.MeshLambertMaterial({ color: 0x3b3f46 });
    for (let j = 1; j < poses[0].length; j++) {
      const m = new THREE.Mesh(new THREE.CylinderGeometry(0.035, 0.035, 1, 12), linkMat);
      scene.add(m); links.push(m);
    }
    for (let j = 0; j < poses[0].length; j++) {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.045, 12, 8), jointMat);
      scene.add(m); joints.push(m);
    }
  }
  function poseArm(k) {  // k ∈ [0, waypoints − 1], fractional between waypoints
    if (!poses.length) return;
    const i = Math.min(Math.floor(k), poses.length - 1), i1 = Math.min(i + 1, poses.length - 1), f = k - i;
    const at = poses[i].map((p, j) => p.clone().lerp(poses[i1][j], f));
    at.forEach((p, j) => joints[j].position.copy(p));
    for (let j = 1; j < at.length; j++) poseLink(links[j - 1], at[j - 1], at[j]);
  }
  poseArm(0);
  const panel = { renderer, scene, controls, links, replayStart: null };
  panel.frame = (now) => {
    if (panel.replayStart !== null) {
      // rAF's time stamp is the frame's start, which may precede the click's performance.now()
      const k = Math.min(Math.max(now - panel.replayStart, 0) / 3000, 1) * (pts.length - 1), i = Math.floor(k);
      ball.position.copy(pts[Math.min(i + 1, pts.length - 1)]).lerp(pts[i], 1 - (k - i));
      poseArm(k);
      if (k >= pts.length - 1) panel.replayStart = null;
    }
    renderer.render(scene, camera);
  };
  shared.panels.push(panel);
  if (!shared.loop) {
    shared.loop = true;
    const loop = (now) => { for (const p of shared.panels) p.frame(now); requestAnimationFrame(loop); };
    requestAnimationFrame(loop);
  }
  return () => { panel.replayStart = performance.now(); };
}

function replayAll() {
  const now = performance.now();
  for (const p of shared.panels) p.replayStart = now;
}

for (const v of ["default", "top", "side"]) $(`view-${v}`).onclick = () => shared.camera && setView(v);
$("replay-all").onclick = replayAll;

// Tests and curious users: the shared camera and what each panel draws.
window.__study = {
  camera: () => (shared.camera ? shared.camera.position.toArray() : null),
  view: () => shared.view,
  panels: () => shared.panels.map((p) => ({ links: p.links.length })),
};

function drawJaco2D(canvas, t, color) {  // fallback: top view
  const ctx = canvas.getContext("2d"), sc = canvas.width / 2.2;
  const X = (x) => canvas.width / 2 + x * sc, Y = (y) => canvas.height * 0.25 - y * sc;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  for (const o of t.objects) { ctx.fillStyle = "#333"; ctx.fillRect(X(o.pos[0]) - 17, Y(o.pos[1]) - 12, 34, 24); }
  ctx.strokeStyle = color; ctx.lineWidth = 3; ctx.beginPath();
  t.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
  ctx.stroke();
}

// Text from the server shown as text, never as markup.
const esc = (v) => String(v).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

// A path of 2-D points in the environment's own units (view "path"), drawn to fit `box` (the
// bounds of every trajectory shown together, so the panels share one scale); a dot marks its start.
function drawPath(canvas, t, color, box) {
  const ctx = canvas.getContext("2d"), pad = 12;
  const w = Math.max(box.x1 - box.x0, 1e-9), h = Math.max(box.y1 - box.y0, 1e-9);
  const sc = Math.min((canvas.width - 2 * pad) / w, (canvas.height - 2 * pad) / h);
  const X = (x) => pad + (x - box.x0) * sc, Y = (y) => canvas.height - pad - (y - box.y0) * sc;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = color; ctx.lineWidth = 3; ctx.beginPath();
  t.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
  ctx.stroke();
  if (t.points.length) {
    ctx.fillStyle = "#333"; ctx.beginPath();
    ctx.arc(X(t.points[0][0]), Y(t.points[0][1]), 4, 0, 2 * Math.PI); ctx.fill();
  }
}

function pathBox(ts) {
  const pts = ts.flatMap((t) => t.points);
  const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
  return { x0: Math.min(...xs), x1: Math.max(...xs), y0: Math.min(...ys), y1: Math.max(...ys) };
}

async function showOptions(view, ids) {
  const views = $("views");
  views.innerHTML = "";
  animators.length = 0;
  for (const p of shared.panels) { p.controls.dispose(); p.renderer.dispose(); }
  shared.panels.length = 0;
  const arm = view === "arm" && THREE;
  $("viewbar").hidden = !arm;
  const all = [];
  for (const id of ids) all.push(await trajectory(id));
  const box = view === "path" ? pathBox(all) : null;
  for (let i = 0; i < ids.length; i++) {
    const t = all[i];
    const div = document.createElement("div");
    div.className = "view";
    div.innerHTML = `<div><b>Trajectory ${i + 1}</b></div>`;
    views.appendChild(div);
    if (view === "plane") {
      const c = document.createElement("canvas"); c.width = c.height = 250; div.appendChild(c);
      drawGrid(c, t, COLORS[i]);
    } else if (view === "path") {
      const c = document.createElement("canvas"); c.width = c.height = 250; div.appendChild(c);
      drawPath(c, t, COLORS[i], box);
    } else if (THREE) {
      const replay = drawJaco3D(div, t, COLORS[i]);
      const b = document.createElement("button");
      b.textContent = "Replay"; b.onclick = replay; div.appendChild(b);
      animators.push(replay);
    } else {
      const c = document.createElement("canvas"); c.width = 300; c.height = 260; div.appendChild(c);
      drawJaco2D(c, t, COLORS[i]);
    }
  }
}

// Answer buttons, each with a key: [label, value, key]. The promise resolves with the value of
// the button clicked or the key pressed (keys of other controls — r, t, s, f — are not answers).
let keyHandler = null;
function buttons(list) {
  const b = $("buttons");
  b.innerHTML = "";
  return new Promise((resolve) => {
    // The buttons go at once: no second answer while this one is saved and the next loads.
    const done = (value) => { keyHandler = null; b.innerHTML = ""; resolve(value); };
    for (const [label, value, key] of list) {
      const el = document.createElement("button");
      el.innerHTML = `${label} <kbd>${key === "Enter" ? "↵" : key}</kbd>`;
      el.dataset.answer = value;
      el.dataset.key = key;
      el.onclick = () => done(value);
      b.appendChild(el);
    }
    keyHandler = (e) => {
      const hit = list.find(([, , key]) => key === e.key);
      if (hit) { e.preventDefault(); done(hit[1]); }
    };
  });
}
document.addEventListener("keydown", (e) => {
  if (e.target && e.target.tagName === "INPUT") return;
  if (e.key === "r" && shared.panels.length) return replayAll();
  const views = { t: "top", s: "side", f: "default" };
  if (views[e.key] && shared.panels.length) return setView(views[e.key]);
  if (keyHandler) keyHandler(e);
});

const SIM_CHOICES = [["1 and 2 are most similar", 2, "1"], ["1 and 3 are most similar", 1, "2"], ["2 and 3 are most similar", 0, "3"]];
const PREF_CHOICES = [["I prefer 1", 1, "1"], ["I prefer 2", 0, "2"], ["Equally good", 0.5, "0"]];

function text(html) { $("text").innerHTML = html; }
function progress(s) {
  const done = s.similarity.done + s.preference.done, total = s.similarity.total + s.preference.total;
  $("progress").textContent = `similarity ${s.similarity.done}/${s.similarity.total} · preference ${s.preference.done}/${s.preference.total}`;
  $("bar").max = total;
  $("bar").value = done;
  $("bar").title = `${done} of ${total} questions answered`;
}

async function practice(view, list, kind) {
  for (let i = 0; i < list.length; i++) {
    text(`<p class="practice">Practice ${i + 1} of ${list.length} (not recorded): ${kind === "similarity" ? "which two of these three trajectories are most similar?" : "which trajectory do you prefer?"}</p>`);
    await showOptions(view, list[i]);
    await buttons(kind === "similarity" ? SIM_CHOICES : PREF_CHOICES);
  }
}

async function continueButton(label) { await buttons([[label, "go", "Enter"]]); }

async function run() {
  if (!P || !T) { text("<p>This link is incomplete: it needs ?p=…&t=… from the study organiser.</p>"); return; }
  let s = await api(`/api/state?${q}`);
  progress(s);
  const feats = s.features.join(" and ");
  if (s.stage === "similarity" && s.similarity.done === 0) {
    const scene = s.view === "path"
      ? `Each picture shows one trajectory of ${esc(s.title)}, seen from above; the dot marks where it starts.`
      : "A robot arm carries objects over a table. Each picture shows the path of its hand.";
    text(`<h2>Welcome</h2><p>${scene} People care about how a trajectory relates to: <b>${feats}</b> (${s.features_gloss}).</p><p>First you will see groups of three trajectories and tell us which two are <b>most similar</b>.${s.view === "arm" ? " All three views share one camera: drag any of them to turn it, or pick the top or side view (keys t, s; f for the default). Replay (key r) shows the arm moving." : ""} Answer with the buttons or the keys shown on them. A few practice questions come first.</p>`);
    $("views").innerHTML = "";
    await continueButton("Start practice");
    await practice(s.view, s.practice.similarity, "similarity");
    text("<p>Practice done. Now the recorded questions.</p>");
    await continueButton("Begin");
  }
  let scenarioShown = s.preference.done > 0;  // resumed inside phase 2: already seen
  while (s.stage !== "done") {
    if (s.stage === "preference" && !scenarioShown) {
      text(`<h2>Your scenario</h2><p>${s.scenario}</p><p>Now you will see two trajectories at a time: pick the one you prefer in this scenario. A few practice questions come first.</p>`);
      $("views").innerHTML = "";
      await continueButton("Start practice");
      await practice(s.view, s.practice.preference, "preference");
      text("<p>Practice done. Now the recorded questions.</p>");
      await continueButton("Begin");
      scenarioShown = true;
    }
    const n = s.next;
    text(n.kind === "similarity"
      ? `<p>Question ${n.index + 1} of ${s.similarity.total}: which two of these three trajectories are <b>most similar</b>?</p>`
      : `<p>Question ${n.index + 1} of ${s.preference.total} — ${s.scenario} Which trajectory do you prefer?</p>`);
    await showOptions(s.view, n.trajectories);
    const shown = performance.now();
    const answer = await buttons(n.kind === "similarity" ? SIM_CHOICES : PREF_CHOICES);
    const body = new URLSearchParams({ p: P, t: T, kind: n.kind, index: n.index, answer, response_ms: Math.round(performance.now() - shown) });
    try {
      s = await api("/api/answer", { method: "POST", body });
      $("status").textContent = "";
    } catch (e) {
      $("status").textContent = `Not saved: ${e.message}. Reloading the current question…`;
      s = await api(`/api/state?${q}`);
    }
    progress(s);
  }
  $("views").innerHTML = "";
  $("buttons").innerHTML = "";
  text("<h2>Thank you!</h2><p>All your answers are saved. You can close this page.</p>");
}
run().catch((e) => { $("status").textContent = e.message; });
