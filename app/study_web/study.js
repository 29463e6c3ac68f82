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

function drawJaco3D(container, t, color) {
  const w = 300, h = 260;
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setSize(w, h);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  const camera = new THREE.PerspectiveCamera(45, w / h, 0.01, 20);
  camera.up.set(0, 0, 1);
  camera.position.set(1.6, 1.2, 1.3);
  const controls = new OrbitControls(camera, renderer.domElement);  // click and drag to orbit
  controls.target.set(0, -0.3, 0.3);
  controls.update();
  const table = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.MeshBasicMaterial({ color: 0xd8c3a5, side: THREE.DoubleSide }));
  table.position.set(0, -0.4, 0);
  scene.add(table);
  for (const o of t.objects) {
    const box = new THREE.Mesh(new THREE.BoxGeometry(0.34, 0.24, 0.02), new THREE.MeshBasicMaterial({ color: 0x333333 }));
    box.position.set(...o.pos);
    scene.add(box);
  }
  const pts = t.points.map((p) => new THREE.Vector3(...p));
  scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color })));
  const ball = new THREE.Mesh(new THREE.SphereGeometry(0.03), new THREE.MeshBasicMaterial({ color }));
  ball.position.copy(pts[0]);
  scene.add(ball);
  let replayStart = null;
  function frame(now) {
    if (replayStart !== null) {
      const k = Math.min((now - replayStart) / 3000, 1) * (pts.length - 1), i = Math.floor(k);
      ball.position.copy(pts[Math.min(i + 1, pts.length - 1)]).lerp(pts[i], 1 - (k - i));
      if (k >= pts.length - 1) replayStart = null;
    }
    renderer.render(scene, camera);
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
  return () => { replayStart = performance.now(); };
}

function drawJaco2D(canvas, t, color) {  // fallback: top view
  const ctx = canvas.getContext("2d"), sc = canvas.width / 2.2;
  const X = (x) => canvas.width / 2 + x * sc, Y = (y) => canvas.height * 0.25 - y * sc;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  for (const o of t.objects) { ctx.fillStyle = "#333"; ctx.fillRect(X(o.pos[0]) - 17, Y(o.pos[1]) - 12, 34, 24); }
  ctx.strokeStyle = color; ctx.lineWidth = 3; ctx.beginPath();
  t.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
  ctx.stroke();
}

async function showOptions(view, ids) {
  const views = $("views");
  views.innerHTML = "";
  animators.length = 0;
  for (let i = 0; i < ids.length; i++) {
    const t = await trajectory(ids[i]);
    const div = document.createElement("div");
    div.className = "view";
    div.innerHTML = `<div><b>Trajectory ${i + 1}</b></div>`;
    views.appendChild(div);
    if (view === "plane") {
      const c = document.createElement("canvas"); c.width = c.height = 250; div.appendChild(c);
      drawGrid(c, t, COLORS[i]);
    } else if (THREE) {
      const replay = drawJaco3D(div, t, COLORS[i]);
      const b = document.createElement("button");
      b.textContent = "Replay"; b.onclick = replay; div.appendChild(b);
    } else {
      const c = document.createElement("canvas"); c.width = 300; c.height = 260; div.appendChild(c);
      drawJaco2D(c, t, COLORS[i]);
    }
  }
}

function buttons(list) {
  const b = $("buttons");
  b.innerHTML = "";
  return new Promise((resolve) => {
    for (const [label, value] of list) {
      const el = document.createElement("button");
      el.textContent = label;
      el.dataset.answer = value;
      el.onclick = () => resolve(value);
      b.appendChild(el);
    }
  });
}

const SIM_CHOICES = [["1 and 2 are most similar", 2], ["1 and 3 are most similar", 1], ["2 and 3 are most similar", 0]];
const PREF_CHOICES = [["I prefer 1", 1], ["I prefer 2", 0], ["Equally good", 0.5]];

function text(html) { $("text").innerHTML = html; }
function progress(s) {
  $("progress").textContent = `similarity ${s.similarity.done}/${s.similarity.total} · preference ${s.preference.done}/${s.preference.total}`;
}

async function practice(view, list, kind) {
  for (let i = 0; i < list.length; i++) {
    text(`<p class="practice">Practice ${i + 1} of ${list.length} (not recorded): ${kind === "similarity" ? "which two of these three trajectories are most similar?" : "which trajectory do you prefer?"}</p>`);
    await showOptions(view, list[i]);
    await buttons(kind === "similarity" ? SIM_CHOICES : PREF_CHOICES);
  }
}

async function continueButton(label) { await buttons([[label, "go"]]); }

async function run() {
  if (!P || !T) { text("<p>This link is incomplete: it needs ?p=…&t=… from the study organiser.</p>"); return; }
  let s = await api(`/api/state?${q}`);
  progress(s);
  const feats = s.features.join(" and ");
  if (s.stage === "similarity" && s.similarity.done === 0) {
    text(`<h2>Welcome</h2><p>A robot arm carries objects over a table. Each picture shows the path of its hand. People care about how a trajectory relates to: <b>${feats}</b> (${s.features_gloss}).</p><p>First you will see groups of three trajectories and tell us which two are <b>most similar</b>.${s.view === "plane" ? "" : " Drag a 3-D view to turn it; press Replay to watch the motion."} A few practice questions come first.</p>`);
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
