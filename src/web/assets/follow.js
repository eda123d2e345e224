// gspn viewer, following a run: the selected place (click it) or robot (click it on the map
// or in the timeline) with its agents, the robot ids on the places that hold them, the
// transition that just fired flashing, a tokens-over-time plot of the selected place, a
// per-robot timeline (Gantt of places over time, coloured by the agent's state), and panes
// that can be resized (drag the bars between them) and collapsed (the buttons in the header).
//
// Test hooks: the selected place's <g> (or canvas hook) has data-selected="true", a
// selected robot's map <g> too; #selection says what is selected; each timeline bar is a
// <rect data-robot data-place data-state>; the plot's <polyline> has data-place and
// data-points="t,k t,k ...".
'use strict';

const follow = {
  place: -1, // selected place
  plotted: [], // places in the plot
  robot: null, // selected robot id
  times: [], // model time per recorded frame
  tokens: [], // tokens per recorded frame
  robots: new Map(), // robot id -> {agent, place, state}
  segments: new Map(), // robot id -> [{t0, t1, place, state}]
  cursor: null, // a replay's model time (the timeline's cursor); null: live or the token game
  lastFiredSeq: -1,
  drawPending: false,
};

// Frames kept for the plot (the oldest are dropped past this).
const HISTORY_KEPT = 20000;

// Records the marking at model time `t` (a frame with the same time and tokens is skipped).
function recordTokens(t, tokens) {
  const n = follow.times.length;
  if (n && follow.times[n - 1] === t && follow.tokens[n - 1].every((k, i) => k === tokens[i])) return;
  if (n && t < follow.times[n - 1]) {
    // A reset of the token game: a new history.
    follow.times.length = follow.tokens.length = 0;
  }
  follow.times.push(t);
  follow.tokens.push(tokens.slice());
  if (follow.times.length > HISTORY_KEPT) {
    follow.times.shift();
    follow.tokens.shift();
  }
}

// A live state frame: robots, their places and timelines, the fired transition, the plot.
function followLive(s) {
  recordTokens(s.time, s.tokens);
  const byPlace = new Map();
  follow.robots.clear();
  for (const a of s.agent_list || []) {
    if (a.robot === null || a.robot === undefined) continue;
    follow.robots.set(a.robot, a);
    if (!byPlace.has(a.place)) byPlace.set(a.place, []);
    byPlace.get(a.place).push(a.robot);
    extendSegment(a.robot, s.time, a.place, a.state);
  }
  if (!s.stopped) for (const segs of follow.segments.values()) segs[segs.length - 1].t1 = s.time;
  net.places.forEach((p, i) => {
    const robots = byPlace.get(p.name);
    if (robots) {
      robots.sort(byId);
      setAgents(i, robots.join(' '));
      return;
    }
    const agents = s.agents[p.name];
    setAgents(i, agents ? Object.entries(agents).map(([k, n]) => k + ' ' + n).join(', ') : '');
  });
  for (const e of s.log) if (e.event === 'fired') flashFired(e);
  tputLog(s.log);
  scheduleFollowDraw();
}

// The transition of a `Fired` log entry flashes (once per entry).
function flashFired(e) {
  if (e.seq <= follow.lastFiredSeq) return;
  follow.lastFiredSeq = e.seq;
  const i = e.transition;
  if (!Number.isInteger(i) || !transEls[i]) return;
  setFired(i);
  const g = transEls[i];
  g.classList.remove('flash');
  // Restart the animation: a reflow between removing and adding the class.
  void g.getBoundingClientRect();
  g.classList.add('flash');
}

function byId(a, b) {
  return String(a).localeCompare(String(b), 'en', { numeric: true });
}

function extendSegment(robot, t, place, state) {
  if (!follow.segments.has(robot)) follow.segments.set(robot, []);
  const segs = follow.segments.get(robot);
  const last = segs[segs.length - 1];
  // A stay from the history (state unknown) goes on with the state a live frame gives.
  if (last && last.place === place && (last.state === state || last.state === '')) {
    last.t1 = t;
    last.state = state;
    return;
  }
  if (last) last.t1 = t;
  segs.push({ t0: t, t1: t, place, state });
}

// ---- selection -------------------------------------------------------------------------

function placeIndex(name) {
  if (!net.placeByName) net.placeByName = new Map(net.places.map((p, i) => [p.name, i]));
  const i = net.placeByName.get(name);
  return i === undefined ? -1 : i;
}

// Selects place `i` (-1: none), with `robot` when a robot was clicked; `add` (a
// shift-click) adds the place to the plot, or takes it out, instead of plotting it alone.
function selectPlace(i, robot, add) {
  if (add && i >= 0) {
    const k = follow.plotted.indexOf(i);
    if (k >= 0) follow.plotted.splice(k, 1);
    else if (follow.plotted.length < CURVE_COLOURS.length) follow.plotted.push(i);
  } else {
    follow.plotted = i >= 0 ? [i] : [];
  }
  if (follow.place >= 0 && placeEls[follow.place]) placeEls[follow.place].removeAttribute('data-selected');
  follow.place = i;
  follow.robot = robot === undefined ? null : robot;
  if (i >= 0) placeEls[i].setAttribute('data-selected', 'true');
  for (const [id, g] of map.robots) {
    const r = follow.robots.get(id);
    const on = follow.robot !== null ? id === follow.robot : i >= 0 && r && r.place === net.places[i].name;
    if (on) g.setAttribute('data-selected', 'true');
    else g.removeAttribute('data-selected');
  }
  canvasDirty();
  describeSelection();
  drawPlot();
  drawGantt();
}

// Selects robot `id`: its place in the net and its agent.
function selectRobot(id) {
  const r = follow.robots.get(id);
  selectPlace(r ? placeIndex(r.place) : -1, id);
}

function describeSelection() {
  const box = $('selection');
  if (follow.place < 0 && follow.robot === null) {
    box.textContent = 'click a place, or a robot on the map';
    return;
  }
  const parts = [];
  if (follow.robot !== null) {
    const r = follow.robots.get(follow.robot);
    parts.push('robot ' + follow.robot + (r ? ': agent ' + r.id + ' in ' + r.place + ', ' + r.state : ': not in the net'));
    const segs = (follow.segments.get(follow.robot) || []).filter((x) => follow.cursor === null || x.t0 <= follow.cursor);
    if (segs.length) {
      // Its history: the places before this one, the latest last.
      const past = segs.slice(-4, -1).map((x) => x.place + ' ' + fmtTime(x.t0) + '–' + fmtTime(x.t1) + ' s');
      parts.push(segs.length + ' stay' + (segs.length === 1 ? '' : 's') + (past.length ? ', before: ' + past.join(', ') : ''));
    }
  }
  if (follow.place >= 0) {
    const p = net.places[follow.place];
    const robots = [...follow.robots.entries()].filter(([, r]) => r.place === p.name).map(([id]) => id).sort(byId);
    parts.push(p.name + ': ' + placeTokens[follow.place] + ' token' + (placeTokens[follow.place] === 1 ? '' : 's') +
      (robots.length ? ', robots ' + robots.join(' ') : ''));
  }
  box.textContent = parts.join(' — ');
}

// ---- plot ------------------------------------------------------------------------------

function scheduleFollowDraw() {
  if (follow.drawPending) return;
  follow.drawPending = true;
  setTimeout(() => {
    follow.drawPending = false;
    if (follow.place >= 0 || follow.robot !== null) describeSelection();
    drawPlot();
    drawGantt();
    drawThroughput();
  }, 250);
}

// Tokens of the plotted places over model time, as step lines (click a place to plot it,
// shift-click to add or remove one; at most CURVE_COLOURS.length).
function plotSeries() {
  return follow.plotted.map((i) => ({
    name: net.places[i].name,
    step: true,
    points: follow.times.map((t, f) => [t, follow.tokens[f][i]]),
  }));
}

function drawPlot() {
  const svg = $('plot');
  const names = follow.plotted.map((i) => net.places[i].name);
  $('plot-place').textContent = names.length ? names.join(', ') : '(click a place; shift-click adds one)';
  const empty = !names.length || !follow.times.length;
  svg.classList.toggle('hidden', empty);
  $('plot-csv').classList.toggle('hidden', empty);
  if (empty) {
    svg.textContent = '';
    return;
  }
  lineChart(svg, plotSeries(), 's');
  // The first curve keeps the older hook: data-place on its polyline.
  const first = svg.querySelector('polyline');
  if (first) first.setAttribute('data-place', names[0]);
}

// ---- timeline --------------------------------------------------------------------------

// Colours of places in the timeline (a place keeps its colour while the page is open).
const PLACE_COLOURS = ['#4a90d9', '#e8a33a', '#3a3', '#c55', '#8a6cc8', '#2aa6a6', '#b5762c', '#d36fb0', '#7a8a2a', '#5b6b8c'];
const placeColour = new Map();

function colourOf(place) {
  if (!placeColour.has(place)) placeColour.set(place, PLACE_COLOURS[placeColour.size % PLACE_COLOURS.length]);
  return placeColour.get(place);
}

// One row per robot: a bar per stay in a place, coloured by the place (legend below; the
// agent's state in the bar's tooltip); in a replay a line at the slider's time.
function drawGantt() {
  const svg = $('gantt');
  const panel = $('timeline-panel');
  if (!follow.segments.size) {
    panel.classList.add('hidden');
    return;
  }
  panel.classList.remove('hidden');
  svg.textContent = '';
  const robots = [...follow.segments.keys()].sort(byId);
  const W = Math.max(300, svg.clientWidth || 300);
  const row = 16;
  const left = 34;
  const H = robots.length * row + 16;
  let t0 = Infinity;
  let t1 = -Infinity;
  for (const segs of follow.segments.values()) {
    if (!segs.length) continue;
    t0 = Math.min(t0, segs[0].t0);
    t1 = Math.max(t1, segs[segs.length - 1].t1);
  }
  if (!Number.isFinite(t0)) t0 = 0;
  if (!(t1 > t0)) t1 = t0 + 1;
  const x = (t) => left + (t - t0) / (t1 - t0) * (W - left - 4);
  svg.setAttribute('viewBox', '0 0 ' + W + ' ' + H);
  svg.style.height = H + 'px';
  const used = new Set();
  robots.forEach((id, r) => {
    const name = el('text', { class: 'tick robot-name', x: 2, y: r * row + 11 }, svg);
    name.textContent = id;
    name.setAttribute('data-robot-row', id);
    name.addEventListener('click', () => selectRobot(id));
    for (const s of follow.segments.get(id)) {
      const w = Math.max(0.5, x(s.t1) - x(s.t0));
      used.add(s.place);
      const rect = el('rect', { class: 'seg', x: x(s.t0).toFixed(1), y: r * row + 2, width: w.toFixed(1), height: row - 4 }, svg);
      rect.style.fill = colourOf(s.place);
      rect.setAttribute('data-robot', id);
      rect.setAttribute('data-place', s.place);
      rect.setAttribute('data-state', s.state);
      rect.addEventListener('click', () => selectRobot(id));
      if (follow.robot === id || (follow.place >= 0 && net.places[follow.place].name === s.place)) rect.classList.add('hi');
      if (w > 40) {
        // The place's own name (after a `p12:` prefix) where the bar has room for it.
        const label = el('text', { class: 'seg-label', x: (x(s.t0) + 2).toFixed(1), y: r * row + 11 }, svg);
        label.textContent = s.place.replace(/^[^:]*:/, '').slice(0, Math.floor(w / 5));
      }
      el('title', {}, rect).textContent = id + ' in ' + s.place + ' (' + s.state + ') ' + fmtTime(s.t0) + '–' + fmtTime(s.t1) + ' s';
    }
  });
  if (follow.cursor !== null) {
    const cx = x(Math.min(t1, Math.max(t0, follow.cursor))).toFixed(1);
    el('line', { class: 'cursor', x1: cx, x2: cx, y1: 0, y2: H - 14 }, svg);
  }
  const axis = el('text', { class: 'tick', x: left, y: H - 3 }, svg);
  axis.textContent = fmtTime(t0) + ' s';
  const end = el('text', { class: 'tick', x: W - 4, y: H - 3, 'text-anchor': 'end' }, svg);
  end.textContent = fmtTime(t1) + ' s';
  const legend = $('gantt-legend');
  legend.textContent = '';
  for (const place of [...placeColour.keys()].filter((p) => used.has(p))) {
    const item = document.createElement('span');
    item.className = 'legend-item';
    item.dataset.legendPlace = place;
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = colourOf(place);
    item.append(swatch, place);
    legend.appendChild(item);
  }
}

// ---- panes -----------------------------------------------------------------------------

// Bars between the panes resize them; the header's buttons collapse them. The net is fitted
// again when its pane changes size (if it was fitted).
function setupPanes() {
  $('plot-csv').addEventListener('click', () => downloadCsv(plotSeries(), 'tokens.csv'));
  window.gspnPlot = { csv: () => seriesCsv(plotSeries()) };
  for (const bar of document.querySelectorAll('.splitter')) {
    const width = remembered('pane.' + bar.dataset.pane);
    if (width) {
      $(bar.dataset.pane).style.width = width;
      $(bar.dataset.pane).style.flex = 'none';
    }
    bar.addEventListener('mousedown', (ev) => {
      ev.preventDefault();
      const pane = $(bar.dataset.pane);
      const start = ev.clientX;
      const width = pane.getBoundingClientRect().width;
      const moveTo = (e) => {
        // The pane is to the right of its bar: dragging left makes it wider.
        pane.style.width = Math.max(120, width - (e.clientX - start)) + 'px';
        pane.style.flex = 'none';
        refit();
      };
      const up = () => {
        remember('pane.' + bar.dataset.pane, pane.style.width);
        window.removeEventListener('mousemove', moveTo);
        window.removeEventListener('mouseup', up);
      };
      window.addEventListener('mousemove', moveTo);
      window.addEventListener('mouseup', up);
    });
  }
  for (const b of document.querySelectorAll('[data-collapse]')) {
    const pane = $(b.dataset.collapse);
    const set = (collapsed) => {
      pane.classList.toggle('collapsed', collapsed);
      b.setAttribute('aria-pressed', collapsed ? 'false' : 'true');
    };
    if (remembered('collapsed.' + b.dataset.collapse) === 'true') set(true);
    b.addEventListener('click', () => {
      const collapsed = !pane.classList.contains('collapsed');
      set(collapsed);
      remember('collapsed.' + b.dataset.collapse, String(collapsed));
      refit();
    });
  }
  describeSelection();
}

// The page's remembered settings (pane sizes, collapsed panes), in localStorage when the
// browser allows it.
function remembered(key) {
  try {
    return localStorage.getItem('gspn.' + key);
  } catch (_) {
    return null;
  }
}

function remember(key, value) {
  try {
    localStorage.setItem('gspn.' + key, value);
  } catch (_) {
    // Not remembered: the setting holds for this visit.
  }
}

function refit() {
  if (fitted && net) requestAnimationFrame(() => fit(fittedWhole));
}
