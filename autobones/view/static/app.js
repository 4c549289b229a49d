// autobones view: one rig (orbit, pose, weights, expressions) or a batch folder (thumbnails + report).
// The server (autobones/view/server.py) serves this page, the rig files under files/ and JSON under api/,
// all under /TOKEN/: every URL here is relative to the page, so each request carries the token.
// window.autobonesViewer is a small hook for scripts and tests: state, sliders, skinned positions.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const hook = window.autobonesViewer = { ready: false, error: null, mode: null };
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
const fileURL = (rel) => 'files/' + rel.split('/').map(encodeURIComponent).join('/');
const fmt = (x, d = 3) => (x === null || x === undefined || Number.isNaN(x)) ? '–' : (+x).toPrecision(d);

async function getJSON(url) {
  const r = await fetch(url);
  const body = await r.json().catch(() => ({}));
  if (!r.ok) throw new Error(`${url}: ${body.error || r.status}`);
  return body;
}

async function loadGLB(url) {
  // fetched whole, then parsed: one plain request (three's FileLoader streams it through an abortable
  // reader, which Chromium reports as an aborted request even when it completed)
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: ${r.status}`);
  return new GLTFLoader().parseAsync(await r.arrayBuffer(), '');
}

function setStatus(text) { $('#status').textContent = text; }

async function main() {
  const site = await getJSON('api/site');
  const wanted = new URLSearchParams(location.search).get('rig');
  hook.site = site;
  if (wanted) await showRig(wanted, site.mode === 'batch');
  else if (site.mode === 'rig') await showRig(site.rig, false);
  else await showBatch(site);
  hook.ready = true;
}

main().catch((err) => {
  hook.error = String(err && err.message || err);
  setStatus('error');
  $('#main').replaceChildren(el('div', { class: 'error', text: hook.error }));
  console.error(err);  // a failure to show the rig must be seen (tests count console errors)
});

// ---------------------------------------------------------------- one rig

// weight ramp: 0 -> blue, 0.25 cyan, 0.5 green, 0.75 yellow, 1 red; exactly 0 -> grey (no influence)
const RAMP = [[0.13, 0.25, 1.0], [0.0, 0.78, 1.0], [0.13, 0.82, 0.25], [1.0, 0.88, 0.0], [1.0, 0.13, 0.0]];
const GREY = [0.80, 0.80, 0.80];
function ramp(w, out, o) {
  if (!(w > 1e-4)) { out[o] = GREY[0]; out[o + 1] = GREY[1]; out[o + 2] = GREY[2]; return; }
  const t = Math.min(w, 1) * (RAMP.length - 1), i = Math.min(Math.floor(t), RAMP.length - 2), f = t - i;
  for (let c = 0; c < 3; c++) out[o + c] = RAMP[i][c] * (1 - f) + RAMP[i + 1][c] * f;
}

function hsv(h, s, v, out, o) {  // Python's colorsys.hsv_to_rgb, as the thumbnails use it
  const i = Math.floor(h * 6), f = h * 6 - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  const rgb = [[v, t, p], [q, v, p], [p, v, t], [p, q, v], [t, p, v], [v, p, q]][i % 6];
  out[o] = rgb[0]; out[o + 1] = rgb[1]; out[o + 2] = rgb[2];
}

async function showRig(rel, fromBatch) {
  hook.mode = 'rig';
  $('#crumb').replaceChildren(
    fromBatch ? el('a', { href: './', text: '← batch' }) : '', fromBatch ? ' / ' : '', rel);
  setStatus('loading the rig…');
  const [facts, gltf] = await Promise.all([
    getJSON('api/rig?path=' + encodeURIComponent(rel)),
    loadGLB(fileURL(rel)),
  ]);
  hook.facts = facts;
  const json = gltf.parser.json;
  let mesh = null;
  gltf.scene.traverse((o) => { if (o.isSkinnedMesh || (o.isMesh && !mesh)) mesh = o; });
  if (!mesh) throw new Error(`${rel}: the glb has no mesh`);

  // layout
  const view = el('div', { id: 'view' });
  const panel = el('div', { id: 'panel' });
  const legend = el('div', { id: 'legend', hidden: true });
  view.append(legend);
  $('#main').replaceChildren(el('div', { class: 'rig-layout' }, view, panel));

  // renderer, scene, camera
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.prepend(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef1f4);
  scene.add(gltf.scene);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6));

  const geom = mesh.geometry;
  if (!geom.attributes.normal) geom.computeVertexNormals();
  const n = geom.attributes.position.count;
  const colors = new Float32Array(n * 3).fill(GREY[0]);
  geom.setAttribute('color', new THREE.BufferAttribute(colors, 3));
  mesh.material = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.75, metalness: 0.0,
                                                   side: THREE.DoubleSide });
  mesh.frustumCulled = false;  // a posed skin leaves its rest bounding box

  // the head's axes: rows are its left, up and front in the file's frame (frame.axes, a transferred rig's
  // anatomical axes; else the rows of frame.rotation, canonical +X, +Y, +Z)
  const fr = facts.frame || {};
  const R = fr.axes || fr.rotation || [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  const axes = R.map((r) => new THREE.Vector3(...r).normalize());
  const canon = new THREE.Quaternion().setFromRotationMatrix(new THREE.Matrix4().makeBasis(axes[0], axes[1], axes[2]));
  scene.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromBufferAttribute(geom.attributes.position);
  const center = box.getCenter(new THREE.Vector3());
  const size = fr.head_size || box.getSize(new THREE.Vector3()).length() / 2 || 1;

  // the camera looks along the file's axis nearest the face's front, up the axis nearest up (what the user
  // modelled); the bone sliders turn about the exact head frame
  const axisOf = (name, fallback) => {
    const m = /^([+-])([xyz])$/.exec(name || '');
    if (!m) return fallback.clone();
    const v = new THREE.Vector3(); v[m[2]] = m[1] === '-' ? -1 : 1; return v;
  };
  const up = axisOf(fr.up, axes[1]), front = axisOf(fr.front, axes[2]);
  const side = new THREE.Vector3().crossVectors(up, front);
  const camera = new THREE.PerspectiveCamera(35, 1, size * 0.01, size * 200);
  camera.up.copy(up);
  camera.position.copy(center).addScaledVector(front, size * 2.3).addScaledVector(side, size * 0.7)
    .addScaledVector(up, size * 0.2);
  const light = new THREE.DirectionalLight(0xffffff, 1.4);
  light.position.set(0.5, 1, 1);
  camera.add(light);
  scene.add(camera);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  controls.update();

  let dirty = true;
  const redraw = () => { dirty = true; };
  controls.addEventListener('change', redraw);
  function resize() {
    const w = view.clientWidth || 1, h = view.clientHeight || 1;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    redraw();
  }
  new ResizeObserver(resize).observe(view);
  resize();

  // bones: names as the file spells them (the loader strips '/' and '.' from node names)
  const skin = (json.skins || [])[0];
  const boneNames = skin ? skin.joints.map((j) => json.nodes[j].name) : [];
  const bones = mesh.isSkinnedMesh ? mesh.skeleton.bones : [];
  const restLocal = bones.map((b) => b.quaternion.clone());
  const restWorld = bones.map((b) => b.getWorldQuaternion(new THREE.Quaternion()));
  const angles = bones.map(() => [0, 0, 0]);
  const canonInv = canon.clone().invert();
  function applyBone(i) {
    // rotate about the head frame's axes (pitch about +X: positive opens a jaw; yaw +Y; roll +Z) at the bone's head
    const a = angles[i].map(THREE.MathUtils.degToRad);
    const qe = new THREE.Quaternion().setFromEuler(new THREE.Euler(a[0], a[1], a[2], 'XYZ'));
    const qWorld = canon.clone().multiply(qe).multiply(canonInv);
    const delta = restWorld[i].clone().invert().multiply(qWorld).multiply(restWorld[i]);
    bones[i].quaternion.copy(restLocal[i]).multiply(delta);
    redraw();
  }

  // muscles follow their marker nodes (children of bones); landmarks are the sidecar's rest positions.
  // A linear muscle is its origin -> insertion; a sphincter or sheet is its ellipse (the sidecar's rest segments),
  // carried rigidly by its centre's marker (the ring's origin)
  const nodeObjects = await Promise.all((json.nodes || []).map((_, i) => gltf.parser.getDependency('node', i)));
  const byName = new Map((json.nodes || []).map((nd, i) => [nd.name, nodeObjects[i]]));
  scene.updateMatrixWorld(true);
  const muscles = (facts.muscles || []).map((m) => {
    const o = byName.get(`muscle/${m.name}/origin`);
    const ring = m.kind !== 'linear' && (m.segments || []).length > 1 ? m.segments.flat() : null;
    return { name: m.name, o, i: byName.get(`muscle/${m.name}/insertion`), origin: m.origin, insertion: m.insertion,
             ring, restInv: ring && o ? o.matrixWorld.clone().invert() : null };
  });
  const nPoints = muscles.reduce((k, m) => k + (m.ring ? m.ring.length : 2), 0);
  const muscleGeom = new THREE.BufferGeometry();
  muscleGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(nPoints * 3), 3));
  const muscleLines = new THREE.LineSegments(muscleGeom, new THREE.LineBasicMaterial({ color: 0xc2185b, depthTest: false }));
  muscleLines.renderOrder = 2;
  muscleLines.frustumCulled = false;
  muscleLines.visible = false;
  scene.add(muscleLines);
  const tmp = new THREE.Vector3();
  const moved = new THREE.Matrix4();
  function updateMuscles() {
    if (!muscleLines.visible) return;
    const p = muscleGeom.attributes.position.array;
    let k = 0;
    for (const m of muscles) {
      if (m.ring) {
        if (m.restInv) moved.multiplyMatrices(m.o.matrixWorld, m.restInv); else moved.identity();
        for (const q of m.ring) { tmp.set(q[0], q[1], q[2]).applyMatrix4(moved); p.set([tmp.x, tmp.y, tmp.z], 3 * k++); }
        continue;
      }
      if (m.o) m.o.getWorldPosition(tmp); else tmp.set(...(m.origin || [0, 0, 0]));
      p.set([tmp.x, tmp.y, tmp.z], 3 * k++);
      if (m.i) m.i.getWorldPosition(tmp); else tmp.set(...(m.insertion || [0, 0, 0]));
      p.set([tmp.x, tmp.y, tmp.z], 3 * k++);
    }
    muscleGeom.attributes.position.needsUpdate = true;
  }
  const marks = new THREE.Group();
  marks.visible = false;
  const markGeom = new THREE.SphereGeometry(size * 0.012, 12, 8);
  const markMat = new THREE.MeshBasicMaterial({ color: 0xe53935, depthTest: false });
  for (const [name, p] of Object.entries(facts.landmarks || {})) {
    const s = new THREE.Mesh(markGeom, markMat);
    s.position.set(...p);
    s.name = name;
    s.renderOrder = 3;
    marks.add(s);
  }
  scene.add(marks);
  const skelHelper = bones.length ? new THREE.SkeletonHelper(bones[0].parent && bones[0].parent.isBone ? bones[0].parent : bones[0]) : null;
  if (skelHelper) { skelHelper.visible = false; skelHelper.material.depthTest = false; scene.add(skelHelper); }

  // skin coloured by one bone's weight: the glb's 4 largest influences, or the npz's full column
  const weightCache = new Map();
  let weightBone = '', weightSource = 'glb';
  async function colourBy(name, source) {
    weightBone = name; weightSource = source;
    if (!name) { colors.fill(GREY[0]); legend.hidden = true; }
    else if (name === '*') {  // each vertex the colour of its largest influence (as the batch thumbnails)
      const si = geom.attributes.skinIndex, sw = geom.attributes.skinWeight;
      for (let v = 0; v < n; v++) {
        let best = 0;
        for (let c = 1; c < sw.itemSize; c++) if (sw.array[v * sw.itemSize + c] > sw.array[v * sw.itemSize + best]) best = c;
        const hue = (0.08 + 0.618034 * si.array[v * si.itemSize + best]) % 1;
        hsv(hue, 0.55, 0.95, colors, 3 * v);
      }
      legend.hidden = false;
      legend.replaceChildren('each vertex: the colour of its largest bone influence');
    } else {
      let w;
      if (source === 'npz') {
        const key = name;
        if (!weightCache.has(key)) {
          const r = await getJSON(`api/weights?path=${encodeURIComponent(rel)}&bone=${encodeURIComponent(name)}`);
          weightCache.set(key, Float32Array.from(r.weights));
        }
        w = weightCache.get(key);
      } else {
        const j = boneNames.indexOf(name);
        const si = geom.attributes.skinIndex, sw = geom.attributes.skinWeight;
        w = new Float32Array(n);
        if (si && sw) for (let v = 0; v < n; v++) {
          for (let c = 0; c < si.itemSize; c++) if (si.array[v * si.itemSize + c] === j) w[v] += sw.array[v * sw.itemSize + c];
        }
      }
      for (let v = 0; v < n; v++) ramp(w[v], colors, 3 * v);
      legend.hidden = false;
      legend.replaceChildren(`${name} weight (${source === 'npz' ? 'full matrix' : '4 largest, glb'})  0`,
                             el('span', { class: 'bar' }), '1');
    }
    geom.attributes.color.needsUpdate = true;
    redraw();
  }

  // animation, when the glb has one (autobones animate)
  let mixer = null, playing = false, last = performance.now();
  if (gltf.animations && gltf.animations.length) {
    mixer = new THREE.AnimationMixer(gltf.scene);
    mixer.clipAction(gltf.animations[0]).play();
    mixer.update(0);
  }

  // ---- the panel
  const facts_ = el('dl');
  const fact = (k, v) => { if (v !== undefined && v !== null && v !== '') facts_.append(el('dt', { text: k }), el('dd', { text: String(v) })); };
  fact('file', rel);
  fact('source', facts.source);
  fact('made by', facts.command && `autobones ${facts.command}`);
  fact('status', facts.status);
  fact('input', facts.input);
  fact('vertices', facts.vertices);
  fact('bones', boneNames.length);
  fact('muscles', (facts.muscles || []).length || null);
  fact('landmarks', Object.keys(facts.landmarks || {}).length ? `${Object.keys(facts.landmarks).length}` +
       (facts.landmarks_source ? ` (${facts.landmarks_source})` : '') : null);
  fact('morph targets', Object.keys(mesh.morphTargetDictionary || {}).length || null);
  fact('frame', fr.up ? `up ${fr.up}, front ${fr.front}` : null);
  fact('head size', fr.head_size !== undefined ? fmt(fr.head_size, 4) : null);
  fact('symmetry error', fr.symmetry_error !== undefined && fr.symmetry_error !== null ? fmt(fr.symmetry_error, 3) + ' head sizes' : null);
  fact('fields reliable', facts.reliable_fraction !== null && facts.reliable_fraction !== undefined ? `${(100 * facts.reliable_fraction).toFixed(0)}% of vertices` : null);
  fact('seconds', facts.seconds !== null && facts.seconds !== undefined ? fmt(facts.seconds, 3) : null);
  for (const [k, v] of Object.entries(facts.timings || {})) fact(`  ${k}`, `${fmt(v, 3)} s`);
  fact('autobones', facts.autobones_version);
  panel.append(el('h3', { text: 'Rig' }), facts_);
  if ((facts.warnings || []).length) {
    panel.append(el('h3', { text: 'Warnings' }), ...facts.warnings.map((w) => el('div', { class: 'warn', text: w.text })));
  }

  const show = el('div');
  const weightSel = el('select', { id: 'weight-bone' }, el('option', { value: '', text: 'none (plain skin)' }),
                       geom.attributes.skinIndex ? el('option', { value: '*', text: 'all bones (largest influence)' }) : null,
                       ...boneNames.map((b) => el('option', { value: b, text: b })));
  const sourceSel = el('select', { id: 'weight-source' }, el('option', { value: 'glb', text: '4 largest (glb)' }),
                       el('option', { value: 'npz', text: 'full matrix (npz)' }));
  const onWeights = () => colourBy(weightSel.value, sourceSel.value).catch(fail);
  weightSel.addEventListener('change', onWeights);
  sourceSel.addEventListener('change', onWeights);
  const toggle = (id, label, obj, after) => el('label', { class: 'check' }, el('input', {
    type: 'checkbox', id, onchange: (e) => { obj.visible = e.target.checked; if (after) after(); redraw(); },
  }), ' ' + label);
  show.append(el('div', { class: 'row' }, el('label', { text: 'weights of' }), weightSel),
              el('div', { class: 'row' }, el('label', { text: 'from' }), sourceSel),
              el('div', { class: 'row wrap' },
                 marks.children.length ? toggle('show-landmarks', 'landmarks', marks) : '',
                 muscles.length ? toggle('show-muscles', 'muscles', muscleLines, updateMuscles) : '',
                 skelHelper ? toggle('show-skeleton', 'skeleton', skelHelper) : '',
                 el('label', { class: 'check' }, el('input', { type: 'checkbox', id: 'show-wireframe',
                   onchange: (e) => { mesh.material.wireframe = e.target.checked; redraw(); } }), ' wireframe')));
  panel.append(el('h3', { text: 'Show' }), show);

  const sliders = [];
  const slider = (label, attrs, min, max, step, onInput) => {
    const out = el('output', { text: '0' });
    const input = el('input', { type: 'range', min, max, step, value: 0, ...attrs });
    input.addEventListener('input', () => { out.textContent = (+input.value).toFixed(step < 1 ? 2 : 0); onInput(+input.value); });
    sliders.push([input, out]);
    return el('div', { class: 'row' }, el('label', { text: label, title: label }), input, out);
  };
  if (mixer) {
    panel.append(el('h3', { text: 'Animation' }), el('div', { class: 'row' },
      el('button', { id: 'play', text: 'play', onclick: (e) => {
        playing = !playing; e.target.textContent = playing ? 'pause' : 'play'; last = performance.now(); redraw(); } })));
  }
  if (bones.length) {
    panel.append(el('h3', { text: 'Pose (degrees, head frame)' }),
                 el('div', { class: 'row' }, el('button', { id: 'reset', text: 'reset pose and expressions', onclick: reset })));
    bones.forEach((b, i) => {
      const name = boneNames[i];
      const d = el('details', { class: 'bone', 'data-bone': name, open: ['jaw', 'head'].includes(name) },
                   el('summary', { text: name }));
      ['pitch', 'yaw', 'roll'].forEach((ax, k) => d.append(slider(ax, { 'data-bone': name, 'data-axis': 'xyz'[k] }, -60, 60, 1,
        (v) => { angles[i][k] = v; applyBone(i); })));
      panel.append(d);
    });
  }
  const dict = mesh.morphTargetDictionary || {};
  const labels = new Map((facts.morph_targets || []).map((m) => [m.name, m.label]));
  const targets = Object.entries(dict).sort((a, b) => a[1] - b[1]);
  const groups = [['FACS action units (0..1)', targets.filter(([name]) => /^AU\d/.test(name))],
                  ['Other morph targets (ARKit…, 0..1)', targets.filter(([name]) => !/^AU\d/.test(name))]];
  for (const [title, group] of groups) {
    if (!group.length) continue;
    panel.append(el('h3', { text: title }));
    for (const [name, idx] of group) {
      const row = slider(name, { 'data-morph': name }, 0, 1, 0.01, (v) => { mesh.morphTargetInfluences[idx] = v; redraw(); });
      if (labels.get(name)) row.title = labels.get(name);
      panel.append(row);
    }
  }
  function reset() {
    for (const [input, out] of sliders) { input.value = 0; out.textContent = '0'; }
    angles.forEach((a, i) => { a.fill(0); applyBone(i); });
    if (mesh.morphTargetInfluences) mesh.morphTargetInfluences.fill(0);
    redraw();
  }
  function fail(err) { hook.error = String(err && err.message || err); setStatus('error'); console.error(err); }

  let frames = 0;
  renderer.setAnimationLoop(() => {
    const now = performance.now();
    if (playing && mixer) { mixer.update((now - last) / 1000); dirty = true; }
    last = now;
    if (!dirty) return;
    dirty = false;
    scene.updateMatrixWorld(true);
    updateMuscles();
    renderer.render(scene, camera);
    frames++;
  });

  Object.assign(hook, {
    rig: rel, bones: boneNames, morphs: Object.keys(dict), vertexCount: n,
    frames: () => frames,
    setBone(name, deg) {  // deg: [pitch, yaw, roll]; moves the sliders too
      const i = boneNames.indexOf(name);
      if (i < 0) throw new Error(`no bone ${name}`);
      angles[i] = deg.slice(0, 3).map(Number);
      sliders.filter(([inp]) => inp.dataset.bone === name).forEach(([inp, out]) => {
        inp.value = angles[i]['xyz'.indexOf(inp.dataset.axis)]; out.textContent = inp.value; });
      applyBone(i);
    },
    setMorph(name, v) {
      if (!(name in dict)) throw new Error(`no morph target ${name}`);
      mesh.morphTargetInfluences[dict[name]] = +v; redraw();
    },
    colourBy: (name, source = 'glb') => colourBy(name, source),
    muscleLines() {  // the drawn muscle segments, flat [x0, y0, z0, x1, ...], two points a segment
      const was = muscleLines.visible;
      muscleLines.visible = true; scene.updateMatrixWorld(true); updateMuscles(); muscleLines.visible = was;
      return Array.from(muscleGeom.attributes.position.array);
    },
    weightColours: () => Array.from(colors),
    positions() {  // skinned and morphed vertices, the file's frame and units, flat [x0, y0, z0, x1, ...]
      scene.updateMatrixWorld(true);
      if (mesh.skeleton) mesh.skeleton.update();
      const v = new THREE.Vector3(), out = new Array(3 * n);
      for (let i = 0; i < n; i++) { mesh.getVertexPosition(i, v); out[3 * i] = v.x; out[3 * i + 1] = v.y; out[3 * i + 2] = v.z; }
      return out;
    },
    reset,
    showOverlays(on = true) {
      for (const id of ['show-landmarks', 'show-muscles', 'show-skeleton']) {
        const box = document.getElementById(id);
        if (box && box.checked !== on) box.click();
      }
    },
  });
  const warn = (facts.warnings || []).length;
  setStatus(`${n} vertices, ${boneNames.length} bones, ${Object.keys(dict).length} morph targets` +
            (warn ? `, ${warn} warning${warn > 1 ? 's' : ''}` : ''));
}

// ---------------------------------------------------------------- a batch folder

async function showBatch(site) {
  hook.mode = 'batch';
  $('#crumb').textContent = site.title;
  setStatus('reading the report…');
  const data = await getJSON('api/batch');
  const files = data.files;
  const counts = { ok: 0, failed: 0, skipped: 0 };
  for (const f of files) counts[f.status] = (counts[f.status] || 0) + 1;
  const kinds = [...new Set(files.flatMap((f) => f.warnings.map((w) => w.kind)))].sort();

  const s = data.summary;
  const summary = el('div', { id: 'summary' }, s
    ? `${files.length} files: ${counts.ok} ok, ${counts.failed} failed, ${counts.skipped} skipped · ` +
      `${fmt(s.seconds, 3)} s wall on ${s.engine || 'local'}${s.jobs ? ` (${s.jobs} jobs)` : ''}` +
      (s.options && s.options.mode ? ` · ${s.options.mode}` : '') + (s.finished ? ` · finished ${s.finished}` : '')
    : `${files.length} rigs (no batch_report.json in this folder)`);

  const statusBoxes = ['ok', 'failed', 'skipped'].map((st) => el('label', {},
    el('input', { type: 'checkbox', 'data-status': st, checked: true, onchange: apply }), ` ${st} (${counts[st] || 0})`));
  const warnSel = el('select', { id: 'warning-filter', onchange: apply },
    el('option', { value: 'any', text: 'any warnings' }),
    el('option', { value: 'some', text: 'with warnings' }),
    el('option', { value: 'none', text: 'without warnings' }),
    ...kinds.map((k) => el('option', { value: 'kind:' + k, text: k })));
  const search = el('input', { type: 'search', id: 'search', placeholder: 'file name…', oninput: apply });
  const sortSel = el('select', { id: 'sort', onchange: apply },
    el('option', { value: 'name', text: 'by name' }), el('option', { value: 'time', text: 'slowest first' }),
    el('option', { value: 'status', text: 'failed first' }));
  const filters = el('div', { id: 'filters' }, el('span', {}, 'status: ', ...statusBoxes),
                     el('span', {}, 'warnings: ', warnSel), search, sortSel);
  const grid = el('div', { id: 'grid' });
  $('#main').replaceChildren(el('div', { class: 'batch-layout' }, summary, filters, grid));

  const cards = files.map((f) => {
    const name = f.output || f.input || '?';
    const pic = f.viewable
      ? el('img', { class: 'thumb', loading: 'lazy', alt: name, src: 'api/thumb?path=' + encodeURIComponent(f.output) })
      : el('div', { class: 'nothumb', text: f.status === 'failed' ? 'failed' : 'no rig' });
    const meta = [f.input && f.input !== name ? `from ${f.input}` : null,
                  f.vertices ? `${f.vertices} vertices` : null, f.bones ? `${f.bones} bones` : null,
                  f.morph_targets ? `${f.morph_targets} morph targets` : null,
                  f.seconds ? `${fmt(f.seconds, 3)} s` : null].filter(Boolean).join(' · ');
    const card = el('div', { class: `card ${f.status}${f.viewable ? ' viewable' : ''}`, 'data-status': f.status,
                             'data-output': f.output, title: f.viewable ? 'open this rig' : '' },
      pic,
      el('div', { class: 'body' },
        el('div', { class: 'name' }, el('span', { class: `badge ${f.status}`, text: f.status }), name),
        el('div', { class: 'meta', text: meta }),
        f.status === 'failed' && f.error ? el('div', { class: 'err', text: f.error }) : null,
        f.status === 'skipped' && f.reason ? el('div', { class: 'meta', text: f.reason }) : null,
        ...f.warnings.map((w) => el('div', { class: 'warn', text: w.text }))));
    if (f.viewable) card.addEventListener('click', () => { location.href = './?rig=' + encodeURIComponent(f.output); });
    return { f, card, name };
  });

  function apply() {
    const statuses = new Set(statusBoxes.map((l) => l.firstChild).filter((b) => b.checked).map((b) => b.dataset.status));
    const w = warnSel.value, q = search.value.trim().toLowerCase();
    const keep = cards.filter(({ f, name }) => statuses.has(f.status)
      && (w === 'any' || (w === 'some' && f.warnings.length) || (w === 'none' && !f.warnings.length)
          || (w.startsWith('kind:') && f.warnings.some((x) => x.kind === w.slice(5))))
      && (!q || name.toLowerCase().includes(q) || (f.input || '').toLowerCase().includes(q)));
    const order = { failed: 0, skipped: 1, ok: 2 };
    if (sortSel.value === 'time') keep.sort((a, b) => (b.f.seconds || 0) - (a.f.seconds || 0));
    else if (sortSel.value === 'status') keep.sort((a, b) => order[a.f.status] - order[b.f.status] || a.name.localeCompare(b.name));
    else keep.sort((a, b) => a.name.localeCompare(b.name));
    grid.replaceChildren(...keep.map((c) => c.card));
    setStatus(`${keep.length} of ${cards.length} shown`);
  }
  apply();
  Object.assign(hook, {
    files: files.length,
    visible: () => [...grid.children].map((c) => c.dataset.output),
    thumbnailsLoaded: () => [...grid.querySelectorAll('img.thumb')].filter((i) => i.complete && i.naturalWidth > 0).length,
  });
}
