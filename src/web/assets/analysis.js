// gspn viewer, the analysis panel: starts the analysis on the server, shows its progress
// (phase, markings, seconds) with a cancel button, then the properties, the steady-state
// bars and the dead markings (click one to replay its firing sequence on the net).
'use strict';

// ---- analysis --------------------------------------------------------------------------

// Bars in the net's order (`names`), not the JSON object's.
function bars(title, values, cls, names) {
  const entries = names.filter((n) => n in values).map((n) => [n, values[n]]);
  const max = Math.max(1e-300, ...entries.map(([, v]) => v));
  let html = '<h4>' + title + '</h4><table>';
  for (const [name, v] of entries) {
    html += '<tr><td>' + escapeHtml(name) + '</td><td class="mono">' + fmt(v) +
      '</td><td class="barcell"><div class="bar ' + cls + '" data-width="' +
      (100 * v / max).toFixed(1) + '"></div></td></tr>';
  }
  return html + '</table>';
}

function escapeHtml(s) {
  return String(s).replace(/[&<>"']/g, (c) => '&#' + c.charCodeAt(0) + ';');
}

let analysing = false;

function showProgress(p) {
  const t = p.seconds !== undefined ? ', ' + fmt(Math.round(p.seconds * 10) / 10) + ' s' : '';
  const m = p.markings !== undefined && p.markings !== null ? ', ' + p.markings.toLocaleString('en') + ' markings' : '';
  $('analysis-progress').textContent = p.state === 'done' ? '' :
    p.state + (p.phase ? ' (' + p.phase + ')' : '') + m + t;
}

// Starts the analysis on the server, shows its progress every 200 ms (with a cancel button),
// then the result.
async function analyse() {
  if (analysing) return;
  analysing = true;
  const out = $('analysis');
  out.textContent = '';
  $('analysis-cancel').classList.remove('hidden');
  let a;
  try {
    let p = await api('POST', '/api/analysis/start');
    while (p.state === 'running' || p.state === 'cancelling') {
      showProgress(p);
      await new Promise((r) => setTimeout(r, 200));
      p = await api('GET', '/api/analysis/progress');
    }
    showProgress(p);
    if (p.state === 'cancelled') {
      out.innerHTML = '<p class="error">cancelled after ' + p.markings + ' markings (' +
        escapeHtml(p.phase) + ')</p>';
      return;
    }
    const res = await fetch('/api/analysis');
    a = await res.json();
  } catch (e) {
    out.innerHTML = '<p class="error">' + escapeHtml(e.message) + '</p>';
    return;
  } finally {
    analysing = false;
    $('analysis-cancel').classList.add('hidden');
  }
  if (a.error) {
    out.innerHTML = '<p class="error">' + escapeHtml(a.error) + '</p>';
    return;
  }
  let html = '<p>' + a.reachable + ' reachable markings (' + a.tangible + ' tangible, ' +
    a.vanishing + ' vanishing); safe: ' + a.safe + '; reversible: ' + a.reversible +
    '; deadlock-free: ' + a.deadlock_free + '</p>';
  if (a.steady) {
    html += bars('mean tokens' + (a.steady.ergodic ? '' : ' (limiting)'), a.steady.mean_tokens, 'tok',
      net.places.map((p) => p.name));
    html += bars('throughput', a.steady.throughput, 'thr', net.transitions.map((t) => t.name));
  } else if (a.steady_error) {
    html += '<p class="error">' + escapeHtml(a.steady_error) + '</p>';
  }
  html += '<h4>dead markings (' + a.dead_markings.length + ')</h4><ol>';
  a.dead_markings.forEach((d, i) => {
    html += '<li class="dead mono" data-dead="' + i + '" title="click to replay">' +
      escapeHtml(d.text || '(empty)') + ' ← ' + escapeHtml(d.path.join(' ')) + '</li>';
  });
  out.innerHTML = html + '</ol>';
  // Widths through the CSSOM: the page's policy forbids inline style attributes.
  for (const b of out.querySelectorAll('.bar')) b.style.width = b.dataset.width + '%';
  for (const li of out.querySelectorAll('[data-dead]')) {
    li.addEventListener('click', () => replay(a.dead_markings[Number(li.dataset.dead)].path));
  }
}

// Replays a firing sequence from the initial marking, one firing at a time.
async function replay(path) {
  stopRun();
  await act('POST', '/api/sim/reset', {});
  for (const name of path) {
    await new Promise((r) => setTimeout(r, 250));
    await fire(name);
  }
}
