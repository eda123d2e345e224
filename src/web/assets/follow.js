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
  robot: null, // selected robot id
  times: [], // model time per recorded frame
  tokens: [], // tokens per recorded frame
  robots: new Map(), // robot id -> {agent, place, state}
  segments: new Map(), // robot id -> [{t0, t1, place, state}]
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
  if (last && last.place === place && last.state === state) {
    last.t1 = t;
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

// Selects place `i` (-1: none), with `robot` when a robot was clicked.
function selectPlace(i, robot) {
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
  }, 250);
}

// Tokens of the selected place over model time, as a step line.
function drawPlot() {
  const svg = $('plot');
  svg.textContent = '';
  const i = follow.place;
  $('plot-place').textContent = i >= 0 ? net.places[i].name : '(click a place)';
  svg.classList.toggle('hidden', i < 0);
  if (i < 0 || !follow.times.length) return;
  const W = 300;
  const H = 110;
  const pad = [28, 8, 8, 18]; // left, right, top, bottom
  const t0 = follow.times[0];
  const t1 = Math.max(follow.times[follow.times.length - 1], t0 + 1e-9);
  const kMax = Math.max(1, ...follow.tokens.map((m) => m[i]));
  const x = (t) => pad[0] + (t - t0) / (t1 - t0) * (W - pad[0] - pad[1]);
  const y = (k) => H - pad[3] - k / kMax * (H - pad[2] - pad[3]);
  svg.setAttribute('viewBox', '0 0 ' + W + ' ' + H);
  el('line', { class: 'axis', x1: pad[0], y1: H - pad[3], x2: W - pad[1], y2: H - pad[3] }, svg);
  el('line', { class: 'axis', x1: pad[0], y1: pad[2], x2: pad[0], y2: H - pad[3] }, svg);
  const label = (text, attrs) => { el('text', attrs, svg).textContent = text; };
  label(String(kMax), { class: 'tick', x: pad[0] - 3, y: pad[2] + 4, 'text-anchor': 'end' });
  label('0', { class: 'tick', x: pad[0] - 3, y: H - pad[3], 'text-anchor': 'end' });
  label(fmt(t0) + ' s', { class: 'tick', x: pad[0], y: H - 3 });
  label(fmt(t1) + ' s', { class: 'tick', x: W - pad[1], y: H - 3, 'text-anchor': 'end' });
  const pts = [];
  const data = [];
  follow.times.forEach((t, f) => {
    const k = follow.tokens[f][i];
    if (f > 0) pts.push(x(t).toFixed(1) + ',' + y(follow.tokens[f - 1][i]).toFixed(1));
    pts.push(x(t).toFixed(1) + ',' + y(k).toFixed(1));
    data.push(t + ',' + k);
  });
  const line = el('polyline', { class: 'plot-line', points: pts.join(' ') }, svg);
  line.setAttribute('data-place', net.places[i].name);
  line.setAttribute('data-points', data.join(' '));
}

// ---- timeline --------------------------------------------------------------------------

const STATE_CLASS = ['free', 'occupied', 'done', 'waiting', 'inactive'];

// One row per robot: a bar per stay in a place, coloured by the agent's state.
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
  const W = 300;
  const row = 14;
  const left = 34;
  const H = robots.length * row + 16;
  let t0 = Infinity;
  let t1 = -Infinity;
  for (const segs of follow.segments.values()) {
    t0 = Math.min(t0, segs[0].t0);
    t1 = Math.max(t1, segs[segs.length - 1].t1);
  }
  if (!(t1 > t0)) t1 = t0 + 1;
  const x = (t) => left + (t - t0) / (t1 - t0) * (W - left - 4);
  svg.setAttribute('viewBox', '0 0 ' + W + ' ' + H);
  robots.forEach((id, r) => {
    const name = el('text', { class: 'tick robot-name', x: 2, y: r * row + 10 }, svg);
    name.textContent = id;
    name.addEventListener('click', () => selectRobot(id));
    for (const s of follow.segments.get(id)) {
      const w = Math.max(0.5, x(s.t1) - x(s.t0));
      const cls = STATE_CLASS.includes(s.state) ? s.state : 'free';
      const rect = el('rect', { class: 'seg ' + cls, x: x(s.t0).toFixed(1), y: r * row + 2, width: w.toFixed(1), height: row - 4 }, svg);
      rect.setAttribute('data-robot', id);
      rect.setAttribute('data-place', s.place);
      rect.setAttribute('data-state', s.state);
      if (follow.robot === id || (follow.place >= 0 && net.places[follow.place].name === s.place)) rect.classList.add('hi');
      if (w > 40) {
        // The place's own name (after a `p12:` prefix) where the bar has room for it.
        const label = el('text', { class: 'seg-label', x: (x(s.t0) + 2).toFixed(1), y: r * row + 10 }, svg);
        label.textContent = s.place.replace(/^[^:]*:/, '').slice(0, Math.floor(w / 5));
      }
      el('title', {}, rect).textContent = id + ' in ' + s.place + ' (' + s.state + ') ' + fmt(s.t0) + '–' + fmt(s.t1) + ' s';
    }
  });
  const axis = el('text', { class: 'tick', x: left, y: H - 3 }, svg);
  axis.textContent = fmt(t0) + ' s';
  const end = el('text', { class: 'tick', x: W - 4, y: H - 3, 'text-anchor': 'end' }, svg);
  end.textContent = fmt(t1) + ' s';
}

// ---- panes -----------------------------------------------------------------------------

// Bars between the panes resize them; the header's buttons collapse them. The net is fitted
// again when its pane changes size (if it was fitted).
function setupPanes() {
  for (const bar of document.querySelectorAll('.splitter')) {
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
        window.removeEventListener('mousemove', moveTo);
        window.removeEventListener('mouseup', up);
      };
      window.addEventListener('mousemove', moveTo);
      window.addEventListener('mouseup', up);
    });
  }
  for (const b of document.querySelectorAll('[data-collapse]')) {
    b.addEventListener('click', () => {
      const pane = $(b.dataset.collapse);
      const collapsed = pane.classList.toggle('collapsed');
      b.setAttribute('aria-pressed', collapsed ? 'false' : 'true');
      refit();
    });
  }
  describeSelection();
}

function refit() {
  if (fitted && net) requestAnimationFrame(fit);
}
