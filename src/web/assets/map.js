// gspn viewer, live runs with a simulated world (LiveRun::with_world): a 2D map beside the
// net — walls, obstacles, the topological map's locations (named) and edges, robots as
// circles with their ids — updated with every state frame. World units are metres, y up.
//
// Test hooks: each robot's <g> carries data-robot="ID" data-x data-y (metres, as sent);
// each location's data-location="NAME".
'use strict';

const map = { key: null, robots: new Map(), size: 1 };

function mapEl(tag, attrs, parent) {
  return el(tag, attrs, parent);
}

// Bounds of everything static and of the robots, as [x0, y0, x1, y1].
function worldBounds(w) {
  let b = [Infinity, Infinity, -Infinity, -Infinity];
  const add = (x, y) => {
    b = [Math.min(b[0], x), Math.min(b[1], y), Math.max(b[2], x), Math.max(b[3], y)];
  };
  const m = w.map || {};
  for (const l of m.locations || []) add(l.x, l.y);
  for (const [x1, y1, x2, y2] of m.walls || []) {
    add(x1, y1);
    add(x2, y2);
  }
  for (const o of m.obstacles || []) {
    add(o.x, o.y);
    add(o.x + o.w, o.y + o.h);
  }
  for (const r of w.robots || []) {
    add(r.x - (r.radius || 0), r.y - (r.radius || 0));
    add(r.x + (r.radius || 0), r.y + (r.radius || 0));
  }
  if (!Number.isFinite(b[0])) b = [0, 0, 1, 1];
  return b;
}

// The static layer: drawn again only when the map changes.
function drawMapStatic(w) {
  const svg = $('map');
  const [x0, y0, x1, y1] = worldBounds(w);
  const span = Math.max(x1 - x0, y1 - y0, 1);
  const pad = span * 0.06;
  // y up: a point (x, y) is drawn at (x, -y).
  svg.setAttribute('viewBox', [x0 - pad, -y1 - pad, x1 - x0 + 2 * pad, y1 - y0 + 2 * pad].join(' '));
  map.size = span / 45; // font size and marker size, in metres
  const g = $('map-static');
  g.textContent = '';
  $('map-robots').textContent = '';
  map.robots.clear();
  const m = w.map || {};
  for (const o of m.obstacles || []) {
    mapEl('rect', { class: 'obstacle', x: o.x, y: -(o.y + o.h), width: o.w, height: o.h }, g);
  }
  for (const [xa, ya, xb, yb] of m.walls || []) {
    mapEl('line', { class: 'wall', x1: xa, y1: -ya, x2: xb, y2: -yb }, g);
  }
  const at = new Map((m.locations || []).map((l) => [l.name, l]));
  for (const [a, b] of m.edges || []) {
    const p = at.get(a);
    const q = at.get(b);
    if (p && q) mapEl('line', { class: 'edge', x1: p.x, y1: -p.y, x2: q.x, y2: -q.y }, g);
  }
  const s = map.size;
  // Names below the marker, clear of a robot standing on it (robot names go above).
  const robotR = Math.max(0, ...(w.robots || []).map((r) => r.radius || 0));
  for (const l of m.locations || []) {
    const lg = mapEl('g', { class: 'location', 'data-location': l.name,
      transform: 'translate(' + l.x + ',' + -l.y + ')' }, g);
    mapEl('rect', { x: -s * 0.35, y: -s * 0.35, width: s * 0.7, height: s * 0.7 }, lg);
    const t = mapEl('text', { y: Math.max(s * 0.35, robotR) + s * 1.1, 'font-size': s }, lg);
    t.textContent = l.name;
  }
}

const ROBOT_COLOURS = ['#d9480f', '#1971c2', '#2f9e44', '#ae3ec9', '#f08c00', '#0c8599', '#c2255c', '#5c940d'];

// A colour per robot id (FNV-1a hash), the same on every page.
function robotColour(id) {
  let h = 2166136261;
  for (const c of String(id)) h = Math.imul(h ^ c.charCodeAt(0), 16777619) >>> 0;
  return ROBOT_COLOURS[h % ROBOT_COLOURS.length];
}

// Draws (or moves) the world of a live state frame.
function drawWorld(w) {
  const panel = $('map-panel');
  if (panel.classList.contains('hidden')) {
    // The net's side got narrower: fit it again.
    panel.classList.remove('hidden');
    if (net) fit();
  }
  const key = JSON.stringify(w.map || {});
  if (key !== map.key) {
    map.key = key;
    drawMapStatic(w);
  }
  const seen = new Set();
  const layer = $('map-robots');
  for (const r of w.robots || []) {
    const id = String(r.id);
    seen.add(id);
    let g = map.robots.get(id);
    if (!g) {
      g = mapEl('g', { class: 'robot', 'data-robot': id }, layer);
      g.addEventListener('click', () => selectRobot(id));
      const c = mapEl('circle', { r: r.radius || map.size * 0.4 }, g);
      c.style.fill = robotColour(id);
      const t = mapEl('text', { 'font-size': map.size * 0.9, y: -(r.radius || map.size * 0.4) - map.size * 0.2 }, g);
      t.textContent = id + (r.agent !== undefined && r.agent !== null ? ' (' + r.agent + ')' : '');
      map.robots.set(id, g);
    }
    g.setAttribute('data-x', String(r.x));
    g.setAttribute('data-y', String(r.y));
    g.setAttribute('transform', 'translate(' + r.x + ',' + -r.y + ')');
  }
  for (const [id, g] of map.robots) {
    if (!seen.has(id)) {
      g.remove();
      map.robots.delete(id);
    }
  }
  const n = (w.robots || []).length;
  $('map-time').textContent = 'sim time ' + fmt(w.time || 0) + ' s, ' + n + ' robot' + (n === 1 ? '' : 's') +
    ($('map-panel').classList.contains('stopped') ? ' — stopped' : '');
}
