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
      adoptLayout(msg);
      net = msg;
      $('title').textContent = net.name + ' — live';
      $('title').title = $('title').textContent;
      document.title = net.name + ' — gspn (live)';
      scaleCoordinates();
      drawNet();
      if (first) fit();
      $('log').textContent = '';
      live.logTotal = 0;
    } else if (msg.type === 'history') {
      // The run before this page joined: the plot and the robot timeline start at 0.
      follow.times.length = follow.tokens.length = 0;
      for (const f of msg.frames) recordTokens(f.time, f.tokens);
      follow.segments.clear();
      for (const row of msg.robots) {
        follow.segments.set(row.robot, row.stays.map((x) => ({ t0: x.t0, t1: x.t1, place: x.place, state: '' })));
      }
      tputReset(msg.throughput, msg.after);
      scheduleFollowDraw();
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
    li.title = timeTitle(e.time);
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

// Speeds of the replay's playback: model seconds per second of wall time.
const REPLAY_SPEEDS = [0.1, 1, 10, 100, 1000];

// Plays a journal back on a full-width timeline in model seconds: the slider picks a time
// (the marking after the last firing up to it), ◀ and ▶ (keys ← →) step one firing, play
// (space) runs model time at the chosen speed (×1 = real time, ×10 ten times faster; a change
// while playing applies at once), `loop` starts again at the end; the trace follows. The
// robots' stays (from the journal's events) put their ids on the places that hold them and
// fill the robot timeline; a journal with a simulated world shows its map, the robots moving
// between their recorded poses.
//
// The run comes a window of firings at a time (`/api/replay/window?k=`), fetched when the
// slider, a step or the playback reaches it (the next one ahead while playing), a few kept:
// the page and the server hold the window shown, not the run (issue 32). The trace lists the
// window's firings.
async function startReplay() {
  for (const id of ['step', 'step-n', 'reset', 'n', 'seed']) {
    const e = $(id);
    (e.closest('label') || e).classList.add('hidden');
  }
  $('speed').closest('label').classList.add('hidden');
  const { firings, end, window: size, starts, world, conform, robots, throughput } = await api('GET', '/api/replay');
  tputReset(throughput);
  drawThroughput();
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
  // Windows fetched (k -> {first, frames, times, poses, poseTimes}), most recently used last.
  const KEPT = 4;
  const windows = new Map();
  const pending = new Map();
  const fetchWindow = (k) => {
    if (windows.has(k)) return Promise.resolve(windows.get(k));
    if (!pending.has(k)) {
      pending.set(k, api('GET', '/api/replay/window?k=' + k).then((w) => {
        pending.delete(k);
        w.times = w.frames.map((f) => f.time);
        w.poseTimes = w.poses.map((p) => p.time);
        windows.set(k, w);
        while (windows.size > KEPT) windows.delete(windows.keys().next().value);
        return w;
      }, (e) => {
        pending.delete(k);
        throw e;
      }));
    }
    return pending.get(k);
  };
  // Runs `then` with window k: at once when it is here, else once fetched unless a later
  // request came meanwhile (the latest wins).
  let wanted = 0;
  let done = 0;
  const withWindow = (k, then) => {
    const ticket = ++wanted;
    const w = windows.get(k);
    if (w) {
      windows.delete(k);
      windows.set(k, w);
      done = ticket;
      then(w);
      return;
    }
    fetchWindow(k).then((got) => {
      if (ticket !== wanted) return;
      done = ticket;
      then(got);
    }, () => {});
  };
  const windowOf = (i) => Math.floor(i / size);
  // The robots at t: between two recorded poses, on the straight line between them.
  const showWorld = (w, t) => {
    const poses = w.poses;
    if (!world || poses.length === 0) return;
    const k = lastAtOrBefore(w.poseTimes, t);
    const a = poses[k];
    const b = poses[k + 1];
    const u = b && b.time > a.time ? Math.min(1, Math.max(0, (t - a.time) / (b.time - a.time))) : 0;
    const next = new Map(b ? b.robots.map((r) => [r.id, r]) : []);
    drawWorld({
      time: t,
      map: world.map,
      robots: a.robots.map((r) => {
        const q = next.get(r.id);
        const moved = q && u > 0 ? { x: r.x + (q.x - r.x) * u, y: r.y + (q.y - r.y) * u } : {};
        return Object.assign({ radius: world.radius }, r, moved);
      }),
    });
  };
  // Each robot's stays, for the timeline and for where it is at t.
  follow.segments.clear();
  for (const row of robots || []) {
    follow.segments.set(row.robot, row.stays.map((s) => ({ t0: s.t0, t1: s.t1, place: s.place, state: 'agent ' + s.agent, agent: s.agent })));
  }
  const showRobots = (t) => {
    if (!follow.segments.size) return;
    follow.robots.clear();
    follow.cursor = t;
    const byPlace = new Map();
    for (const [id, segs] of follow.segments) {
      const s = segs[lastAtOrBefore(segs.map((x) => x.t0), t)];
      if (!s || s.t0 > t + 1e-12 * Math.max(1, end)) continue;
      follow.robots.set(id, { id: s.agent, place: s.place, state: 'since ' + fmtTime(s.t0) + ' s' });
      if (!byPlace.has(s.place)) byPlace.set(s.place, []);
      byPlace.get(s.place).push(id);
    }
    net.places.forEach((p, i) => {
      const ids = byPlace.get(p.name);
      setAgents(i, ids ? ids.sort(byId).join(' ') : '');
    });
  };
  const slider = $('slider');
  slider.min = '0';
  slider.max = String(end);
  slider.step = 'any';
  $('timeline').classList.remove('hidden');
  $('timeline-end').textContent = fmtTime(end) + ' s';
  $('timeline-end').title = timeTitle(end);
  $('timeline-end').dataset.t = String(end);
  const ol = $('trace');
  $('trace-count').textContent = firings + ' firings';
  // The trace lists the firings of the window shown (its first frame's number: `listed`).
  let listed = -1;
  const listWindow = (w) => {
    if (listed === w.first) return;
    listed = w.first;
    ol.textContent = '';
    w.frames.forEach((f, j) => {
      const i = w.first + j;
      if (i === 0) return;
      const li = listItem(i, fmtTime(f.time) + '  ' + f.transition);
      li.title = timeTitle(f.time);
      li.addEventListener('click', () => show(i));
      ol.appendChild(li);
    });
  };
  let at = 0;
  let now = 0;
  // Frame i of window w; the map at model time t (the frame's time unless the slider picked
  // another).
  // What model time t shows whatever the window: the robots, the table, the cursor.
  const showTime = (t) => {
    now = t;
    slider.value = String(now);
    showRobots(now);
    if (conform) showConformAt(conform, now);
    $('timeline-time').textContent = 't = ' + fmtTime(now) + ' s';
    $('timeline-time').dataset.t = String(now);
    $('timeline-time').title = timeTitle(now);
    scheduleFollowDraw();
  };
  const render = (w, i, t) => {
    const f = w.frames[i - w.first];
    showTime(t === undefined ? f.time : t);
    showWorld(w, now);
    if (i === at && t !== undefined && $('frame').textContent) return;
    at = i;
    f.tokens.forEach((k, p) => setTokens(p, k));
    setFired(f.transition ? transitionIndex(f.transition) : -1);
    recordTokens(f.time, f.tokens);
    listWindow(w);
    for (const li of ol.querySelectorAll('li.current')) li.classList.remove('current');
    const li = i > 0 ? ol.children[i - Math.max(1, w.first)] : null;
    if (li) {
      li.classList.add('current');
      li.scrollIntoView({ block: 'nearest' });
    }
    $('frame').textContent = i + '/' + firings;
    $('clock').textContent = 'time ' + fmtTime(f.time) + ', ' + i + ' firings' +
      (f.transition ? ' — ' + f.transition + ' fired' : '');
  };
  const show = (i, t) => withWindow(windowOf(i), (w) => render(w, i, t));
  // The frame shown at model time t: the last firing at or before it (the range input
  // keeps its value to about 15 digits: a hair's tolerance).
  const showAt = (t) => {
    showTime(t);
    withWindow(lastAtOrBefore(starts, t), (w) => render(w, w.first + lastAtOrBefore(w.times, t), t));
  };
  slider.addEventListener('input', () => showAt(Number(slider.value)));
  const speedBox = $('replay-speed');
  speedBox.textContent = '';
  for (const v of REPLAY_SPEEDS) {
    const o = document.createElement('option');
    o.value = String(v);
    o.textContent = '×' + v;
    speedBox.appendChild(o);
  }
  speedBox.value = '1';
  speedBox.closest('label').classList.remove('hidden');
  // Playing: every animation frame moves model time on by the wall time since the last
  // one times the speed.
  let frame = null;
  let wall = 0;
  const playing = () => frame !== null;
  const pause = () => {
    if (frame !== null) cancelAnimationFrame(frame);
    frame = null;
    $('run').textContent = 'run';
    $('play').textContent = '▶ play';
  };
  const tick = (ms) => {
    const dt = Math.max(0, ms - wall) / 1000;
    wall = ms;
    let t = now + dt * (Number(speedBox.value) || 1);
    if (t >= end) {
      if (!$('loop').checked) {
        show(firings, end);
        pause();
        return;
      }
      t = 0;
    }
    // Playing on: the window after this one, fetched ahead.
    const k = lastAtOrBefore(starts, t);
    if (k + 1 < starts.length) fetchWindow(k + 1).catch(() => {});
    if (windows.has(k)) showAt(t);
    else {
      fetchWindow(k).catch(() => {});
      now = t;
    }
    frame = requestAnimationFrame(tick);
  };
  const play = () => {
    if (playing()) {
      pause();
      return;
    }
    if (now >= end) show(0, 0);
    $('run').textContent = 'pause';
    $('play').textContent = '❚❚ pause';
    wall = performance.now();
    frame = requestAnimationFrame(tick);
  };
  const stepBy = (d) => {
    pause();
    show(Math.min(firings, Math.max(0, at + d)));
  };
  $('run').addEventListener('click', play);
  $('play').addEventListener('click', play);
  $('step-back').addEventListener('click', () => stepBy(-1));
  $('step-forward').addEventListener('click', () => stepBy(1));
  // `tick`: the animation frame's timestamp (ms) that set `time`, so a test can read the
  // model time advanced per wall second without timing the page from outside.
  // `settled`: the last window asked for is shown (a test waits for it after moving the
  // slider; the frames of a window not yet fetched come when it arrives).
  window.gspnReplay = { playing, at: () => at, time: () => now, tick: () => wall, settled: () => done === wanted };
  await fetchWindow(0);
  show(0);
}
