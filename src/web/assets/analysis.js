// gspn viewer, the analysis panel: starts the analysis on the server (with the "max states"
// field's limit), shows its progress (phase, markings, seconds) with a cancel button, then
// what was analysed ("net under plan policy" or "bare net"), the properties, the place
// bounds, the invariants, the steady-state bars, the plan's reward rates and the dead
// markings (click one to replay its firing sequence on the net); then questions on the
// analysed state space: probabilities of `--prob`-style predicates (steady state and at
// times t) and the expected tokens at those times, computed by the server exactly as
// `plan-runner analyze --prob EXPR --transient T` computes them, with their progress (the
// time point, the solver's iterations) and the same cancel button.
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
// The last analysis's steady-state throughput by transition name (drawn beside the throughput
// over time), null without one.
let exactThroughput = null;

// The "max states" field starts at the server's limit (`serve --max-states`).
async function initMaxStates() {
  try {
    const p = await api('GET', '/api/analysis/progress');
    if (p.max_states && !$('max-states').value) $('max-states').value = p.max_states;
  } catch (e) {
    status(e.message);
  }
}

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
  // The last results stay until new ones replace them (or the server cannot be reached).
  out.classList.add('stale');
  $('analysis-cancel').classList.remove('hidden');
  let a;
  try {
    const max = Number($('max-states').value);
    const body = Number.isSafeInteger(max) && max > 0 ? { max_states: max } : {};
    let p = await api('POST', '/api/analysis/start', body);
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
    if (unreachable(e)) {
      offline(e);
      $('analysis-progress').textContent = 'the server cannot be reached';
    } else {
      out.innerHTML = '<p class="error">' + escapeHtml(e.message) + '</p>';
    }
    return;
  } finally {
    analysing = false;
    out.classList.remove('stale');
    $('analysis-cancel').classList.add('hidden');
  }
  const analysed = a.analysed ? '<p class="analysed" data-analysed="' + escapeHtml(a.analysed) +
    '">' + escapeHtml(a.analysed) + '</p>' : '';
  if (a.error) {
    out.innerHTML = analysed + '<p class="error">' + escapeHtml(a.error) + '</p>';
    return;
  }
  let html = analysed + '<p>' + a.reachable + ' reachable markings (' + a.tangible + ' tangible, ' +
    a.vanishing + ' vanishing); safe: ' + a.safe + '; reversible: ' + a.reversible +
    '; deadlock-free: ' + a.deadlock_free + '</p>';
  exactThroughput = a.steady ? a.steady.throughput : null;
  if (tput.counts.size) drawThroughput();
  if (a.steady) {
    html += bars('mean tokens' + (a.steady.ergodic ? '' : ' (limiting)'), a.steady.mean_tokens, 'tok',
      net.places.map((p) => p.name));
    html += bars('throughput', a.steady.throughput, 'thr', net.transitions.map((t) => t.name));
    if (a.steady.rewards) html += rewardTable(a.steady.rewards);
  } else if (a.steady_error) {
    html += '<p class="error">' + escapeHtml(a.steady_error) + '</p>';
  }
  html += boundsTable(a.place_bounds);
  html += invariantList('P-invariants', a.p_invariants, net.places.map((p) => p.name));
  html += invariantList('T-invariants', a.t_invariants, net.transitions.map((t) => t.name));
  html += '<h4>dead markings (' + a.dead_markings.length + ')</h4><ol>';
  a.dead_markings.forEach((d, i) => {
    html += '<li class="dead mono" data-dead="' + i + '" title="click to replay">' +
      escapeHtml(d.text || '(empty)') + ' ← ' + escapeHtml(d.path.join(' ')) + '</li>';
  });
  out.innerHTML = html + '</ol>' + (a.steady ? queryForm() : '');
  // Widths through the CSSOM: the page's policy forbids inline style attributes.
  for (const b of out.querySelectorAll('.bar')) b.style.width = b.dataset.width + '%';
  for (const li of out.querySelectorAll('[data-dead]')) {
    li.addEventListener('click', () => replay(a.dead_markings[Number(li.dataset.dead)].path));
  }
  if (a.steady) {
    $('query').addEventListener('click', ask);
    $('query-cancel').addEventListener('click', cancelQuestion);
  }
}

// The questions' form: times (comma-separated) and predicates (one per line).
function queryForm() {
  return '<h4>questions</h4><div class="query">' +
    '<label>at times <input id="query-times" class="mono" placeholder="0.5, 1, 10"></label>' +
    '<label>P( … ) <textarea id="query-prob" class="mono" rows="2" ' +
    'placeholder="one predicate or query per line, e.g. P1 > 0 &amp;&amp; P2 == 0 or P=? [F&lt;=10 P3=1]"></textarea></label>' +
    '<button id="query" title="probabilities and expected tokens, as plan-runner analyze --prob --transient">ask</button>' +
    '<button id="query-cancel" class="hidden" title="stop the question">cancel</button>' +
    '<span id="query-progress" class="mono"></span>' +
    '</div><div id="query-result"></div>';
}

// Stops the running question (the header's cancel button does the same while one runs).
function cancelQuestion() {
  api('POST', '/api/analysis/query/cancel').then(showQuestionProgress).catch((e) => status(e.message));
}

let asking = false;

// The question's progress line: its phase (the time point the transient solver works
// towards), the point of the times asked, the solver's iterations done of planned.
// Shown in the panel's header and beside the form's buttons.
function showQuestionProgress(p) {
  let text = '';
  if (p.state !== 'done' && p.state !== 'idle') {
    const it = p.of ? ', ' + p.iterations.toLocaleString('en') + ' of ' +
      p.of.toLocaleString('en') + ' iterations' : '';
    const pt = p.points > 1 ? ', point ' + p.point + ' of ' + p.points : '';
    text = 'question ' + p.state + ' (' + p.phase + pt + ')' + it + ', ' +
      fmt(Math.round(p.seconds * 10) / 10) + ' s';
  }
  $('analysis-progress').textContent = text;
  if ($('query-progress')) $('query-progress').textContent = text;
}

// Asks the server the form's questions and shows a table: a row per predicate (steady state,
// then each time) and per place (expected tokens at each time). Each number's cell carries
// its full value in data-value. While the server computes, the progress line shows how far
// the transient solver is and the cancel button stops it.
async function ask() {
  const out = $('query-result');
  const text = $('query-times').value.trim();
  const times = text ? text.split(/[\s,]+/).filter((x) => x).map(Number) : [];
  const lines = $('query-prob').value.split('\n').map((x) => x.trim()).filter((x) => x);
  // A line in Storm's syntax (`P=? [F<=10 done=1]`, `T=? …`, `S=? …`, `R{"r"}=? …`) is a
  // query (`analyze --query`); any other line a predicate (`analyze --prob`).
  const isQuery = (x) => /^(P|T|S|R\s*\{[^}]*\})\s*(max|min)?\s*=\s*\?/.test(x);
  const queries = lines.filter(isQuery);
  const prob = lines.filter((x) => !isQuery(x));
  if (times.some((t) => !Number.isFinite(t))) {
    out.innerHTML = '<p class="error">times: numbers separated by commas</p>';
    return;
  }
  if (asking) return;
  asking = true;
  out.classList.add('stale');
  $('analysis-cancel').classList.remove('hidden');
  $('query-cancel').classList.remove('hidden');
  $('query').disabled = true;
  let q;
  let polling = true;
  const poll = (async () => {
    while (polling) {
      await new Promise((r) => setTimeout(r, 200));
      if (!polling) break;
      try {
        showQuestionProgress(await api('GET', '/api/analysis/query/progress'));
      } catch (e) {
        break;
      }
    }
  })();
  try {
    const res = await fetch('/api/analysis/query', {
      method: 'POST',
      headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ transient: times, prob, query: queries }),
    });
    const data = await res.json();
    if (res.status === 409 && data.kind === 'cancelled') {
      const p = data.progress;
      out.innerHTML = '<p class="error" data-cancelled="' + p.iterations + '">question cancelled (' +
        escapeHtml(p.phase) + ') after ' + p.iterations.toLocaleString('en') + ' of ' +
        p.of.toLocaleString('en') + ' iterations</p>';
      return;
    }
    if (!res.ok) throw new Error(data.error || res.statusText);
    q = data;
  } catch (e) {
    if (unreachable(e)) offline(e);
    out.innerHTML = '<p class="error">' + escapeHtml(e.message) + '</p>';
    return;
  } finally {
    polling = false;
    asking = false;
    out.classList.remove('stale');
    $('analysis-cancel').classList.add('hidden');
    $('query-cancel').classList.add('hidden');
    $('query').disabled = false;
    await poll;
    showQuestionProgress({ state: 'done' });
  }
  const cell = (attrs, v) => '<td class="mono" ' + attrs + ' data-value="' + v + '">' + fmt(v) + '</td>';
  let html = '';
  if (q.queries && q.queries.length) {
    html += '<table class="query-answers">';
    for (const a of q.queries) {
      const x = escapeHtml(a.query);
      html += '<tr><td class="qname mono">' + x + '</td><td class="mono" data-query="' + x +
        '" data-value="' + a.value + '">' + (typeof a.value === 'number' ? fmt(a.value) : '∞') +
        '</td></tr>';
    }
    html += '</table>';
  }
  html += '<table class="query"><tr><th></th>' + (prob.length ? '<th>steady</th>' : '') +
    q.transient.map((p) => '<th>t = ' + fmtTime(p.t) + '</th>').join('') + '</tr>';
  for (const e of prob) {
    const x = escapeHtml(e);
    html += '<tr><td class="qname mono">P(' + x + ')</td>' +
      cell('data-prob="' + x + '" data-t="steady"', q.steady_state.probability[e]) +
      q.transient.map((p) => cell('data-prob="' + x + '" data-t="' + p.t + '"', p.probability[e])).join('') +
      '</tr>';
  }
  if (q.transient.length) {
    for (const pl of net.places) {
      const x = escapeHtml(pl.name);
      html += '<tr><td class="qname">E[' + x + ']</td>' + (prob.length ? '<td></td>' : '') +
        q.transient.map((p) => cell('data-tokens="' + x + '" data-t="' + p.t + '"', p.mean_tokens[pl.name])).join('') +
        '</tr>';
    }
  }
  out.innerHTML = html + '</table>';
  plotAnswers(out, q, prob);
}

// Most tokens each place ever holds, in the net's order.
function boundsTable(bounds) {
  if (!bounds) return '';
  let html = '<h4>place bounds</h4><table class="bounds">';
  for (const p of net.places) {
    if (!(p.name in bounds)) continue;
    html += '<tr data-bound="' + escapeHtml(p.name) + '"><td>' + escapeHtml(p.name) +
      '</td><td class="mono">' + bounds[p.name] + '</td></tr>';
  }
  return html + '</table>';
}

// Invariants as weighted sums of names (`P1 + 2·P3`), the names in the net's order; the
// first 50.
function invariantList(title, vectors, names) {
  if (!vectors) return '';
  const shown = vectors.slice(0, 50);
  let html = '<h4>' + title + ' (' + vectors.length + ')</h4><ol class="invariants mono">';
  for (const v of shown) {
    const terms = names.filter((n) => n in v).map((n) => (v[n] === 1 ? '' : v[n] + '·') + n);
    html += '<li>' + escapeHtml(terms.join(' + ')) + '</li>';
  }
  if (vectors.length > shown.length) html += '<li>… ' + (vectors.length - shown.length) + ' more</li>';
  return html + '</ol>';
}

// The plan's reward structures: long-run reward per unit of time.
function rewardTable(rewards) {
  let html = '<h4>rewards (per unit of time)</h4><table class="rewards">';
  for (const [name, r] of Object.entries(rewards)) {
    html += '<tr data-reward="' + escapeHtml(name) + '"><td>' + escapeHtml(name) +
      '</td><td class="mono">' + fmt(r.rate) + '</td></tr>';
  }
  return html + '</table>';
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
