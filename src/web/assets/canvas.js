// gspn viewer, large nets: past BIG nodes the net is drawn on one <canvas> instead of an SVG
// element per node, which a browser cannot repaint fast enough (10,000 places: seconds to
// open, ~0.4 s per live frame). The test hooks stay in the DOM, on hidden <span>s: one per
// place (data-place, data-tokens) and per transition (data-transition, data-enabled).
//
// The canvas is redrawn whole on the next frame after any change (one path per kind of
// shape, nodes outside the window skipped, labels and token dots only when zoomed in enough
// to read them). app.js calls: canvasInit, canvasHooks, canvasDirty, nodeAt.
'use strict';

// Places + transitions past which the canvas is used.
const BIG = 1500;

const cvs = { on: false, el: null, ctx: null, dirty: false, arcPts: [], base: null, baseKey: null };

function canvasInit() {
  // `?renderer=svg` or `?renderer=canvas` forces one (to compare them).
  const forced = new URLSearchParams(location.search).get('renderer');
  cvs.on = forced ? forced === 'canvas' : net.places.length + net.transitions.length > BIG;
  cvs.el = $('net-canvas');
  $('net').classList.toggle('hidden', cvs.on);
  cvs.el.classList.toggle('hidden', !cvs.on);
  if (!cvs.on) return false;
  cvs.ctx = cvs.el.getContext('2d', { alpha: false });
  window.addEventListener('resize', canvasViewChanged);
  return true;
}

// Hidden elements carrying the test hooks, in the order of the net.
function canvasHooks() {
  const box = $('hooks');
  box.textContent = '';
  const frag = document.createDocumentFragment();
  const places = [];
  const transitions = [];
  net.places.forEach((p, i) => {
    const s = document.createElement('span');
    s.setAttribute('data-place', p.name);
    s.setAttribute('data-tokens', '');
    s.dataset.index = i;
    frag.appendChild(s);
    places.push(s);
  });
  net.transitions.forEach((t, i) => {
    const s = document.createElement('span');
    s.setAttribute('data-transition', t.name);
    s.setAttribute('data-enabled', 'false');
    s.dataset.index = i;
    frag.appendChild(s);
    transitions.push(s);
  });
  box.appendChild(frag);
  cvs.arcPts = net.arcs.map((_, i) => arcPoints(i));
  cvs.baseKey = null;
  return { places, transitions };
}

// An arc's end points moved (a node was dragged).
function canvasArcMoved(i) {
  cvs.arcPts[i] = arcPoints(i);
  cvs.baseKey = null;
}

function canvasDirty() {
  if (!cvs.on || cvs.dirty) return;
  cvs.dirty = true;
  requestAnimationFrame(canvasDraw);
}

// The node under the window point (x, y) relative to the canvas: {isPlace, i} or null.
function nodeAt(x, y) {
  const wx = (x - view.x) / view.k;
  const wy = (y - view.y) / view.k;
  let best = null;
  let bestD = Infinity;
  net.places.forEach((p, i) => {
    const d = Math.hypot(p.x - wx, p.y - wy);
    if (d <= R && d < bestD) {
      best = { isPlace: true, i };
      bestD = d;
    }
  });
  net.transitions.forEach((t, i) => {
    const hw = transitionWidth(t) / 2;
    if (Math.abs(t.x - wx) <= hw && Math.abs(t.y - wy) <= TH / 2) {
      const d = Math.hypot(t.x - wx, t.y - wy);
      if (d < bestD) {
        best = { isPlace: false, i };
        bestD = d;
      }
    }
  });
  return best;
}

// A colour of the page's theme (its CSS variable), so that the canvas follows the dark theme
// like the SVG; read once per theme.
const inks = new Map();
let inkTheme = null;
const darkScheme = window.matchMedia('(prefers-color-scheme: dark)');
function ink(name) {
  const theme = (document.documentElement.dataset.theme || '') + darkScheme.matches;
  if (theme !== inkTheme) {
    inks.clear();
    inkTheme = theme;
  }
  if (!inks.has(name)) inks.set(name, getComputedStyle(document.documentElement).getPropertyValue(name).trim() || '#888');
  return inks.get(name);
}

// Everything that changes only with the view or the layout: arcs, empty places, transitions
// at rest, names and parameters. Kept as a bitmap; a live update paints the marking over it.
function drawBase(ctx, w, h, dpr) {
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.fillStyle = ink('--bg');
  ctx.fillRect(0, 0, w, h);
  const k = view.k;
  ctx.setTransform(dpr * k, 0, 0, dpr * k, dpr * view.x, dpr * view.y);
  const inside = visibleTest(w, h);
  const px = 1 / k; // one screen pixel in net units

  // Arcs: one path per colour; arrow heads once they are a few pixels long.
  const heads = k > 0.25;
  const arcPath = (kind) => {
    ctx.beginPath();
    net.arcs.forEach((a, i) => {
      if ((a.kind === 'inhibitor') !== (kind === 'inhibitor')) return;
      if (!inside(net.places[a.place]) && !inside(net.transitions[a.transition])) return;
      const pts = cvs.arcPts[i];
      ctx.moveTo(pts[0][0], pts[0][1]);
      for (let j = 1; j < pts.length; j++) ctx.lineTo(pts[j][0], pts[j][1]);
      if (heads && kind !== 'inhibitor') {
        const [ex, ey] = pts[pts.length - 1];
        const [sx, sy] = pts[pts.length - 2];
        const d = Math.hypot(ex - sx, ey - sy) || 1;
        const ux = (ex - sx) / d;
        const uy = (ey - sy) / d;
        ctx.moveTo(ex - 8 * ux - 4 * uy, ey - 8 * uy + 4 * ux);
        ctx.lineTo(ex, ey);
        ctx.lineTo(ex - 8 * ux + 4 * uy, ey - 8 * uy - 4 * ux);
      }
    });
  };
  ctx.lineWidth = Math.max(1.2, px);
  ctx.strokeStyle = ink('--arc');
  arcPath('normal');
  ctx.stroke();
  ctx.strokeStyle = ink('--inhib');
  arcPath('inhibitor');
  ctx.stroke();
  if (heads) {
    ctx.fillStyle = ink('--bg');
    ctx.beginPath();
    net.arcs.forEach((a, i) => {
      if (a.kind !== 'inhibitor' || !inside(net.transitions[a.transition])) return;
      const pts = cvs.arcPts[i];
      const [ex, ey] = pts[pts.length - 1];
      ctx.moveTo(ex + 4, ey);
      ctx.arc(ex, ey, 4, 0, 2 * Math.PI);
    });
    ctx.fill();
    ctx.stroke();
  }

  ctx.lineWidth = Math.max(1.5, px);
  ctx.strokeStyle = ink('--stroke');
  ctx.fillStyle = ink('--node');
  ctx.beginPath();
  net.places.forEach((p) => {
    if (!inside(p)) return;
    ctx.moveTo(p.x + R, p.y);
    ctx.arc(p.x, p.y, R, 0, 2 * Math.PI);
  });
  ctx.fill();
  ctx.stroke();
  transitionRects(ctx, inside, (t) => t.kind === 'immediate', ink('--stroke'), ink('--stroke'), 1.5, px);
  transitionRects(ctx, inside, (t) => t.kind !== 'immediate', ink('--node'), ink('--stroke'), 1.5, px);

  if (k < 0.6) return;
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  ctx.font = '11px system-ui, sans-serif';
  ctx.fillStyle = ink('--fg');
  for (const n of net.places.concat(net.transitions)) {
    if (inside(n)) ctx.fillText(n.name, n.x, n.y + (n.kind ? TH / 2 : R) + 10);
  }
  ctx.font = '10px system-ui, sans-serif';
  ctx.fillStyle = ink('--muted');
  net.transitions.forEach((t) => {
    if (inside(t)) ctx.fillText(paramText(t), t.x, t.y - TH / 2 - 7);
  });
}

// A test for "near the window", in net coordinates, with a node's margin.
function visibleTest(w, h) {
  const k = view.k;
  const m = 40;
  const x0 = -view.x / k - m;
  const y0 = -view.y / k - m;
  const x1 = (w - view.x) / k + m;
  const y1 = (h - view.y) / k + m;
  return (n) => n.x >= x0 && n.x <= x1 && n.y >= y0 && n.y <= y1;
}

function transitionRects(ctx, inside, filter, fill, stroke, lw, px) {
  ctx.beginPath();
  net.transitions.forEach((t, i) => {
    if (!inside(t) || !filter(t, i)) return;
    const tw = transitionWidth(t);
    ctx.rect(t.x - tw / 2, t.y - TH / 2, tw, TH);
  });
  ctx.fillStyle = fill;
  ctx.fill();
  ctx.lineWidth = Math.max(lw, px);
  ctx.strokeStyle = stroke;
  ctx.stroke();
}

// The view (or a node) moved: the base bitmap must be drawn again.
function canvasViewChanged() {
  cvs.baseKey = null;
  canvasDirty();
}

function canvasDraw() {
  cvs.dirty = false;
  const el = cvs.el;
  const ctx = cvs.ctx;
  const dpr = window.devicePixelRatio || 1;
  const w = el.clientWidth;
  const h = el.clientHeight;
  const pw = Math.round(w * dpr);
  const ph = Math.round(h * dpr);
  if (el.width !== pw || el.height !== ph) {
    el.width = pw;
    el.height = ph;
  }
  const key = [pw, ph, view.x, view.y, view.k].join(' ');
  if (cvs.baseKey !== key) {
    if (!cvs.base) cvs.base = document.createElement('canvas');
    cvs.base.width = pw;
    cvs.base.height = ph;
    drawBase(cvs.base.getContext('2d', { alpha: false }), w, h, dpr);
    cvs.baseKey = key;
  }
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.drawImage(cvs.base, 0, 0);
  const k = view.k;
  ctx.setTransform(dpr * k, 0, 0, dpr * k, dpr * view.x, dpr * view.y);
  const inside = visibleTest(w, h);
  const px = 1 / k;

  // Tokens: dots when there is room, else the place filled.
  const detail = k * R >= 7;
  const marked = [];
  net.places.forEach((p, i) => {
    if (placeTokens[i] > 0 && inside(p)) marked.push(i);
  });
  ctx.fillStyle = ink('--fg');
  ctx.beginPath();
  for (const i of marked) {
    const p = net.places[i];
    const n = placeTokens[i];
    if (!detail) {
      ctx.moveTo(p.x + R * 0.6, p.y);
      ctx.arc(p.x, p.y, R * 0.6, 0, 2 * Math.PI);
    } else if (n <= 5) {
      for (const [dx, dy] of DOTS[n]) {
        ctx.moveTo(p.x + dx + 3.5, p.y + dy);
        ctx.arc(p.x + dx, p.y + dy, 3.5, 0, 2 * Math.PI);
      }
    }
  }
  ctx.fill();

  // Transitions that may fire green, the one fired last yellow.
  const on = (i) => transEnabled[i] && i !== firedIndex;
  transitionRects(ctx, inside, (t, i) => on(i) && t.kind === 'immediate', ink('--enabled'), ink('--enabled'), 3, px);
  transitionRects(ctx, inside, (t, i) => on(i) && t.kind !== 'immediate', ink('--enabled-fill'), ink('--enabled'), 3, px);
  if (firedIndex >= 0) transitionRects(ctx, inside, (t, i) => i === firedIndex, ink('--fired'), ink('--stroke'), 1.5, px);

  if (!detail) return;
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  ctx.font = '600 13px system-ui, sans-serif';
  ctx.fillStyle = ink('--fg');
  for (const i of marked) {
    const p = net.places[i];
    if (placeTokens[i] > 5) ctx.fillText(String(placeTokens[i]), p.x, p.y);
  }
  if (k < 0.6) return;
  ctx.font = '10px system-ui, sans-serif';
  ctx.fillStyle = ink('--muted');
  ctx.textAlign = 'start';
  for (const i of marked) {
    const p = net.places[i];
    ctx.fillText(String(placeTokens[i]), p.x + R * 0.75, p.y - R * 0.75);
  }
  ctx.fillStyle = ink('--accent');
  ctx.textAlign = 'center';
  net.places.forEach((p, i) => {
    if (placeAgents[i] && inside(p)) ctx.fillText(placeAgents[i], p.x, p.y + R + 22);
  });
}
