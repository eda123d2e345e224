// gspn viewer, the page among others: every open page follows the same token game (a step
// in one tab shows in the others, through `/api/sim/wait`), a banner says when the server
// cannot be reached (the last results stay on the page), and the current view is exported
// as SVG or PNG, or the whole net at full resolution (the header's buttons).
//
// Test hooks: #offline is visible while the server is unreachable; window.gspnExport.svg()
// gives the view's SVG text (`svg(true)`: the whole net's) and window.gspnExport.png() a
// promise of the PNG as a data: URL (`png(true)`: the whole net's).
'use strict';

// ---- other tabs --------------------------------------------------------------------------

// Waits on the server for changes of the token game made anywhere (this tab's own requests
// show at once; another tab's within one round trip).
async function followSession() {
  for (;;) {
    const after = state && state.version !== undefined ? state.version : -1;
    try {
      const s = await api('GET', '/api/sim/wait?after=' + after);
      online();
      // Another page edited the net: draw the new one first.
      if (net && s.net_version !== undefined && s.net_version !== net.version) await reloadNet();
      if (!busy && (!state || s.version !== state.version)) applyState(s);
    } catch (e) {
      offline(e);
      await new Promise((r) => setTimeout(r, 2000));
    }
  }
}

// ---- a lost server -----------------------------------------------------------------------

// Whether `e` says the server could not be reached (not an error the server sent).
function unreachable(e) {
  return e instanceof TypeError || /Failed to fetch|NetworkError|Load failed/.test(String(e && e.message));
}

function offline(e) {
  if (e && !unreachable(e)) return;
  $('offline').classList.remove('hidden');
}

function online() {
  $('offline').classList.add('hidden');
}

// ---- export ------------------------------------------------------------------------------

let styleText = null;

async function loadStyle() {
  if (styleText === null) {
    try {
      styleText = await (await fetch('/style.css')).text();
    } catch (e) {
      styleText = '';
    }
  }
  return styleText;
}

// The whole net's box in drawing units (nodes, routed arcs, room for the names).
function netBounds() {
  let [xa, ya, xb, yb] = [Infinity, Infinity, -Infinity, -Infinity];
  const grow = (x, y) => {
    xa = Math.min(xa, x);
    ya = Math.min(ya, y);
    xb = Math.max(xb, x);
    yb = Math.max(yb, y);
  };
  for (const n of net.places.concat(net.transitions)) grow(n.x, n.y);
  for (const a of net.arcs) for (const q of a.points) grow(q[0], q[1]);
  if (!Number.isFinite(xa)) return { x0: 0, y0: 0, w: 1, h: 1 };
  return { x0: xa - 90, y0: ya - 50, w: xb - xa + 180, h: yb - ya + 110 };
}

// The view as drawn now (same pan and zoom, same size), or with `whole` the whole net at
// zoom 1 (full resolution, whatever the view); with the page's style inside, in the theme
// the page shows. A net drawn on a canvas is written out as vector SVG from its data.
function exportSvg(whole) {
  if (cvs.on) return vectorSvg();
  const svg = $('net');
  const copy = svg.cloneNode(true);
  const box = svg.getBoundingClientRect();
  let [w, h] = [Math.round(box.width), Math.round(box.height)];
  if (whole) {
    const b = netBounds();
    [w, h] = [Math.ceil(b.w), Math.ceil(b.h)];
    copy.querySelector('#viewport').setAttribute('transform', 'translate(' + -b.x0 + ',' + -b.y0 + ')');
    copy.classList.remove('no-labels', 'no-params');
  }
  copy.setAttribute('width', String(w));
  copy.setAttribute('height', String(h));
  copy.setAttribute('viewBox', '0 0 ' + w + ' ' + h);
  return withStyle(copy);
}

// The page's style and colours inside an exported <svg>, serialised.
function withStyle(copy) {
  const theme = document.documentElement.dataset.theme;
  if (theme) copy.setAttribute('data-theme', theme);
  const style = document.createElementNS(SVG_NS, 'style');
  // The page's variables are set on :root, which is the <svg> in a file of its own.
  const vars = getComputedStyle(document.documentElement);
  const names = ['--bg', '--fg', '--muted', '--node', '--stroke', '--arc', '--accent', '--inhib',
    '--enabled', '--enabled-fill', '--fired'];
  // After the page's rules, and more specific than its `:root[data-theme]`: the colours shown.
  const root = ':root:root:root{' + names.map((n) => n + ':' + vars.getPropertyValue(n)).join(';') + '}';
  style.textContent = (styleText || '') + root + '#net{background:' + vars.getPropertyValue('--bg') + '}';
  copy.insertBefore(style, copy.firstChild);
  return new XMLSerializer().serializeToString(copy);
}

// The whole net as SVG text built from its data (a net drawn on a canvas has no SVG on
// the page): arcs, places with their tokens, transitions, names — vector, any size.
function vectorSvg() {
  const b = netBounds();
  const svg = document.createElementNS(SVG_NS, 'svg');
  svg.setAttribute('xmlns', SVG_NS);
  svg.setAttribute('id', 'net');
  svg.setAttribute('width', String(Math.ceil(b.w)));
  svg.setAttribute('height', String(Math.ceil(b.h)));
  svg.setAttribute('viewBox', '0 0 ' + Math.ceil(b.w) + ' ' + Math.ceil(b.h));
  svg.appendChild($('net').querySelector('defs').cloneNode(true));
  const root = el('g', { transform: 'translate(' + -b.x0 + ',' + -b.y0 + ')' }, svg);
  const arcs = el('g', {}, root);
  net.arcs.forEach((a, i) => {
    const pts = arcPoints(i);
    el('path', {
      class: 'arc ' + a.kind,
      d: 'M' + pts.map((q) => q[0].toFixed(1) + ' ' + q[1].toFixed(1)).join(' L'),
      'marker-end': a.kind === 'inhibitor' ? 'url(#inhibitor)' : 'url(#arrow)',
    }, arcs);
  });
  const nodes = el('g', {}, root);
  net.places.forEach((p, i) => {
    const g = el('g', { class: 'node place', 'data-place': p.name, transform: 'translate(' + p.x + ',' + p.y + ')' }, nodes);
    el('circle', { class: 'body', r: R }, g);
    if (placeTokens[i] > 0) el('text', { class: 'count' }, g).textContent = String(placeTokens[i]);
    el('text', { class: 'label', y: R + 13 }, g).textContent = p.name;
  });
  net.transitions.forEach((t) => {
    const g = el('g', { class: 'node transition ' + t.kind, 'data-transition': t.name, transform: 'translate(' + t.x + ',' + t.y + ')' }, nodes);
    const [hw, hh] = transitionHalf(t);
    el('rect', { x: -hw, y: -hh, width: 2 * hw, height: 2 * hh }, g);
    el('text', { class: 'label', y: hh + 13 }, g).textContent = t.name;
    el('text', { class: 'param', y: -hh - 5 }, g).textContent = paramText(t);
  });
  return withStyle(svg);
}

// Largest side of an exported PNG, in pixels (browsers refuse bigger canvases).
const PNG_MAX = 16384;

// The view as a PNG data: URL, or with `whole` the whole net at twice its drawing size (less
// when that would pass PNG_MAX pixels).
function exportPng(whole) {
  if (cvs.on && !whole) return Promise.resolve(cvs.el.toDataURL('image/png'));
  const text = exportSvg(whole);
  return new Promise((resolve, reject) => {
    const img = new Image();
    img.onload = () => {
      const c = document.createElement('canvas');
      const k = whole ? Math.min(2, PNG_MAX / Math.max(img.width, img.height)) : window.devicePixelRatio || 1;
      c.width = img.width * k;
      c.height = img.height * k;
      const g = c.getContext('2d');
      g.scale(k, k);
      g.drawImage(img, 0, 0);
      resolve(c.toDataURL('image/png'));
    };
    img.onerror = () => reject(new Error('the SVG could not be drawn'));
    // A data: URL: the page's policy allows no blob: images.
    img.src = 'data:image/svg+xml;base64,' + btoa(unescape(encodeURIComponent(text)));
  });
}

function download(href, name) {
  const a = document.createElement('a');
  a.href = href;
  a.download = name;
  a.click();
}

function setupExport() {
  loadStyle();
  window.gspnExport = { svg: exportSvg, png: exportPng, pdf: exportPdf };
  // The buttons export the whole net (the view: `gspnExport.svg()`, `.png()`).
  $('export-svg').addEventListener('click', () => {
    const url = URL.createObjectURL(new Blob([exportSvg(true)], { type: 'image/svg+xml' }));
    download(url, (net ? net.name : 'net') + '.svg');
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  });
  $('export-png').addEventListener('click', () =>
    exportPng(true).then((url) => download(url, (net ? net.name : 'net') + '.png')).catch((e) => status(e.message)));
  $('export-pdf').addEventListener('click', downloadPdf);
}
