// gspn viewer, runs that are not the page's own token game: a running plan followed over a
// WebSocket (with its simulated world, map.js), and a journal played back on a time slider.
'use strict';

// ---- live run --------------------------------------------------------------------------

// Events the log keeps on the page.
const LOG_KEPT = 500;
const live = { logTotal: 0 };

// Follows a running plan: the server sends the net, then snapshots; on a lost connection
// the page reconnects and the server starts again with the net and the current snapshot.
function startLive() {
  for (const id of ['step', 'step-n', 'run', 'reset', 'n', 'seed', 'trace-panel']) {
    const e = $(id);
    (e.closest('label') || e).classList.add('hidden');
  }
  $('speed').closest('label').classList.add('hidden');
  $('stop').classList.remove('hidden');
  $('log-panel').classList.remove('hidden');
  $('stop').addEventListener('click', () =>
    api('POST', '/api/live/stop').catch((e) => status(e.message)));
  connectLive();
}

function connectLive() {
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const socket = new WebSocket(scheme + '//' + location.host + '/api/live/ws');
  socket.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    if (msg.type === 'net') {
      const first = net === null;
      net = msg;
      $('title').textContent = net.name + ' — live';
      document.title = net.name + ' — gspn (live)';
      scaleCoordinates();
      drawNet();
      if (first) fit();
      $('log').textContent = '';
      live.logTotal = 0;
    } else if (msg.type === 'state') {
      const t0 = performance.now();
      applyLive(msg);
      pushCapped(gspnPerf.handler, performance.now() - t0);
      afterPaint(() => pushCapped(gspnPerf.frames, performance.now() - t0));
      markDrawn();
    }
  };
  socket.onopen = () => {
    status('');
    online();
  };
  socket.onclose = () => {
    status('connection lost, reconnecting…');
    offline();
    setTimeout(connectLive, 1000);
  };
}

function applyLive(s) {
  s.tokens.forEach((k, i) => setTokens(i, k));
  setAllEnabled(s.firable);
  // Before the map is drawn: its clock line says when the run (and so the world) stopped.
  $('map-panel').classList.toggle('stopped', !!s.stopped);
  if (s.world) drawWorld(s.world);
  followLive(s);
  $('clock').textContent = 'time ' + fmt(s.time) + ', ' + s.firings + ' firings' +
    (s.stopped ? ' — stopped: ' + s.stopped : '') +
    (s.lagged ? ' (' + s.lagged + ' events skipped)' : '');
  $('marking-text').textContent = shorten(s.text, 2000);
  const ol = $('log');
  const follow = atBottom(ol);
  const filter = $('log-filter').value.trim().toLowerCase();
  for (const e of s.log) {
    const li = listItem(e.seq, fmtTime(e.time) + '  ' + e.text);
    if (filter && !li.textContent.toLowerCase().includes(filter)) li.classList.add('hidden');
    ol.appendChild(li);
    live.logTotal = Math.max(live.logTotal, e.seq);
  }
  while (ol.childElementCount > LOG_KEPT) ol.firstElementChild.remove();
  $('log-count').textContent = live.logTotal > ol.childElementCount
    ? 'last ' + ol.childElementCount + ' of ' + live.logTotal : live.logTotal + ' events';
  if (follow) ol.scrollTop = ol.scrollHeight;
  if (s.stopped) $('stop').disabled = true;
}

// ---- replay ----------------------------------------------------------------------------

// Plays a journal back: the slider picks a frame (the marking after each firing); `run`
// plays the frames at the chosen speed.
async function startReplay() {
  for (const id of ['step', 'step-n', 'reset', 'n', 'seed']) {
    const e = $(id);
    (e.closest('label') || e).classList.add('hidden');
  }
  const { frames } = await api('GET', '/api/replay');
  const slider = $('slider');
  slider.max = String(frames.length - 1);
  $('slider-label').classList.remove('hidden');
  const show = (i) => {
    const f = frames[i];
    slider.value = String(i);
    f.tokens.forEach((k, p) => setTokens(p, k));
    setFired(f.transition ? transitionIndex(f.transition) : -1);
    const items = $('trace').children;
    for (const li of $('trace').querySelectorAll('li.current')) li.classList.remove('current');
    if (i > 0 && items[i - 1]) items[i - 1].classList.add('current');
    $('frame').textContent = i + '/' + (frames.length - 1);
    $('clock').textContent = 'time ' + fmt(f.time) + ', ' + i + ' firings' +
      (f.transition ? ' — ' + f.transition + ' fired' : '');
  };
  slider.addEventListener('input', () => show(Number(slider.value)));
  const ol = $('trace');
  ol.textContent = '';
  frames.slice(1).forEach((f, i) => {
    const li = document.createElement('li');
    li.textContent = fmt(f.time) + '  ' + f.transition;
    li.addEventListener('click', () => show(i + 1));
    ol.appendChild(li);
  });
  let timer = null;
  $('run').addEventListener('click', () => {
    if (timer !== null) {
      clearInterval(timer);
      timer = null;
      $('run').textContent = 'run';
      return;
    }
    $('run').textContent = 'pause';
    timer = setInterval(() => {
      const i = Number(slider.value) + 1;
      if (i >= frames.length) {
        clearInterval(timer);
        timer = null;
        $('run').textContent = 'run';
        return;
      }
      show(i);
    }, 1000 / (Number($('speed').value) || 1));
  });
  show(0);
}
