// gspn viewer, the page among others: every open page follows the same token game (a step
// in one tab shows in the others, through `/api/sim/wait`), a banner says when the server
// cannot be reached (the last results stay on the page), and the current view is exported
// as SVG or PNG.
//
// Test hooks: #offline is visible while the server is unreachable; window.gspnExport.svg()
// gives the SVG text and window.gspnExport.png() a promise of the PNG as a data: URL.
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

// The view as drawn now (same pan and zoom, same size), with the page's style inside, in the
// theme the page shows.
function exportSvg() {
  const svg = $('net');
  const copy = svg.cloneNode(true);
  const box = svg.getBoundingClientRect();
  copy.setAttribute('width', String(Math.round(box.width)));
  copy.setAttribute('height', String(Math.round(box.height)));
  copy.setAttribute('viewBox', '0 0 ' + Math.round(box.width) + ' ' + Math.round(box.height));
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

// The view as a PNG data: URL (the canvas itself for a large net).
function exportPng() {
  if (cvs.on) return Promise.resolve(cvs.el.toDataURL('image/png'));
  const text = exportSvg();
  return new Promise((resolve, reject) => {
    const img = new Image();
    img.onload = () => {
      const c = document.createElement('canvas');
      const k = window.devicePixelRatio || 1;
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
  window.gspnExport = { svg: exportSvg, png: exportPng };
  $('export-svg').addEventListener('click', () => {
    if (cvs.on) {
      status('a large net is drawn on a canvas: export it as PNG');
      return;
    }
    const url = URL.createObjectURL(new Blob([exportSvg()], { type: 'image/svg+xml' }));
    download(url, (net ? net.name : 'net') + '.svg');
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  });
  $('export-png').addEventListener('click', () =>
    exportPng().then((url) => download(url, (net ? net.name : 'net') + '.png')).catch((e) => status(e.message)));
}
