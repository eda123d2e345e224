// gspn viewer: draws the net in SVG, plays the token game through the JSON API, shows the
// analysis. Plain JavaScript, no library, nothing loaded from anywhere but this server.
//
// Test hooks (stable): each place's <g> has data-place="NAME" data-tokens="K"; each
// transition's <g> has data-transition="NAME" data-enabled="true|false" (true = it may fire
// now under GSPN rules); buttons #step #step-n #run #reset, seed field #seed, trace #trace.
'use strict';

// An XML namespace name, not an address: nothing is ever fetched from it.
const SVG_NS = 'http://www.w3.org/2000/svg';
const R = 18; // place radius
const TH = 30; // transition height

let net = null;
let scale = 1; // drawing units per file unit
let state = null;
let view = { x: 0, y: 0, k: 1 };
let runTimer = null;
let busy = false;
const placeEls = [];
const transEls = [];
const arcEls = [];
const arcsOfPlace = [];
const arcsOfTransition = [];
// What is drawn, per place / transition (both renderers read these).
const placeTokens = [];
const transEnabled = [];
const placeAgents = [];
let firedIndex = -1;

const $ = (id) => document.getElementById(id);

// Timings for the benchmark and the browser tests (examples/bench_viewer.rs): when the first
// drawing reached the screen (ms since navigation start), and per live frame the time from
// the message to the paint after it, and the script's share of it (the last 1000 of each).
const gspnPerf = { drawn: null, frames: [], handler: [] };
window.gspnPerf = gspnPerf;
// The token game's last state from the server, for the browser tests.
window.gspnState = () => state;

// Runs `fn` after the next paint: a frame callback runs just before it, a task after that.
function afterPaint(fn) {
  requestAnimationFrame(() => setTimeout(fn, 0));
}

function markDrawn() {
  afterPaint(() => {
    if (gspnPerf.drawn === null) gspnPerf.drawn = performance.now();
  });
}

function pushCapped(list, v) {
  list.push(v);
  if (list.length > 1000) list.shift();
}

function el(tag, attrs, parent) {
  const e = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function status(text) {
  $('status').textContent = text || '';
}

// Every request that changes something is JSON (an empty object when there is nothing to
// say): the server refuses any other content type, which is what keeps other sites out.
async function api(method, path, body) {
  const opts = { method, headers: {} };
  if (method !== 'GET' || body !== undefined) {
    opts.headers['Content-Type'] = 'application/json';
    opts.body = JSON.stringify(body === undefined ? {} : body);
  }
  const res = await fetch(path, opts);
  const data = await res.json();
  if (!res.ok) throw new Error(data.error || res.statusText);
  return data;
}

// At most `n` characters of a marking `p=k,...`, then how many places were left out.
function shorten(text, n) {
  if (text.length <= n) return text;
  const cut = text.lastIndexOf(',', n);
  const rest = text.slice(cut + 1).split(',').length;
  return text.slice(0, cut) + ' … (' + rest + ' more)';
}

function fmt(x) {
  if (typeof x !== 'number') return String(x);
  if (Number.isInteger(x)) return String(x);
  return Number(x.toPrecision(4)).toString();
}

// A time to the microsecond (`2.679`, not `2.6790000000000003`), a time under a millisecond
// to 4 significant figures; the full value goes in the element's tooltip ([`timeTitle`]).
function fmtTime(x) {
  if (typeof x !== 'number' || !Number.isFinite(x)) return String(x);
  const a = Math.abs(x);
  return String(Number(a !== 0 && a < 1e-3 ? x.toPrecision(4) : x.toFixed(6)));
}

// Every digit of a time (the shortest text that reads back the same), for a tooltip.
function timeTitle(x) {
  return 'time ' + String(x);
}

// A list entry `N  text` with its number in its own cell (no digit is cut however long the
// run), shown or hidden by the list's filter box.
function listItem(seq, text) {
  const li = document.createElement('li');
  const n = document.createElement('span');
  n.className = 'seq';
  n.textContent = String(seq);
  li.appendChild(n);
  li.appendChild(document.createTextNode(text));
  li.dataset.seq = seq;
  return li;
}

// Whether a scrolled list shows its last line (then new lines keep it at the bottom; a user
// reading further up is left where they are).
function atBottom(box) {
  return box.scrollTop + box.clientHeight >= box.scrollHeight - 4;
}

// Hides the entries of `ol` that do not contain the text of its filter box `input`.
function applyFilter(ol, input) {
  const q = input.value.trim().toLowerCase();
  for (const li of ol.children) li.classList.toggle('hidden', q !== '' && !li.textContent.toLowerCase().includes(q));
}

function transitionWidth(t) {
  return t.kind === 'immediate' ? 6 : 20;
}

// Half the width and half the height of a transition as drawn: a GreatSPN rotation of a
// quarter turn lays the bar down.
function transitionHalf(t) {
  const w = transitionWidth(t) / 2;
  const r = t.look && t.look.rotation;
  return r && Math.abs(Math.sin(r)) > 0.5 ? [TH / 2, w] : [w, TH / 2];
}

// A text's place from the file's offset (GreatSPN's label-x/label-y, delay-x/delay-y, in
// the file's units, from the node's centre), else the default `y` under or over the node.
function placeText(text, offset, y) {
  if (!offset) {
    text.setAttribute('y', y);
    return;
  }
  const [dx, dy] = offset;
  text.setAttribute('x', ((dx || 0) * scale).toFixed(1));
  text.setAttribute('y', dy === null || dy === undefined ? y : (dy * scale).toFixed(1));
  text.setAttribute('dominant-baseline', 'central');
}

function paramText(t) {
  if (t.kind === 'immediate') {
    return 'w=' + fmt(t.weight) + (t.priority !== 1 ? ' π=' + t.priority : '');
  }
  const s = t.servers === 'single' ? '' : t.servers === 'infinite' ? ' ∞' : ' ×' + t.servers;
  return 'λ=' + fmt(t.rate) + s;
}

// ---- layout ----------------------------------------------------------------------------

// The layout the user chose for a net ('file' or 'layered'), remembered per net name.
function layoutKey(n) {
  return 'layout.' + n.name;
}


// Puts the net's other layout (the server sends the file's positions and the automatic
// layout when the file has positions) in place of the one it came with.
function swapLayout(n) {
  const o = n.other_layout;
  const mine = {
    layout: n.layout,
    places: n.places.map((p) => [p.x, p.y]),
    transitions: n.transitions.map((t) => [t.x, t.y]),
    arcs: n.arcs.map((a) => a.points),
  };
  n.places.forEach((p, i) => { [p.x, p.y] = o.places[i]; });
  n.transitions.forEach((t, i) => { [t.x, t.y] = o.transitions[i]; });
  n.arcs.forEach((a, i) => { a.points = o.arcs[i]; });
  n.layout = o.layout;
  n.other_layout = mine;
}

// A net from the server in the layout chosen for it (before its coordinates are scaled).
// The automatic layout places the names itself: a file's label offsets and rotations are
// for the file's positions.
function adoptLayout(n) {
  if (n.other_layout && remembered(layoutKey(n)) === n.other_layout.layout) swapLayout(n);
  if (n.layout === 'layered') for (const node of n.places.concat(n.transitions)) delete node.look;
  const pick = $('layout-choice');
  pick.classList.toggle('hidden', !n.other_layout);
  pick.value = n.layout;
  pick.title = 'the positions drawn: the file\'s or an automatic layered layout' +
    (n.layout_note ? ' (automatic because ' + n.layout_note + ')' : '');
}

function showTitle() {
  $('title').textContent = net.name + (net.layout === 'layered' ? ' (automatic layout)' : '');
  $('title').title = $('title').textContent + (net.layout_note ? ': ' + net.layout_note : '');
}

// The `layout` control: draws the net again in the other layout, remembered for this net.
async function chooseLayout() {
  const want = $('layout-choice').value;
  remember(layoutKey(net), want);
  if (want === net.layout) return;
  const n = await api('GET', '/api/net');
  adoptLayout(n);
  net = n;
  scaleCoordinates();
  showTitle();
  drawNet();
  fit();
  if (state) applyState(state);
}

// ---- drawing ---------------------------------------------------------------------------

// Files use different units (GreatSPN: about one per grid cell; PIPE: pixels): scale the
// drawing so that nodes sit at least ~70 px from their nearest neighbour (median).
function scaleCoordinates() {
  scale = nearestScale(net.places.concat(net.transitions).map((n) => [n.x, n.y]));
  if (scale === 1) return;
  for (const n of net.places.concat(net.transitions)) {
    n.x *= scale;
    n.y *= scale;
  }
  for (const a of net.arcs) a.points = a.points.map((q) => [q[0] * scale, q[1] * scale]);
}

// The scale that puts the median nearest neighbour of `points` ([x, y]) 70 px away; 1 when
// they are that far apart already.
function nearestScale(points) {
  const nodes = points.slice(0, 400);
  if (nodes.length < 2) return 1;
  const nearest = nodes.map((a) => {
    let best = Infinity;
    for (const b of nodes) {
      const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
      if (b !== a && d > 0 && d < best) best = d;
    }
    return best;
  }).filter(Number.isFinite).sort((x, y) => x - y);
  if (!nearest.length) return 1;
  return Math.max(1, 70 / nearest[Math.floor(nearest.length / 2)]);
}

function drawNet() {
  const arcs = $('arcs');
  const nodes = $('nodes');
  arcs.textContent = '';
  nodes.textContent = '';
  $('hooks').textContent = '';
  placeEls.length = transEls.length = arcEls.length = 0;
  arcsOfPlace.length = arcsOfTransition.length = 0;
  placeTokens.length = transEnabled.length = placeAgents.length = 0;
  firedIndex = -1;
  for (const _ of net.places) {
    placeTokens.push(-1);
    placeAgents.push('');
    arcsOfPlace.push([]);
  }
  for (const _ of net.transitions) {
    transEnabled.push(false);
    arcsOfTransition.push([]);
  }
  net.arcs.forEach((a, i) => {
    arcsOfPlace[a.place].push(i);
    arcsOfTransition[a.transition].push(i);
  });
  fillNames();
  drawMinimap();
  if (canvasInit()) {
    const hooks = canvasHooks();
    placeEls.push(...hooks.places);
    transEls.push(...hooks.transitions);
    net.places.forEach((p, i) => setTokens(i, p.tokens));
    canvasDirty();
    return;
  }
  net.places.forEach((p, i) => {
    const g = el('g', { class: 'node place', 'data-place': p.name, 'data-tokens': '' }, nodes);
    g.dataset.index = i;
    el('circle', { class: 'body', r: R }, g);
    g.tokens = el('g', {}, g);
    const label = el('text', { class: 'label' }, g);
    placeText(label, p.look && p.look.label, R + 13);
    label.textContent = p.name;
    if (p.capacity !== null && p.capacity !== undefined) {
      const cap = el('text', { class: 'param', y: -R - 5 }, g);
      cap.textContent = 'cap ' + p.capacity;
    }
    const title = el('title', {}, g);
    title.textContent = p.name;
    placeEls.push(g);
    setTokens(i, p.tokens);
    move(g, p);
  });
  net.transitions.forEach((t, i) => {
    const g = el('g', {
      class: 'node transition ' + t.kind,
      'data-transition': t.name,
      'data-enabled': 'false',
    }, nodes);
    g.dataset.index = i;
    const [hw, hh] = transitionHalf(t);
    el('rect', { x: -hw, y: -hh, width: 2 * hw, height: 2 * hh }, g);
    const label = el('text', { class: 'label' }, g);
    placeText(label, t.look && t.look.label, hh + 13);
    label.textContent = t.name;
    const param = el('text', { class: 'param' }, g);
    placeText(param, t.look && t.look.param, -hh - 5);
    if (hw > hh && !(t.look && t.look.param)) {
      // A bar laid down has its arcs above and below: the rate goes beside it.
      param.setAttribute('x', hw + 3);
      param.setAttribute('y', -3);
      param.setAttribute('text-anchor', 'start');
      param.style.textAnchor = 'start';
    }
    param.textContent = paramText(t);
    const title = el('title', {}, g);
    title.textContent = t.name + ' (' + t.kind + ', ' + paramText(t) + ')';
    transEls.push(g);
    move(g, t);
  });
  // Inhibitor arcs over the others, so that an arc never hides their circle head.
  const under = el('g', { class: 'arcs-normal' }, arcs);
  const over = el('g', { class: 'arcs-inhibitor' }, arcs);
  net.arcs.forEach((a, i) => {
    const layer = a.kind === 'inhibitor' ? over : under;
    const path = el('path', {
      class: 'arc ' + a.kind,
      'marker-end': a.kind === 'inhibitor' ? 'url(#inhibitor)' : 'url(#arrow)',
    }, layer);
    let weight = null;
    if (a.weight > 1) {
      weight = el('text', { class: 'arc-weight' }, layer);
      weight.textContent = String(a.weight);
    }
    arcEls.push({ path, weight });
    drawArc(i);
  });
}

function move(g, node) {
  g.setAttribute('transform', 'translate(' + node.x + ',' + node.y + ')');
}

// The point where the segment from `c` towards `o` leaves a box of half-size hw × hh.
function clipBox(c, o, hw, hh) {
  const dx = o[0] - c[0];
  const dy = o[1] - c[1];
  if (dx === 0 && dy === 0) return c;
  const s = Math.min(dx !== 0 ? hw / Math.abs(dx) : Infinity, dy !== 0 ? hh / Math.abs(dy) : Infinity);
  return [c[0] + dx * s, c[1] + dy * s];
}

function clipCircle(c, o, r) {
  const dx = o[0] - c[0];
  const dy = o[1] - c[1];
  const d = Math.hypot(dx, dy) || 1;
  return [c[0] + (dx / d) * r, c[1] + (dy / d) * r];
}

// An arc's polyline, from its source's border to its target's border.
function arcPoints(i) {
  const a = net.arcs[i];
  const p = net.places[a.place];
  const t = net.transitions[a.transition];
  const pc = [p.x, p.y];
  const tc = [t.x, t.y];
  const fromPlace = a.kind !== 'output';
  const bends = a.points.map((q) => [q[0], q[1]]);
  const pts = fromPlace ? [pc, ...bends, tc] : [tc, ...bends, pc];
  const n = pts.length;
  const [hw, hh] = transitionHalf(t);
  const clipT = (c, o) => clipBox(c, o, hw + 1, hh + 1);
  const clipP = (c, o) => clipCircle(c, o, R + 1);
  pts[0] = fromPlace ? clipP(pts[0], pts[1]) : clipT(pts[0], pts[1]);
  pts[n - 1] = fromPlace ? clipT(pts[n - 1], pts[n - 2]) : clipP(pts[n - 1], pts[n - 2]);
  return pts;
}

function drawArc(i) {
  if (cvs.on) {
    canvasArcMoved(i);
    return;
  }
  const pts = arcPoints(i);
  const n = pts.length;
  const { path, weight } = arcEls[i];
  path.setAttribute('d', 'M' + pts.map((q) => q[0].toFixed(1) + ' ' + q[1].toFixed(1)).join(' L'));
  if (weight) {
    const m = Math.floor((n - 1) / 2);
    weight.setAttribute('x', ((pts[m][0] + pts[m + 1][0]) / 2 + 4).toFixed(1));
    weight.setAttribute('y', ((pts[m][1] + pts[m + 1][1]) / 2 - 4).toFixed(1));
  }
}

// Token dots inside a place, by count (up to 5).
const DOTS = {
  1: [[0, 0]],
  2: [[-5, 0], [5, 0]],
  3: [[-6, 4], [6, 4], [0, -6]],
  4: [[-5, -5], [5, -5], [-5, 5], [5, 5]],
  5: [[-6, -6], [6, -6], [0, 0], [-6, 6], [6, 6]],
};

// Dots up to 5 tokens, the number beyond; the number is always in a badge too. Only what
// changed is touched.
function setTokens(i, k) {
  if (placeTokens[i] === k) return;
  placeTokens[i] = k;
  const g = placeEls[i];
  g.setAttribute('data-tokens', String(k));
  if (cvs.on) {
    canvasDirty();
    return;
  }
  const t = g.tokens;
  t.textContent = '';
  const dots = DOTS[k];
  if (dots) {
    for (const [x, y] of dots) el('circle', { class: 'dot', cx: x, cy: y, r: 3.5 }, t);
  } else if (k > 5) {
    el('text', { class: 'count' }, t).textContent = String(k);
  }
  if (k > 0) {
    el('text', { class: 'badge', x: R * 0.75, y: -R * 0.75 }, t).textContent = String(k);
  }
}

// Marks transition i as firable now (or not).
function setEnabled(i, on) {
  if (transEnabled[i] === on) return;
  transEnabled[i] = on;
  transEls[i].setAttribute('data-enabled', on ? 'true' : 'false');
  canvasDirty();
}

function setAllEnabled(names) {
  const firable = new Set(names);
  net.transitions.forEach((t, i) => setEnabled(i, firable.has(t.name)));
}

// Highlights the transition that fired last (-1: none).
function setFired(i) {
  if (i === firedIndex) return;
  if (firedIndex >= 0) transEls[firedIndex].classList.remove('fired');
  firedIndex = i;
  if (i >= 0) transEls[i].classList.add('fired');
  canvasDirty();
}

function transitionIndex(name) {
  if (!net.byName) {
    net.byName = new Map(net.transitions.map((t, i) => [t.name, i]));
  }
  const i = net.byName.get(name);
  return i === undefined ? -1 : i;
}

// Agents per place, as a label under it.
function setAgents(i, text) {
  if (placeAgents[i] === text) return;
  placeAgents[i] = text;
  if (cvs.on) {
    canvasDirty();
    return;
  }
  const g = placeEls[i];
  if (!text) {
    if (g.agents) g.agents.remove();
    g.agents = null;
    return;
  }
  if (!g.agents) g.agents = el('text', { class: 'agents', y: R + 25 }, g);
  g.agents.textContent = text;
}

// The plan policy's choice in the current vanishing marking, as a label over each
// transition it picks from (`policy 0.9`), with data-policy="P" on the transition's hook.
let choiceShown = [];
function setChoice(choice) {
  for (const i of choiceShown) {
    transEls[i].removeAttribute('data-policy');
    if (transEls[i].choice) transEls[i].choice.remove();
    transEls[i].choice = null;
  }
  choiceShown = [];
  if (!choice) return;
  for (const [name, p] of Object.entries(choice.probabilities)) {
    const i = transitionIndex(name);
    if (i < 0) continue;
    choiceShown.push(i);
    const g = transEls[i];
    g.setAttribute('data-policy', String(p));
    if (cvs.on) continue;
    const [, hh] = transitionHalf(net.transitions[i]);
    g.choice = el('text', { class: 'choice', y: -hh - 18 }, g);
    g.choice.textContent = 'policy ' + fmt(p);
    el('title', {}, g.choice).textContent = 'rule ' + (choice.rule + 1) + ' of the plan policy';
  }
}

function applyState(s) {
  state = s;
  s.tokens.forEach((k, i) => setTokens(i, k));
  setAllEnabled(s.firable);
  setChoice(s.choice);
  recordTokens(s.time, s.tokens);
  scheduleFollowDraw();
  const last = s.trace.length ? s.trace[s.trace.length - 1] : null;
  setFired(last ? transitionIndex(last.transition) : -1);
  if (document.activeElement !== $('seed')) $('seed').value = s.seed;
  $('clock').textContent =
    'time ' + fmt(s.time) + ', ' + s.firings + ' firings' +
    (s.dead ? ' — dead marking' : s.vanishing ? ' — vanishing' : '');
  $('marking-text').textContent = shorten(s.text, 2000);
  const ol = $('trace');
  const follow = atBottom(ol);
  ol.textContent = '';
  for (const e of s.trace) {
    const li = listItem(e.step, fmtTime(e.time) + '  ' + e.transition + '  → ' + shorten(e.marking, 160));
    li.title = timeTitle(e.time);
    if (e.manual) li.classList.add('manual');
    ol.appendChild(li);
  }
  applyFilter(ol, $('trace-filter'));
  $('trace-count').textContent = s.firings > s.trace.length
    ? 'last ' + s.trace.length + ' of ' + s.firings : s.firings + ' firings';
  if (follow) ol.scrollTop = ol.scrollHeight;
  if (s.dead) stopRun();
}

// ---- pan, zoom, drag -------------------------------------------------------------------

function applyView() {
  $('viewport').setAttribute('transform', 'translate(' + view.x + ',' + view.y + ') scale(' + view.k + ')');
  canvasDirty();
  viewChanged();
}

// Whether the view is the fitted one (a resize then fits again); panning or zooming by hand
// keeps the user's view.
let fitted = false;
// Whether the fitted view is the whole net (`fit`, key f) or the readable one (on opening,
// and after a resize): names at least READ_PX high, the rest a pan away.
let fittedWhole = false;
// Smallest on-screen size of a name (11 px at zoom 1) in the readable view.
const READ_PX = 10;
// Past this many nodes the readable view would show a sliver of the net: it opens whole.
const READ_MAX_NODES = 1500;

function fit(whole) {
  fitted = true;
  fittedWhole = whole === true;
  const box = $('canvas');
  const all = net.places.concat(net.transitions);
  if (!all.length) return;
  let [xa, ya, xb, yb] = [Infinity, Infinity, -Infinity, -Infinity];
  const grow = (x, y) => {
    xa = Math.min(xa, x);
    ya = Math.min(ya, y);
    xb = Math.max(xb, x);
    yb = Math.max(yb, y);
  };
  for (const n of all) grow(n.x, n.y);
  // Routed arcs may run round the outside of the nodes.
  for (const a of net.arcs) for (const q of a.points) grow(q[0] + 60, q[1] + 30);
  for (const a of net.arcs) for (const q of a.points) grow(q[0] - 60, q[1] - 30);
  // Room for the labels, which are wider than the nodes.
  const x0 = xa - 90;
  const y0 = ya - 50;
  const w = xb + 90 - x0;
  const h = yb + 60 - y0;
  const k = Math.min(box.clientWidth / w, box.clientHeight / h, 2);
  nav.fitK = k;
  view = { k, x: -x0 * k + (box.clientWidth - w * k) / 2, y: -y0 * k + (box.clientHeight - h * k) / 2 };
  const read = READ_PX / 11;
  if (!fittedWhole && k < read && all.length <= READ_MAX_NODES) {
    // Too small to read: zoom to where names are READ_PX high, with the top left marked
    // place (where the layered layout starts) near the top left corner of the window, and
    // nothing left of or above the net shown; pan for the rest.
    const marked = net.places.filter((p) => p.tokens > 0);
    const anchor = (marked.length ? marked : all).reduce((a, b) => (b.x + b.y < a.x + a.y ? b : a));
    view.k = read;
    view.x = w * read <= box.clientWidth ? -x0 * read + (box.clientWidth - w * read) / 2
      : Math.min(-x0 * read, 120 - anchor.x * read);
    view.y = h * read <= box.clientHeight ? -y0 * read + (box.clientHeight - h * read) / 2
      : Math.min(-y0 * read, 100 - anchor.y * read);
  }
  applyView();
}

// The node under a mouse event: {isPlace, i} or null.
function eventNode(ev) {
  if (cvs.on) {
    const rect = cvs.el.getBoundingClientRect();
    return nodeAt(ev.clientX - rect.left, ev.clientY - rect.top);
  }
  const g = ev.target.closest('.node');
  return g ? { isPlace: g.classList.contains('place'), i: Number(g.dataset.index) } : null;
}

function setupInteraction() {
  const box = $('canvas');
  let drag = null;
  box.addEventListener('wheel', (ev) => {
    ev.preventDefault();
    const rect = box.getBoundingClientRect();
    const mx = ev.clientX - rect.left;
    const my = ev.clientY - rect.top;
    zoomAbout(mx, my, Math.exp(-ev.deltaY * 0.001));
    fitted = false;
    applyView();
  }, { passive: false });
  box.addEventListener('mousedown', (ev) => {
    if (!net) return;
    const node = eventNode(ev);
    drag = { node, sx: ev.clientX, sy: ev.clientY, moved: false };
    if (!node) box.classList.add('panning');
  });
  window.addEventListener('mousemove', (ev) => {
    if (!drag) return;
    const dx = ev.clientX - drag.sx;
    const dy = ev.clientY - drag.sy;
    if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
    drag.sx = ev.clientX;
    drag.sy = ev.clientY;
    if (!drag.node) {
      view.x += dx;
      view.y += dy;
      fitted = false;
      applyView();
      return;
    }
    const { isPlace, i } = drag.node;
    const node = isPlace ? net.places[i] : net.transitions[i];
    node.x += dx / view.k;
    node.y += dy / view.k;
    if (!cvs.on) move((isPlace ? placeEls : transEls)[i], node);
    for (const a of (isPlace ? arcsOfPlace : arcsOfTransition)[i]) drawArc(a);
    canvasViewChanged();
  });
  window.addEventListener('mouseup', (ev) => {
    const d = drag;
    drag = null;
    box.classList.remove('panning');
    if (editMouseUp(d, ev)) return;
    if (d && d.node && !d.moved && !d.node.isPlace && transEnabled[d.node.i] && state) {
      fire(net.transitions[d.node.i].name);
    }
    if (d && d.node && !d.moved && d.node.isPlace) {
      if (ev.shiftKey) selectPlace(d.node.i, undefined, true);
      else selectPlace(follow.place === d.node.i ? -1 : d.node.i);
    }
  });
}


// Positions back in the file's units, as a GreatSPN project the browser downloads.
async function saveLayout() {
  try {
    // The automatic layout of a file with positions is written in the file's own units
    // (as the page would scale the file's positions), so it opens at the same size.
    const o = net.other_layout;
    const units = net.layout === 'layered' && o && o.layout === 'file'
      ? scale * nearestScale(o.places.concat(o.transitions)) : scale;
    const at = (n) => [n.x / units, n.y / units];
    const r = await api('POST', '/api/layout', {
      places: net.places.map(at),
      transitions: net.transitions.map(at),
    });
    const a = document.createElement('a');
    a.href = URL.createObjectURL(new Blob([r.pnpro], { type: 'application/xml' }));
    a.download = r.file || net.name + '.PNPRO';
    a.click();
    URL.revokeObjectURL(a.href);
  } catch (e) {
    status(e.message);
  }
}

// ---- token game ------------------------------------------------------------------------

async function act(method, path, body) {
  if (busy) return;
  busy = true;
  try {
    applyState(await api(method, path, body));
    status('');
    online();
  } catch (e) {
    status(e.message);
    offline(e);
    stopRun();
  } finally {
    busy = false;
  }
}

function fire(name) {
  return act('POST', '/api/sim/fire', { transition: name });
}

function stopRun() {
  if (runTimer !== null) clearInterval(runTimer);
  runTimer = null;
  $('run').textContent = 'run';
}

function startRun() {
  stopRun();
  const speed = Number($('speed').value) || 1;
  runTimer = setInterval(() => act('POST', '/api/sim/step', { n: 1 }), 1000 / speed);
  $('run').textContent = 'pause';
}

function setupControls() {
  $('step').addEventListener('click', () => act('POST', '/api/sim/step', { n: 1 }));
  $('step-n').addEventListener('click', () =>
    act('POST', '/api/sim/step', { n: Math.max(1, Number($('n').value) || 1) }));
  $('reset').addEventListener('click', () => {
    stopRun();
    const seed = Number($('seed').value);
    act('POST', '/api/sim/reset', Number.isSafeInteger(seed) && seed >= 0 ? { seed } : {});
  });
  $('run').addEventListener('click', () => {
    if (!state) return; // replay and live modes drive #run themselves
    if (runTimer === null) startRun();
    else stopRun();
  });
  $('speed').addEventListener('input', () => {
    $('speed-value').textContent = $('speed').value;
    if (runTimer !== null) startRun();
  });
  $('fit').addEventListener('click', () => fit(true));
  $('save-layout').addEventListener('click', saveLayout);
  $('layout-choice').addEventListener('change', chooseLayout);
  $('analyze').addEventListener('click', analyse);
  // The same button stops a running question (transient points) or the analysis.
  $('analysis-cancel').addEventListener('click', () => (asking ? cancelQuestion() :
    api('POST', '/api/analysis/cancel').then(showProgress).catch((e) => status(e.message))));
}

// ---- keys, theme, resize -----------------------------------------------------------------

// Keyboard shortcuts (not while typing in a field); `?` lists them.
const KEYS = [
  ['s', 'step', () => $('step').click()],
  ['n', 'step n', () => $('step-n').click()],
  ['r', 'run / pause', () => $('run').click()],
  ['0', 'reset', () => $('reset').click()],
  ['f', 'fit the whole net in the view', () => fit(true)],
  ['a', 'analyse', () => $('analyze').click()],
  ['g', 'find a place or transition by name', () => $('search').focus()],
  [' ', 'replay: play / pause', () => $('play').click()],
  ['ArrowLeft', 'replay: one firing back', () => $('step-back').click()],
  ['ArrowRight', 'replay: one firing on', () => $('step-forward').click()],
  ['/', 'filter the trace / events', () => {
    const box = $('log-panel').classList.contains('hidden') ? $('trace-filter') : $('log-filter');
    box.focus();
  }],
  ['?', 'show / hide this list', () => $('help').classList.toggle('hidden')],
  ['Escape', 'close this list', () => $('help').classList.add('hidden')],
];

function setupKeys() {
  const list = $('help-keys');
  for (const [key, what] of KEYS) {
    const dt = document.createElement('dt');
    dt.textContent = { Escape: 'Esc', ' ': 'space', ArrowLeft: '←', ArrowRight: '→', Delete: 'Del' }[key] || key;
    const dd = document.createElement('dd');
    dd.textContent = what;
    list.append(dt, dd);
  }
  document.addEventListener('keydown', (ev) => {
    const t = ev.target;
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    if (t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.isContentEditable)) {
      if (ev.key === 'Escape') t.blur();
      return;
    }
    const k = KEYS.find(([key]) => key === ev.key);
    if (!k) return;
    ev.preventDefault();
    k[2]();
  });
  $('help-close').addEventListener('click', () => $('help').classList.add('hidden'));
  $('help-open').addEventListener('click', () => $('help').classList.toggle('hidden'));
}

// `?theme=dark` or `?theme=light` forces a theme; otherwise the system's (prefers-color-scheme).
function setupTheme() {
  const forced = new URLSearchParams(location.search).get('theme');
  if (forced === 'dark' || forced === 'light') document.documentElement.dataset.theme = forced;
}

function setupResize() {
  let pending = false;
  window.addEventListener('resize', () => {
    if (!fitted || !net || pending) return;
    pending = true;
    requestAnimationFrame(() => {
      pending = false;
      fit(fittedWhole);
    });
  });
}

// ---- start -----------------------------------------------------------------------------

async function main() {
  setupTheme();
  setupControls();
  setupInteraction();
  setupEdit();
  setupKeys();
  setupResize();
  setupPanes();
  setupThroughput();
  setupExport();
  setupNavigate();
  for (const [list, box] of [['trace', 'trace-filter'], ['log', 'log-filter']]) {
    $(box).addEventListener('input', () => applyFilter($(list), $(box)));
  }
  try {
    const mode = await api('GET', '/api/mode');
    if (mode.live) {
      startLive();
      return;
    }
    const n = await api('GET', '/api/net');
    adoptLayout(n);
    net = n;
    showTitle();
    document.title = net.name + ' — gspn';
    scaleCoordinates();
    drawNet();
    fit();
    if (mode.replay) {
      await startReplay();
      initMaxStates();
      markDrawn();
      return;
    }
    applyState(await api('GET', '/api/sim/state'));
    initMaxStates();
    initEdit();
    markDrawn();
    followSession();
  } catch (e) {
    status(e.message);
    offline(e);
  }
}

main();
