// gspn viewer, curves: one chart for every plot of the page (tokens of the chosen places
// over time, the answers to questions over their times), with a legend, a readout of every
// curve under the pointer, and the data as CSV.
//
// Test hooks: each curve's <polyline> has data-series="NAME" and data-points="t,v t,v ...";
// the readout is #<svg id>-readout with data-t.
'use strict';

const CURVE_COLOURS = ['#06c', '#d35', '#2a2', '#e80', '#85c', '#0aa'];

// Draws `series` ([{name, points: [[t, v]], step}]) in `svg`: a step line when `step` (tokens
// hold their value until the next firing), else straight between the points (with a dot at
// each). The readout follows the pointer.
function lineChart(svg, series, unit) {
  svg.textContent = '';
  const W = Math.max(240, Math.round(svg.clientWidth || 300));
  const H = 130;
  const pad = [36, 8, 8, 18]; // left, right, top, bottom
  const all = series.flatMap((s) => s.points);
  if (!all.length) return;
  const t0 = Math.min(...all.map((p) => p[0]));
  const t1 = Math.max(t0 + 1e-9, ...all.map((p) => p[0]));
  const vMax = Math.max(1e-12, ...all.map((p) => p[1]));
  const x = (t) => pad[0] + (t - t0) / (t1 - t0) * (W - pad[0] - pad[1]);
  const y = (v) => H - pad[3] - v / vMax * (H - pad[2] - pad[3]);
  svg.setAttribute('viewBox', '0 0 ' + W + ' ' + H);
  svg.style.height = H + 'px';
  el('line', { class: 'axis', x1: pad[0], y1: H - pad[3], x2: W - pad[1], y2: H - pad[3] }, svg);
  el('line', { class: 'axis', x1: pad[0], y1: pad[2], x2: pad[0], y2: H - pad[3] }, svg);
  const label = (text, attrs) => { el('text', attrs, svg).textContent = text; };
  label(fmt(vMax), { class: 'tick', x: pad[0] - 3, y: pad[2] + 6, 'text-anchor': 'end' });
  label('0', { class: 'tick', x: pad[0] - 3, y: H - pad[3], 'text-anchor': 'end' });
  label(fmtTime(t0) + ' ' + unit, { class: 'tick', x: pad[0], y: H - 3 });
  label(fmtTime(t1) + ' ' + unit, { class: 'tick', x: W - pad[1], y: H - 3, 'text-anchor': 'end' });
  series.forEach((s, k) => {
    const colour = CURVE_COLOURS[k % CURVE_COLOURS.length];
    const pts = [];
    s.points.forEach(([t, v], j) => {
      if (s.step && j > 0) pts.push(x(t).toFixed(1) + ',' + y(s.points[j - 1][1]).toFixed(1));
      pts.push(x(t).toFixed(1) + ',' + y(v).toFixed(1));
    });
    const line = el('polyline', { class: 'plot-line', points: pts.join(' ') }, svg);
    line.style.stroke = colour;
    line.setAttribute('data-series', s.name);
    line.setAttribute('data-points', s.points.map((p) => p[0] + ',' + p[1]).join(' '));
    if (!s.step) for (const [t, v] of s.points) el('circle', { cx: x(t), cy: y(v), r: 2.5, fill: colour }, svg);
  });
  // The readout: a line at the pointer's time and each curve's value there.
  const cursor = el('line', { class: 'plot-cursor hidden', y1: pad[2], y2: H - pad[3] }, svg);
  const readout = $(svg.id + '-readout');
  svg.onmousemove = (ev) => {
    const r = svg.getBoundingClientRect();
    const px = (ev.clientX - r.left) * W / r.width;
    const t = Math.min(t1, Math.max(t0, t0 + (px - pad[0]) / (W - pad[0] - pad[1]) * (t1 - t0)));
    cursor.setAttribute('x1', x(t));
    cursor.setAttribute('x2', x(t));
    cursor.classList.remove('hidden');
    readout.dataset.t = String(t);
    readout.textContent = 't = ' + fmtTime(t) + ' ' + unit + ': ' +
      series.map((s) => s.name + ' ' + fmt(valueAt(s, t))).join(', ');
  };
  svg.onmouseleave = () => {
    cursor.classList.add('hidden');
    readout.textContent = '';
  };
  const legend = $(svg.id + '-legend');
  if (legend) {
    legend.textContent = '';
    series.forEach((s, k) => {
      const item = document.createElement('span');
      item.className = 'legend-item';
      const swatch = document.createElement('span');
      swatch.className = 'swatch';
      swatch.style.background = CURVE_COLOURS[k % CURVE_COLOURS.length];
      item.append(swatch, s.name);
      legend.appendChild(item);
    });
  }
}

// A curve's value at t: the last point at or before t for a step line, else the nearest.
function valueAt(s, t) {
  let best = s.points[0];
  for (const p of s.points) {
    if (s.step ? p[0] <= t : Math.abs(p[0] - t) < Math.abs(best[0] - t)) best = p;
  }
  return best[1];
}

// The series as CSV text: a `time` column, then one per series (empty where a series has no
// point at that time); every digit of every number.
function seriesCsv(series) {
  const times = [...new Set(series.flatMap((s) => s.points.map((p) => p[0])))].sort((a, b) => a - b);
  const quote = (v) => (/[",\n]/.test(v) ? '"' + v.replace(/"/g, '""') + '"' : v);
  const lines = [['time', ...series.map((s) => quote(s.name))].join(',')];
  const at = series.map((s) => new Map(s.points.map((p) => [p[0], p[1]])));
  for (const t of times) lines.push([t, ...at.map((m) => (m.has(t) ? m.get(t) : ''))].join(','));
  return lines.join('\n') + '\n';
}

function downloadCsv(series, name) {
  const url = URL.createObjectURL(new Blob([seriesCsv(series)], { type: 'text/csv' }));
  download(url, name);
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

// The answers to a question (`POST /api/analysis/query`) as curves over its times: each
// predicate's probability, and the expected tokens of the plotted places (or, with none
// plotted, of every place up to CURVE_COLOURS.length), under the answer's table in `out`.
function plotAnswers(out, q, prob) {
  if (!q.transient || !q.transient.length) return;
  const series = prob.map((e) => ({ name: 'P(' + e + ')', points: q.transient.map((p) => [p.t, p.probability[e]]) }));
  const places = follow.plotted.length ? follow.plotted : net.places.map((_, i) => i);
  for (const i of places.slice(0, Math.max(0, CURVE_COLOURS.length - series.length))) {
    const name = net.places[i].name;
    series.push({ name: 'E[' + name + ']', points: q.transient.map((p) => [p.t, p.mean_tokens[name]]) });
  }
  const box = document.createElement('div');
  box.innerHTML = '<svg id="answer-plot" xmlns="' + SVG_NS + '" role="img" aria-label="the answers over time"></svg>' +
    '<div id="answer-plot-legend" class="legend"></div><div id="answer-plot-readout" class="readout mono"></div>' +
    '<button id="answer-csv" title="download these curves as CSV">CSV</button>';
  out.appendChild(box);
  lineChart($('answer-plot'), series, 's');
  $('answer-csv').addEventListener('click', () => downloadCsv(series, 'answers.csv'));
  window.gspnAnswers = { csv: () => seriesCsv(series) };
}

// ---- throughput over time ----------------------------------------------------------------

// Firings per transition per window of model time, by the rule of src/web/throughput.rs: the
// window is 2^-10 s at first and doubles (pairs of windows merged) whenever a firing comes
// past TPUT_BINS windows. A replay gets the whole run's counts from the server, a live page
// its history's and goes on counting the firings of the log (from `after`, the last event
// the history counted).
const TPUT_BINS = 128;
const tput = { width: 1 / 1024, counts: new Map(), after: -1, picked: [] };

// Starts again from the server's counts `t` ({width, counts}), which counted the events up to
// seq `after`.
function tputReset(t, after) {
  tput.width = t ? t.width : 1 / 1024;
  tput.counts = new Map(Object.entries(t ? t.counts : {}));
  tput.after = Number.isInteger(after) ? after : -1;
}

// Counts the firings of a live frame's log not counted yet.
function tputLog(log) {
  for (const e of log) {
    if (e.event !== 'fired' || e.seq <= tput.after || !net.transitions[e.transition]) continue;
    tput.after = e.seq;
    tputFired(e.time, net.transitions[e.transition].name);
  }
}

function tputFired(t, name) {
  t = Math.max(0, t);
  while (t >= tput.width * TPUT_BINS) {
    tput.width *= 2;
    for (const [n, row] of tput.counts) {
      const merged = [];
      for (let k = 0; k < row.length; k += 2) merged.push(row[k] + (row[k + 1] || 0));
      tput.counts.set(n, merged);
    }
  }
  const k = Math.floor(t / tput.width);
  if (!tput.counts.has(name)) tput.counts.set(name, []);
  const row = tput.counts.get(name);
  while (row.length <= k) row.push(0);
  row[k] += 1;
}

// The picked transitions (by default the three that fired most) as step curves of firings
// per second in each window, every window up to the last with a firing; beside each, the
// exact steady-state throughput when the analysis panel has it (`exactThroughput`).
function tputSeries() {
  const byTotal = [...tput.counts.entries()].map(([n, row]) => [n, row.reduce((a, b) => a + b, 0)]);
  byTotal.sort((a, b) => b[1] - a[1] || byId(a[0], b[0]));
  const picked = tput.picked.length ? tput.picked : byTotal.slice(0, 3).map((e) => e[0]);
  const windows = Math.max(1, ...[...tput.counts.values()].map((row) => row.length));
  const series = picked.map((name) => {
    const row = tput.counts.get(name) || [];
    const points = [];
    for (let k = 0; k < windows; k++) points.push([k * tput.width, (row[k] || 0) / tput.width]);
    return { name, step: true, points };
  });
  if (typeof exactThroughput !== 'undefined' && exactThroughput) {
    const t1 = windows * tput.width;
    for (const name of picked) {
      const v = exactThroughput[name];
      if (Number.isFinite(v)) series.push({ name: name + ' (exact)', points: [[0, v], [t1, v]] });
    }
  }
  return series.slice(0, CURVE_COLOURS.length);
}

function drawThroughput() {
  const panel = $('tput-panel');
  const any = tput.counts.size > 0;
  panel.classList.toggle('hidden', !any);
  if (!any) return;
  const pick = $('tput-pick');
  if (pick.options.length !== net.transitions.length + 1) {
    pick.textContent = '';
    const first = document.createElement('option');
    first.value = '';
    first.textContent = 'add or remove a transition…';
    pick.appendChild(first);
    for (const t of net.transitions) {
      const o = document.createElement('option');
      o.value = o.textContent = t.name;
      pick.appendChild(o);
    }
  }
  $('tput-width').textContent = 'per ' + fmt(tput.width) + ' s';
  lineChart($('tput'), tputSeries(), 's');
}

function setupThroughput() {
  $('tput-pick').addEventListener('change', (ev) => {
    const name = ev.target.value;
    ev.target.value = '';
    if (!name) return;
    if (!tput.picked.length) tput.picked = tputSeries().filter((s) => s.step).map((s) => s.name);
    const k = tput.picked.indexOf(name);
    if (k >= 0) tput.picked.splice(k, 1);
    else if (tput.picked.length < CURVE_COLOURS.length) tput.picked.push(name);
    drawThroughput();
  });
  $('tput-csv').addEventListener('click', () => downloadCsv(tputSeries(), 'throughput.csv'));
  window.gspnThroughput = {
    csv: () => seriesCsv(tputSeries()),
    width: () => tput.width,
    pick: (names) => {
      tput.picked = names.slice();
      drawThroughput();
    },
  };
}
