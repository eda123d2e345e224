// gspn viewer, live runs with a simulated world (LiveRun::with_world): a 2D map beside the
// net — walls, obstacles, the topological map's locations (named) and edges, robots as
// circles with their ids — updated with every state frame. World units are metres, y up.
//
// Test hooks: each robot's <g> carries data-robot="ID" data-x data-y (metres, as sent);
// each location's data-location="NAME".
'use strict';

const map = { key: null, robots: new Map(), size: 1, font: 0, fontDirty: true };
new ResizeObserver(() => { map.fontDirty = true; }).observe(document.getElementById('map'));

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
    const t = mapEl('text', { y: Math.max(s * 0.35, robotR) + s * 1.1, 'font-size': s, class: 'location-name' }, lg);
    t.textContent = l.name;
  }
  map.font = 0;
}

// Names at least 11 px high on the screen whatever the room's size (metres per pixel change
// with the pane's size): the font size in metres.
function mapFont() {
  const svg = $('map');
  const vb = svg.viewBox.baseVal;
  const r = svg.getBoundingClientRect();
  const pxPerMetre = vb && vb.width > 0 && r.width > 0 ? Math.min(r.width / vb.width, r.height / vb.height) : 0;
  return pxPerMetre > 0 ? Math.max(map.size * 0.9, 11 / pxPerMetre) : map.size * 0.9;
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
      const t = mapEl('text', { 'font-size': map.font || map.size * 0.9 }, g);
      t.style.fill = robotColour(id);
      map.robots.set(id, g);
    }
    // The agent it carries changes as it goes.
    const label = id + (r.agent !== undefined && r.agent !== null ? ' (' + r.agent + ')' : '');
    const t = g.querySelector('text');
    if (t.textContent !== label) {
      t.textContent = label;
      g.labelWidth = undefined;
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
  // The font follows the pane's size: measured again only after a resize or a new map
  // (reading the layout on every frame would cost each frame a reflow).
  const font = map.fontDirty || map.font === 0 ? mapFont() : map.font;
  map.fontDirty = false;
  if (Math.abs(font - map.font) > 1e-9) {
    map.font = font;
    for (const t of $('map').querySelectorAll('.robot text, .location-name')) t.setAttribute('font-size', String(font));
    for (const g of map.robots.values()) g.labelWidth = undefined;
  }
  placeRobotLabels(w.robots || []);
  const n = (w.robots || []).length;
  $('map-time').textContent = 'sim time ' + fmt(w.time || 0) + ' s, ' + n + ' robot' + (n === 1 ? '' : 's') +
    ($('map-panel').classList.contains('stopped') ? ' — stopped' : '');
}

// Puts each robot's name where it overlaps no other name and no robot: above it if that is
// free, else below, beside, then further up or down (robots queued side by side at a
// location would otherwise write their names over each other). Names are in the robot's
// colour, so a name set further off still reads as its robot's. Greedy, in id order:
// deterministic, and at most a few thousand box tests for 64 robots.
function placeRobotLabels(robots) {
  const s = map.size;
  const h = map.font || s * 0.9; // the font size: a line's height
  const gap = s * 0.2;
  const discs = robots.map((r) => ({ x: r.x, y: -r.y, r: r.radius || s * 0.4 }));
  const placed = [];
  const hits = (b) => placed.some((o) => b.x0 < o.x1 && o.x0 < b.x1 && b.y0 < o.y1 && o.y0 < b.y1) ||
    discs.some((d) => d.x + d.r > b.x0 && d.x - d.r < b.x1 && d.y + d.r > b.y0 && d.y - d.r < b.y1);
  const order = robots.map((r, i) => i).sort((a, b) => String(robots[a].id).localeCompare(String(robots[b].id), 'en', { numeric: true }));
  for (const i of order) {
    const r = robots[i];
    const g = map.robots.get(String(r.id));
    if (!g) continue;
    const t = g.querySelector('text');
    if (g.labelWidth === undefined) g.labelWidth = t.getComputedTextLength() || h * 0.6 * t.textContent.length;
    const w = g.labelWidth;
    const rad = discs[i].r;
    const cx = r.x;
    const cy = -r.y;
    // Candidate baselines (dy) and centres (dx) relative to the robot, nearest first. A
    // name's box reaches 0.95 of the font size above its baseline and 0.3 below (what the
    // browser's glyph boxes measure), rows are 1.25 apart.
    const up = 0.95 * h;
    const down = 0.3 * h;
    const row = 1.25 * h;
    const cands = [[0, -rad - gap - down], [0, rad + gap + up], [rad + gap + w / 2, h * 0.3], [-rad - gap - w / 2, h * 0.3]];
    for (let k = 1; k <= 8; k++) {
      cands.push([0, -rad - gap - down - k * row], [0, rad + gap + up + k * row]);
    }
    const boxAt = ([dx, dy]) => ({ x0: cx + dx - w / 2, x1: cx + dx + w / 2, y0: cy + dy - up, y1: cy + dy + down });
    let best = cands[0];
    let box = null;
    for (const c of cands) {
      const b = boxAt(c);
      if (!hits(b)) {
        best = c;
        box = b;
        break;
      }
    }
    if (!box) box = boxAt(best);
    placed.push(box);
    t.setAttribute('x', String(best[0]));
    t.setAttribute('y', String(best[1]));
  }
}
