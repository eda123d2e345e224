// gspn viewer: the run's monitor beside the model (`plan-runner run --monitor --web`). Every
// live state frame carries `conform`: per exponential transition its rate (firings per unit
// of enabled time) over the monitor's window, per place its mean tokens over the last
// batches — observed beside predicted, with the 95% interval of the observation, the sample
// size and the p-value. Drifting items (reported, not yet back) are highlighted.
'use strict';

// The table's panel, made on the first frame that has statistics (above the event log).
function conformPanel() {
  let panel = $('conform-panel');
  if (panel) return panel;
  panel = document.createElement('details');
  panel.id = 'conform-panel';
  panel.open = true;
  const summary = document.createElement('summary');
  summary.append('observed vs predicted ');
  const count = document.createElement('span');
  count.id = 'conform-count';
  count.className = 'count';
  summary.appendChild(count);
  const table = document.createElement('table');
  table.id = 'conform';
  table.className = 'mono';
  const head = table.createTHead().insertRow();
  for (const h of ['item', 'observed', 'predicted', '95% interval', 'n', 'p']) {
    const th = document.createElement('th');
    th.textContent = h;
    head.appendChild(th);
  }
  table.createTBody();
  // Wider than the panel: it scrolls sideways, every column reachable.
  const scroll = document.createElement('div');
  scroll.className = 'table-scroll';
  scroll.appendChild(table);
  panel.append(summary, scroll);
  const log = $('log-panel');
  log.parentNode.insertBefore(panel, log);
  return panel;
}

// Four decimals, as `plan-runner conform` prints them.
function conformNumber(x) {
  return typeof x === 'number' ? x.toFixed(4) : String(x);
}

// Redraws the table from one frame's rows: `[{kind, item, observed, predicted, interval,
// n, p_value, drifting}]`.
function showConform(rows) {
  conformPanel();
  const body = $('conform').tBodies[0];
  body.textContent = '';
  let drifting = 0;
  for (const r of rows) {
    const tr = body.insertRow();
    tr.dataset.item = r.item;
    tr.dataset.kind = r.kind;
    tr.dataset.drifting = String(r.drifting);
    if (r.drifting) {
      tr.classList.add('drifting');
      drifting += 1;
    }
    const what = r.kind === 'rate' ? 'rate of ' : 'tokens in ';
    const cells = [
      ['item', what + r.item],
      ['observed', conformNumber(r.observed)],
      ['predicted', conformNumber(r.predicted)],
      ['interval', '[' + conformNumber(r.interval[0]) + ', ' + conformNumber(r.interval[1]) + ']'],
      ['n', String(r.n)],
      ['p', r.p_value.toExponential(1)],
    ];
    for (const [col, text] of cells) {
      const td = tr.insertCell();
      td.dataset.col = col;
      td.textContent = text;
    }
    tr.title = r.drifting ? 'drifting: outside the model' : 'consistent with the model';
  }
  $('conform-count').textContent = rows.length + ' items, ' + drifting + ' drifting';
}

// A replay's table at model time t: the last snapshot (`[{time, rows}]`, sorted by time) at
// or before t; an empty table before the first.
function showConformAt(snapshots, t) {
  let lo = -1;
  let hi = snapshots.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (snapshots[mid].time <= t + 1e-9) lo = mid;
    else hi = mid - 1;
  }
  showConform(lo >= 0 ? snapshots[lo].rows : []);
}
