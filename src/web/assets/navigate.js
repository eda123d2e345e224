// gspn viewer, large nets: find a place or transition by name (the view zooms to it), a
// minimap of the whole net with the window's rectangle (click or drag in it to move there),
// labels that appear as the view zooms in, and zoom limits.
//
// Test hooks: the found node's <g> (or canvas hook) has data-found="true";
// window.gspnView() gives {x, y, k, fitK, min, max}; #minimap is the minimap's canvas.
'use strict';

// Most zoom: a node's name at 11 px × 8.
const ZOOM_MAX = 8;
// Least zoom, as a share of the zoom that fits the net: the whole net at a quarter of the
// window's size.
const ZOOM_OUT = 0.25;
// Names show when they are at least this many pixels high; rates and weights from PARAM_PX.
const LABEL_PX = 4.5;
const PARAM_PX = 6.5;

const nav = { fitK: 1, found: null, mini: null };

function zoomRange() {
  return [Math.min(nav.fitK * ZOOM_OUT, ZOOM_MAX), ZOOM_MAX];
}

// Zooms by factor `f` about the point (mx, my) of the window, within the limits.
function zoomAbout(mx, my, f) {
  const [lo, hi] = zoomRange();
  const k = Math.min(hi, Math.max(lo, view.k * f));
  const g = k / view.k;
  view.x = mx - (mx - view.x) * g;
  view.y = my - (my - view.y) * g;
  view.k = k;
}

// Labels by zoom (SVG; the canvas decides for itself), and the minimap's rectangle.
function viewChanged() {
  const svg = $('net');
  svg.classList.toggle('no-labels', view.k * 11 < LABEL_PX);
  svg.classList.toggle('no-params', view.k * 10 < PARAM_PX);
  drawMinimapWindow();
}

// ---- search ------------------------------------------------------------------------------

// The node named `query`: an exact name first, then the first name that contains it (case
// ignored), places before transitions. {isPlace, i} or null.
function findNode(query) {
  const q = query.trim();
  if (!q || !net) return null;
  const exact = (list) => list.findIndex((n) => n.name === q);
  let i = exact(net.places);
  if (i >= 0) return { isPlace: true, i };
  i = exact(net.transitions);
  if (i >= 0) return { isPlace: false, i };
  const low = q.toLowerCase();
  const part = (list) => list.findIndex((n) => n.name.toLowerCase().includes(low));
  i = part(net.places);
  if (i >= 0) return { isPlace: true, i };
  i = part(net.transitions);
  return i >= 0 ? { isPlace: false, i } : null;
}

// Centres the view on `found` at a zoom where its name reads (at least 1.5).
function zoomTo(found) {
  const node = found.isPlace ? net.places[found.i] : net.transitions[found.i];
  const box = $('canvas');
  view.k = Math.min(ZOOM_MAX, Math.max(view.k, 1.5));
  view.x = box.clientWidth / 2 - node.x * view.k;
  view.y = box.clientHeight / 2 - node.y * view.k;
  fitted = false;
  if (nav.found) nav.found.removeAttribute('data-found');
  nav.found = (found.isPlace ? placeEls : transEls)[found.i];
  nav.found.setAttribute('data-found', 'true');
  applyView();
}

function search() {
  const q = $('search').value;
  const found = findNode(q);
  if (!found) {
    status(q.trim() ? 'no place or transition named “' + q.trim() + '”' : '');
    return;
  }
  status('');
  zoomTo(found);
}

function fillNames() {
  const list = $('node-names');
  list.textContent = '';
  // A datalist of every name helps up to a few thousand; past that typing is faster.
  for (const n of net.places.concat(net.transitions).slice(0, 5000)) {
    const o = document.createElement('option');
    o.value = n.name;
    list.appendChild(o);
  }
}

// ---- minimap -----------------------------------------------------------------------------

// The net's bounds and the minimap's scale, set when the net is drawn.
function drawMinimap() {
  const c = $('minimap');
  const all = net.places.concat(net.transitions);
  if (!all.length) return;
  let [xa, ya, xb, yb] = [Infinity, Infinity, -Infinity, -Infinity];
  for (const n of all) {
    xa = Math.min(xa, n.x);
    ya = Math.min(ya, n.y);
    xb = Math.max(xb, n.x);
    yb = Math.max(yb, n.y);
  }
  const pad = 40;
  [xa, ya, xb, yb] = [xa - pad, ya - pad, xb + pad, yb + pad];
  const W = 150;
  const s = W / Math.max(xb - xa, (yb - ya) * 1.5, 1);
  const H = Math.max(40, Math.round((yb - ya) * s));
  const dpr = window.devicePixelRatio || 1;
  c.width = W * dpr;
  c.height = H * dpr;
  c.style.width = W + 'px';
  c.style.height = H + 'px';
  nav.mini = { xa, ya, s, W, H, dpr, base: null };
  const base = document.createElement('canvas');
  base.width = c.width;
  base.height = c.height;
  const g = base.getContext('2d');
  g.scale(dpr, dpr);
  g.fillStyle = getComputedStyle(document.documentElement).getPropertyValue('--muted') || '#666';
  for (const n of all) g.fillRect((n.x - xa) * s - 0.75, (n.y - ya) * s - 0.75, 1.5, 1.5);
  nav.mini.base = base;
  $('minimap-box').classList.remove('hidden');
  drawMinimapWindow();
}

// The window's rectangle over the minimap's nodes.
function drawMinimapWindow() {
  const m = nav.mini;
  if (!m || !m.base) return;
  const c = $('minimap');
  const g = c.getContext('2d');
  g.setTransform(1, 0, 0, 1, 0, 0);
  g.clearRect(0, 0, c.width, c.height);
  g.drawImage(m.base, 0, 0);
  g.setTransform(m.dpr, 0, 0, m.dpr, 0, 0);
  const box = $('canvas');
  // The window in net units, then in minimap pixels.
  const x0 = (-view.x / view.k - m.xa) * m.s;
  const y0 = (-view.y / view.k - m.ya) * m.s;
  const w = box.clientWidth / view.k * m.s;
  const h = box.clientHeight / view.k * m.s;
  g.strokeStyle = getComputedStyle(document.documentElement).getPropertyValue('--accent') || '#06c';
  g.lineWidth = 1.5;
  g.strokeRect(x0, y0, w, h);
}

// Click or drag in the minimap: the window's centre goes there.
function setupMinimap() {
  const c = $('minimap');
  let dragging = false;
  const go = (ev) => {
    const m = nav.mini;
    if (!m) return;
    const r = c.getBoundingClientRect();
    const nx = (ev.clientX - r.left) / m.s + m.xa;
    const ny = (ev.clientY - r.top) / m.s + m.ya;
    const box = $('canvas');
    view.x = box.clientWidth / 2 - nx * view.k;
    view.y = box.clientHeight / 2 - ny * view.k;
    fitted = false;
    applyView();
  };
  c.addEventListener('mousedown', (ev) => {
    ev.stopPropagation();
    ev.preventDefault();
    dragging = true;
    go(ev);
  });
  window.addEventListener('mousemove', (ev) => {
    if (dragging) go(ev);
  });
  window.addEventListener('mouseup', () => {
    dragging = false;
  });
}

function setupNavigate() {
  window.gspnView = () => {
    const [min, max] = zoomRange();
    return { x: view.x, y: view.y, k: view.k, fitK: nav.fitK, min, max };
  };
  $('search').addEventListener('change', search);
  $('search').addEventListener('keydown', (ev) => {
    if (ev.key === 'Enter') search();
  });
  setupMinimap();
}
