// autobones landmarks HEAD --edit: place, move and check the contract's landmarks on a head (issue #35).
// The server (autobones/view/editor_server.py) serves this page, the mesh and JSON under api/, all under
// /TOKEN/: every URL here is relative, so each request carries the token. The page only places points;
// every check, mirror proposal, assisted proposal and file written is the server's (one implementation,
// the package's own). Coordinates sent and received are the mesh's own frame and units; the scene draws
// the mesh shifted by `center` (float32 keeps its precision near the head) and adds it back.
// window.autobonesEditor is a small hook for scripts and tests.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const hook = window.autobonesEditor = { ready: false, error: null };
const $ = (sel, root = document) => root.querySelector(sel);
const el = (tag, attrs = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? '' : v);
  }
  for (const kid of kids) if (kid !== null && kid !== undefined) e.append(kid);
  return e;
};
// the --preview picture's colours (autobones/landmarks/preview.py COLORS): midline red, left blue, right green
const COLOURS = { mid: 0xdc1e1e, l: 0x1478e6, r: 0x14a03c };
const CSS = { mid: '#dc1e1e', l: '#1478e6', r: '#14a03c' };

let pending = 0;  // requests in flight: tests wait for none (hook.idle)
async function call(url, body) {
  pending++;
  try {
    const r = await fetch(url, body === undefined ? {} : {
      method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
    const isJSON = (r.headers.get('Content-Type') || '').startsWith('application/json');
    const out = isJSON ? await r.json() : await r.arrayBuffer();
    if (!r.ok) throw new Error((out && out.error) || `${url}: ${r.status}`);
    return out;
  } finally { pending--; }
}

function setStatus(text) { $('#status').textContent = text; }

// ---------------------------------------------------------------- the landmarks and their history

// name -> { p: [x, y, z] (mesh frame), kind: 'placed' | 'mirror' | 'assist', conf: number | null,
//          by: 'detector' | 'fit' (an assisted proposal's source) }
// 'mirror' and 'assist' are proposals: drawn hollow, not checked or saved until accepted (moved or accepted)
let marks = new Map();
const undoStack = [], redoStack = [];
const snapshot = () => JSON.stringify([...marks]);
let unsaved = false;  // the page asks before it is closed with edits not saved
function change(fn) {  // every edit: one undo step
  unsaved = true;
  undoStack.push(snapshot());
  redoStack.length = 0;
  fn();
  refresh();
}
function undo() { if (undoStack.length) { unsaved = true; redoStack.push(snapshot()); marks = new Map(JSON.parse(undoStack.pop())); refresh(); } }
function redo() { if (redoStack.length) { unsaved = true; undoStack.push(snapshot()); marks = new Map(JSON.parse(redoStack.pop())); refresh(); } }
const accepted = () => Object.fromEntries([...marks].filter(([, m]) => m.kind === 'placed').map(([n, m]) => [n, m.p]));

let facts = null, names = [], selected = null, problems = { names: {}, set: [] }, assistOffered = false;
let scene3d = null;  // { markers, redraw, ... } once the view is built
let refresh = () => {};

async function main() {
  facts = await call('api/editor');
  names = facts.groups.flatMap((g) => g.names.map((n) => n.name));
  $('#crumb').textContent = `${facts.head} → ${facts.output}${facts.pp_output ? ' and ' + facts.pp_output : ''}`;
  setStatus('loading the mesh…');
  const buf = await call('api/mesh');
  for (const [n, p] of Object.entries(facts.start)) marks.set(n, { p, kind: 'placed', conf: facts.confidence[n] ?? null });
  const view = el('div', { id: 'view' }, el('div', { class: 'hint', text:
    'click the surface to place the selected name · drag a point to move it · drag elsewhere to turn, wheel to zoom' }));
  const side = el('div', { id: 'names' });
  $('#main').replaceChildren(el('div', { class: 'edit-layout' }, view, side));
  scene3d = buildScene(view, buf);
  buildList(side);
  refresh = () => { scene3d.update(); updateList(); check(); };
  select(names.find((n) => !marks.has(n)) || names[0]);
  refresh();
  window.addEventListener('beforeunload', (e) => { if (unsaved && !hook.done) { e.preventDefault(); e.returnValue = ''; } });
  document.addEventListener('keydown', (e) => {
    if (!(e.ctrlKey || e.metaKey)) return;
    const k = e.key.toLowerCase();
    if (k === 'z' && !e.shiftKey) { e.preventDefault(); undo(); }
    else if ((k === 'z' && e.shiftKey) || k === 'y') { e.preventDefault(); redo(); }
  });
  if (assistReady()) await proposeRest();  // started from the five (--assist PARTIAL, --from): offered once at once
  hook.ready = true;
}

main().catch((err) => {
  hook.error = String(err && err.message || err);
  setStatus('error');
  $('#main').replaceChildren(el('div', { class: 'error', text: hook.error }));
  console.error(err);
});

// ---------------------------------------------------------------- checks, proposals, saving (the server's)

let checkSeq = 0;
async function check() {
  const seq = ++checkSeq;
  try {
    const out = await call('api/check', { landmarks: accepted() });
    if (seq !== checkSeq) return;  // a newer edit's answer is on its way
    problems = out;
    updateList();
  } catch (err) { showError(err); }
}

async function proposeMirror(name) {
  const m = marks.get(name);
  if (!m || !/_[lr]$/.test(name)) return;
  try {
    const out = await call('api/mirror', { name, point: m.p });
    if (!marks.has(out.name)) { marks.set(out.name, { p: out.point, kind: 'mirror', conf: null }); refresh(); }
  } catch (err) { showError(err); }
}

function assistReady() {
  return !facts.assist_error && facts.assist_needs.every((n) => marks.has(n) && marks.get(n).kind === 'placed');
}

async function proposeRest() {
  assistOffered = true;
  try {
    const out = await call('api/assist', { landmarks: accepted() });
    const detected = new Set(out.detected || []);
    let added = 0, found = 0;
    for (const [n, p] of Object.entries(out.points)) {
      if (!marks.has(n) || marks.get(n).kind !== 'placed') {
        const by = detected.has(n) ? 'detector' : 'fit';
        marks.set(n, { p, kind: 'assist', conf: out.confidence[n] ?? null, by });
        added++; found += by === 'detector';
      }
    }
    const source = found ? ` (${found} by the face detector, the rest by the generic head's fit)` : ' by the generic head\'s fit';
    if (added) $('#note').textContent = `${added} names proposed${source}: hollow until accepted or moved`;
    refresh();
  } catch (err) { $('#note').textContent = `no proposals: ${err.message}`; }
}

async function save() {
  try {
    const out = await call('api/save', { landmarks: accepted() });
    $('#saved').textContent = `saved ${out.written.join(' and ')} (${Object.keys(accepted()).length} landmarks)`;
    hook.saved = out.written;
    unsaved = false;
  } catch (err) { showError(err); }
}

async function done() {
  try {
    await call('api/done', {});
    hook.done = true;
    $('#main').replaceChildren(el('div', { class: 'error', style: 'color:#333', text:
      `done${hook.saved ? ': saved ' + hook.saved.join(' and ') : ', nothing saved'}. You can close this tab.` }));
    setStatus('done');
  } catch (err) { showError(err); }
}

function showError(err) { $('#saved').textContent = ''; $('#note').textContent = String(err.message || err); }

// ---------------------------------------------------------------- the name list

const rows = new Map();
function buildList(side) {
  const button = (id, text, onclick, title) => el('button', { id, text, onclick, title });
  side.append(
    el('div', { id: 'toolbar' },
      button('undo', 'undo', undo, 'Ctrl+Z'), button('redo', 'redo', redo, 'Ctrl+Shift+Z'),
      button('assist', 'propose the rest', proposeRest, facts.assist_error || `from ${facts.assist_needs.join(', ')}`),
      button('accept-all', 'accept proposals', () => change(() => { for (const m of marks.values()) m.kind = 'placed'; })),
      button('remove', 'remove selected', () => selected && marks.has(selected) && change(() => marks.delete(selected))),
      button('save', 'save', save, `write ${facts.output}`), button('done', 'done', done, 'stop the editor')),
    el('div', { id: 'note', text: facts.note || '' }), el('div', { id: 'saved' }), el('div', { id: 'set-problems' }));
  for (const g of facts.groups) {
    side.append(el('h3', { text: g.name }));
    for (const n of g.names) {
      const state = el('div', { class: 'state' }), problem = el('div', { class: 'problem' });
      const accept = el('button', { class: 'accept', text: 'accept', hidden: true, onclick: (e) => {
        e.stopPropagation(); change(() => { marks.get(n.name).kind = 'placed'; }); } });
      const row = el('div', { class: 'lm', 'data-name': n.name, title: n.where, onclick: () => select(n.name) },
        el('img', { loading: 'lazy', alt: '', src: 'api/picture?name=' + encodeURIComponent(n.name) }),
        el('div', { class: 'name' }, el('span', { class: 'dot', style: `background:${CSS[n.side]}` }), n.name, accept),
        el('div', {}, state, el('div', { class: 'where', text: n.where })), problem);
      rows.set(n.name, { row, state, problem, accept });
      side.append(row);
    }
  }
}

function select(name) {
  selected = name;
  for (const [n, r] of rows) r.row.classList.toggle('selected', n === name);
  if (rows.has(name)) rows.get(name).row.scrollIntoView({ block: 'nearest' });
  if (scene3d) scene3d.update();
}

function updateList() {
  for (const [n, r] of rows) {
    const m = marks.get(n);
    const conf = m && m.conf !== null && m.conf !== undefined ? ` (confidence ${m.conf.toFixed(2)})` : '';
    r.state.textContent = !m ? 'not placed' : m.kind === 'placed' ? 'placed' + conf
      : (m.kind === 'mirror' ? 'proposed by symmetry' : m.by === 'detector' ? 'proposed by the face detector'
        : 'proposed by the fit') + conf;
    r.accept.hidden = !m || m.kind === 'placed';
    const probs = (m && m.kind === 'placed' && problems.names[n]) || [];
    r.problem.textContent = probs.join('; ');
    r.row.classList.toggle('has-problem', probs.length > 0);
  }
  $('#set-problems').replaceChildren(...problems.set.map((t) => el('div', { class: 'problem', text: t })));
  const placed = Object.keys(accepted()).length, proposed = marks.size - placed;
  setStatus(`${placed} placed${proposed ? `, ${proposed} proposed` : ''} of ${names.length}`);
  $('#assist').disabled = !assistReady();
}

// ---------------------------------------------------------------- the 3-D view

function buildScene(view, buf) {
  const v = makeView(view, buf);
  const markers = makeMarkers(v);
  const pick = makePicking(v, markers.group);
  listenPointer(v, pick, markers);
  let frames = 0;
  v.renderer.setAnimationLoop(() => {
    if (!v.dirty) return;
    v.dirty = false;
    markers.face(v.camera);
    v.renderer.render(v.scene, v.camera);
    frames++;
  });
  Object.assign(hook, {
    frames: () => frames,
    project(p) {  // a mesh-frame point -> client pixel [x, y] with the page's camera
      v.camera.updateMatrixWorld();
      const q = new THREE.Vector3(p[0] - v.c[0], p[1] - v.c[1], p[2] - v.c[2]).project(v.camera);
      const r = v.canvas.getBoundingClientRect();
      return [r.left + (q.x + 1) / 2 * r.width, r.top + (1 - q.y) / 2 * r.height];
    },
    surfaceAt: pick.surfaceAt,
  });
  return { update: markers.update, redraw: v.redraw };
}

// the mesh (drawn shifted by facts.center), renderer, lights, camera and orbit controls
function makeView(view, buf) {
  const nv = facts.vertices, nf = facts.triangles;
  const c = facts.center, size = facts.size || 1;
  const geom = new THREE.BufferGeometry();
  geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(buf, 0, 3 * nv), 3));
  geom.setIndex(new THREE.BufferAttribute(new Uint32Array(buf, 12 * nv, 3 * nf), 1));
  geom.computeVertexNormals();
  const mesh = new THREE.Mesh(geom, new THREE.MeshStandardMaterial({ color: 0xd8d2cc, roughness: 0.8, side: THREE.DoubleSide }));
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.prepend(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef1f4);
  scene.add(mesh, new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.4));
  const up = new THREE.Vector3(...facts.up), front = new THREE.Vector3(...facts.front);
  const camera = new THREE.PerspectiveCamera(30, 1, size * 0.01, size * 100);
  camera.up.copy(up);
  // three quarters from the subject's left, a little from above: the face and one ear at once
  const side = new THREE.Vector3().crossVectors(up, front);
  camera.position.copy(front).multiplyScalar(size * 2.4).addScaledVector(side, size * 0.9).addScaledVector(up, size * 0.3);
  const light = new THREE.DirectionalLight(0xffffff, 1.3);
  light.position.set(0.3, 0.6, 1);
  camera.add(light);
  scene.add(camera);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(0, 0, 0);
  controls.update();
  const v = { mesh, renderer, scene, camera, controls, c, size, canvas: renderer.domElement, dirty: true };
  v.redraw = () => { v.dirty = true; };
  controls.addEventListener('change', v.redraw);
  new ResizeObserver(() => {
    const w = view.clientWidth || 1, h = view.clientHeight || 1;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    v.redraw();
  }).observe(view);
  return v;
}

// markers: a filled ball per placed name, a ring (hollow) per proposal, the selected one larger. A ring
// is turned to the camera, and every marker lifted off the skin toward it (a ball half sunk in the skin
// reads poorly), so the surface hides a marker only from behind
function makeMarkers(v) {
  const group = new THREE.Group();
  v.scene.add(group);
  const ball = new THREE.SphereGeometry(v.size * 0.009, 14, 10);
  const ring = new THREE.RingGeometry(v.size * 0.008, v.size * 0.013, 24);
  const mats = {};
  const material = (side) => mats[side] ||= new THREE.MeshBasicMaterial({ color: COLOURS[side], side: THREE.DoubleSide });
  const sideOf = (n) => /_l$/.test(n) ? 'l' : /_r$/.test(n) ? 'r' : 'mid';
  function update() {
    group.clear();
    for (const [n, m] of marks) {
      const s = new THREE.Mesh(m.kind === 'placed' ? ball : ring, material(sideOf(n)));
      s.position.set(m.p[0] - v.c[0], m.p[1] - v.c[1], m.p[2] - v.c[2]);
      s.userData.at = s.position.clone();
      s.name = n;
      if (n === selected) s.scale.setScalar(1.6);
      group.add(s);
    }
    v.redraw();
  }
  function face(camera) {
    for (const o of group.children) {
      const hollow = o.geometry === ring;
      if (hollow) o.quaternion.copy(camera.quaternion);
      o.position.copy(camera.position).sub(o.userData.at).setLength(v.size * (hollow ? 0.015 : 0.006)).add(o.userData.at);
    }
  }
  return { group, update, face };
}

function makePicking(v, group) {
  const ray = new THREE.Raycaster();
  const ndc = new THREE.Vector2();
  function aim(x, y) {  // client pixel -> the ray through it; false off the canvas
    const r = v.canvas.getBoundingClientRect();
    if (x < r.left || x >= r.right || y < r.top || y >= r.bottom) return false;
    ndc.set(((x - r.left) / r.width) * 2 - 1, -((y - r.top) / r.height) * 2 + 1);
    ray.setFromCamera(ndc, v.camera);
    return true;
  }
  return {
    surfaceAt(x, y) {  // the mesh point under a client pixel, mesh frame, or null
      const hit = aim(x, y) && ray.intersectObject(v.mesh, false)[0];
      return hit ? [hit.point.x + v.c[0], hit.point.y + v.c[1], hit.point.z + v.c[2]] : null;
    },
    markerAt(x, y) {
      const hit = aim(x, y) && ray.intersectObjects(group.children, false)[0];
      return hit ? hit.object.name : null;
    },
  };
}

// pointer: on a marker, drag it along the surface (orbit off meanwhile); a click on a marker without
// movement selects its name, or places the selected name there when it is that marker's (accepting a
// proposal where it is clicked); elsewhere, a click places the selected name, a drag turns the view
function listenPointer(v, pick, markers) {
  let drag = null, down = null;
  const canvas = v.canvas;
  canvas.addEventListener('pointerdown', (e) => {  // capture: runs before the orbit controls see the event
    if (e.button !== 0) return;
    const name = pick.markerAt(e.clientX, e.clientY);
    if (name) {
      v.controls.enabled = false;
      drag = { name, before: snapshot(), moved: false, x: e.clientX, y: e.clientY, was: selected };
      canvas.setPointerCapture(e.pointerId);
    } else down = { x: e.clientX, y: e.clientY };
  }, { capture: true });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag || (!drag.moved && Math.hypot(e.clientX - drag.x, e.clientY - drag.y) <= 3)) return;
    if (!drag.moved) select(drag.name);
    const p = pick.surfaceAt(e.clientX, e.clientY);
    if (!p) return;
    const m = marks.get(drag.name);
    m.p = p; m.kind = 'placed'; m.conf = null;
    drag.moved = true;
    markers.update();
  });
  canvas.addEventListener('pointerup', (e) => {
    if (drag) {
      const d = drag;
      drag = null;
      v.controls.enabled = true;
      if (d.moved) { unsaved = true; undoStack.push(d.before); redoStack.length = 0; refresh(); return; }
      const p = d.name === d.was ? pick.surfaceAt(e.clientX, e.clientY) : null;
      if (p) place(d.name, p); else select(d.name);
      return;
    }
    const click = down && Math.hypot(e.clientX - down.x, e.clientY - down.y) <= 4;
    down = null;
    const p = click && selected ? pick.surfaceAt(e.clientX, e.clientY) : null;
    if (p) place(selected, p);
  });
}

function place(name, p) {
  const bilateral = /_[lr]$/.test(name);
  change(() => marks.set(name, { p, kind: 'placed', conf: null }));
  // the next name not placed, in list order, is selected: one click per name down the list
  const next = names.slice(names.indexOf(name) + 1).concat(names).find((n) => !marks.has(n) || marks.get(n).kind !== 'placed');
  if (next) select(next);
  const partner = bilateral ? name.replace(/_([lr])$/, (_, s) => (s === 'l' ? '_r' : '_l')) : null;
  if (partner && !marks.has(partner)) proposeMirror(name);
  if (!assistOffered && assistReady()) proposeRest();  // once, automatically; the button does it again
}

Object.assign(hook, {
  state: () => Object.fromEntries([...marks].map(([n, m]) => [n, { ...m }])),
  problems: () => problems,
  select: (name) => select(name),
  selected: () => selected,
  idle: () => pending === 0,
  undo, redo, save, done,
});
