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
      $('title').title = $('title').textContent;
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
  if (s.conform) showConform(s.conform);
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

// Plays a journal back on a full-width timeline in model seconds: the slider picks a time
// (the marking after the last firing up to it), ◀ and ▶ (keys ← →) step one firing, play
// (space) plays the firings at the speed set now (changed while playing, it applies at
// once), `loop` starts again at the end; the trace follows. A journal with a simulated world
// shows its map beside the net: the robots where they were at the slider's time.
async function startReplay() {
  for (const id of ['step', 'step-n', 'reset', 'n', 'seed']) {
    const e = $(id);
    (e.closest('label') || e).classList.add('hidden');
  }
  const { frames, world, conform } = await api('GET', '/api/replay');
  const times = frames.map((f) => f.time);
  const poses = world ? world.frames : [];
  const poseTimes = poses.map((w) => w.time);
  const end = Math.max(times[times.length - 1] || 0, poseTimes[poseTimes.length - 1] || 0);
  // The last entry of the sorted `ts` at or before t (0 if none).
  const lastAtOrBefore = (ts, t0) => {
    const t = t0 + 1e-12 * Math.max(1, end);
    let lo = 0;
    let hi = ts.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (ts[mid] <= t) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  };
  const showWorld = (t) => {
    if (!world || poses.length === 0) return;
    const w = poses[lastAtOrBefore(poseTimes, t)];
    drawWorld({
      time: t,
      map: world.map,
      robots: w.robots.map((r) => Object.assign({ radius: world.radius }, r)),
    });
  };
  const slider = $('slider');
  slider.min = '0';
  slider.max = String(end);
  slider.step = 'any';
  $('timeline').classList.remove('hidden');
  $('timeline-end').textContent = fmtTime(end) + ' s';
  let at = 0;
  // Frame i; the map at model time t (the frame's time unless the slider picked another).
  const show = (i, t) => {
    at = i;
    const f = frames[i];
    const now = t === undefined ? f.time : t;
    slider.value = String(now);
    showWorld(now);
    if (conform) showConformAt(conform, now);
    f.tokens.forEach((k, p) => setTokens(p, k));
    setFired(f.transition ? transitionIndex(f.transition) : -1);
    recordTokens(f.time, f.tokens);
    for (const li of $('trace').querySelectorAll('li.current')) li.classList.remove('current');
    const li = i > 0 ? $('trace').children[i - 1] : null;
    if (li) {
      li.classList.add('current');
      li.scrollIntoView({ block: 'nearest' });
    }
    $('frame').textContent = i + '/' + (frames.length - 1);
    $('timeline-time').textContent = 't = ' + fmtTime(now) + ' s';
    $('clock').textContent = 'time ' + fmtTime(f.time) + ', ' + i + ' firings' +
      (f.transition ? ' — ' + f.transition + ' fired' : '');
  };
  // The frame shown at model time t: the last firing at or before it (the range input
  // keeps its value to about 15 digits: a hair's tolerance).
  const frameAt = (t) => lastAtOrBefore(times, t);
  slider.addEventListener('input', () => {
    const t = Number(slider.value);
    show(frameAt(t), t);
  });
  const ol = $('trace');
  ol.textContent = '';
  frames.slice(1).forEach((f, i) => {
    const li = listItem(i + 1, fmtTime(f.time) + '  ' + f.transition);
    li.addEventListener('click', () => show(i + 1));
    ol.appendChild(li);
  });
  $('trace-count').textContent = (frames.length - 1) + ' firings';
  let timer = null;
  const playing = () => timer !== null;
  const pause = () => {
    clearTimeout(timer);
    timer = null;
    $('run').textContent = 'run';
    $('play').textContent = '▶ play';
  };
  const tick = () => {
    let i = at + 1;
    if (i >= frames.length) {
      if (!$('loop').checked) {
        pause();
        return;
      }
      i = 0;
    }
    show(i);
    // The speed as it is now: a change while playing applies from the next firing.
    timer = setTimeout(tick, 1000 / (Number($('speed').value) || 1));
  };
  const play = () => {
    if (playing()) {
      pause();
      return;
    }
    if (at >= frames.length - 1) show(0);
    $('run').textContent = 'pause';
    $('play').textContent = '❚❚ pause';
    timer = setTimeout(tick, 1000 / (Number($('speed').value) || 1));
  };
  const stepBy = (d) => {
    pause();
    show(Math.min(frames.length - 1, Math.max(0, at + d)));
  };
  $('run').addEventListener('click', play);
  $('play').addEventListener('click', play);
  $('step-back').addEventListener('click', () => stepBy(-1));
  $('step-forward').addEventListener('click', () => stepBy(1));
  window.gspnReplay = { playing, at: () => at };
  show(0);
}
