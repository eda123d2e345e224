// gspn viewer, the editor (as GreatSPN's): `edit` (key e) shows its tool bar — select and
// move, place, exponential and immediate transition, arc, inhibitor arc — and a properties
// panel for the selected node (name, tokens, capacity; kind, rate, servers, weight,
// priority; its arcs with their kind and multiplicity). Each change is one operation sent
// to the server (POST /api/edit), which checks it as the file readers do and answers the
// new net, or why it refused (shown in #edit-msg, the net unchanged). Undo / redo: buttons,
// Ctrl-Z / Ctrl-Shift-Z. Save writes the file given to `serve --save-to`; PNPRO and PIPE
// XML download the net.
//
// Test hooks: #edit-mode, [data-tool=NAME] buttons, #undo, #redo, #edit-save,
// #export-pnpro, #export-pipe, #edit-msg (the last refusal or what was done), #props (the
// properties form: inputs named name, tokens, capacity, kind, rate, servers, weight,
// priority; #props-apply), #props-arcs with [data-arc="KIND PLACE TRANSITION"] rows with
// inputs named weight and kind and a delete button; the selected node's <g> has data-edit-selected.
'use strict';

const ed = {
  on: false,
  tool: 'select',
  sel: null, // {isPlace, name}
  arcFrom: null, // {isPlace, name}: the first end of the arc being drawn
  editable: false,
  saveTo: null,
  history: null,
};

const TOOLS = [
  ['select', 'v', 'select and move'],
  ['place', 'p', 'add places'],
  ['exponential', 't', 'add exponential transitions'],
  ['immediate', 'i', 'add immediate transitions'],
  ['arc', 'c', 'add arcs (source, then target)'],
  ['inhibitor', 'h', 'add inhibitor arcs (place, then transition)'],
];

function editMsg(text, error) {
  const m = $('edit-msg');
  m.textContent = text || '';
  m.classList.toggle('error', !!error);
}

// ---- the server --------------------------------------------------------------------------

// Sends one change; on success draws the answer, else shows the refusal.
async function change(path, body) {
  try {
    const r = await api('POST', path, body);
    adopt(r);
    const h = r.history;
    editMsg(path.endsWith('/undo') ? 'undone: ' + h.redo : path.endsWith('/redo') ? 'redone: ' + h.undo : 'done: ' + h.undo);
    return true;
  } catch (e) {
    editMsg(e.message, true);
    offline(e);
    return false;
  }
}

function editOp(op) {
  return change('/api/edit', op);
}

// A net from the server drawn in place of the current one: same scale and view, the token
// game's state, the selection kept by name.
function adoptNet(n) {
  adoptLayout(n);
  for (const node of n.places.concat(n.transitions)) {
    node.x *= scale;
    node.y *= scale;
  }
  for (const a of n.arcs) a.points = a.points.map((q) => [q[0] * scale, q[1] * scale]);
  net = n;
  choiceShown = [];
  follow.place = -1;
  follow.times.length = follow.tokens.length = 0;
  drawNet();
  applyView();
  describeSelection();
  if (ed.sel && nodeIndex(ed.sel) < 0) ed.sel = null;
  if (ed.arcFrom && nodeIndex(ed.arcFrom) < 0) ed.arcFrom = null;
  showSelection();
  $('analysis').innerHTML = '<p class="note">the net changed: analyse it again</p>';
  $('analysis-progress').textContent = '';
}

function adopt(r) {
  adoptNet(r.net);
  applyState(r.state);
  showHistory(r.history);
}

// Another page changed the net: draw the new one.
async function reloadNet() {
  try {
    adoptNet(await api('GET', '/api/net'));
    const s = await api('GET', '/api/edit');
    showHistory(s.history);
  } catch (e) {
    offline(e);
  }
}

function showHistory(h) {
  ed.history = h;
  $('undo').disabled = !h.undo;
  $('redo').disabled = !h.redo;
  $('undo').title = h.undo ? 'undo: ' + h.undo + ' (Ctrl-Z)' : 'nothing to undo';
  $('redo').title = h.redo ? 'redo: ' + h.redo + ' (Ctrl-Shift-Z)' : 'nothing to redo';
}

function undo() {
  if (ed.editable) change('/api/edit/undo');
}

function redo() {
  if (ed.editable) change('/api/edit/redo');
}

// Positions as drawn, in the file's units.
function positions() {
  const at = (n) => [n.x / scale, n.y / scale];
  return { places: net.places.map(at), transitions: net.transitions.map(at) };
}

async function save() {
  try {
    const r = await api('POST', '/api/edit/save', positions());
    editMsg('saved ' + r.saved + ' (' + r.bytes + ' bytes)');
  } catch (e) {
    editMsg(e.message, true);
  }
}

async function exportAs(format) {
  try {
    const r = await api('POST', '/api/edit/export', Object.assign({ format }, positions()));
    const url = URL.createObjectURL(new Blob([r.text], { type: 'application/xml' }));
    download(url, r.file);
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  } catch (e) {
    editMsg(e.message, true);
  }
}

// ---- the canvas --------------------------------------------------------------------------

function nodeRef(n) {
  const node = n.isPlace ? net.places[n.i] : net.transitions[n.i];
  return { isPlace: n.isPlace, name: node.name };
}

function nodeIndex(ref) {
  return ref.isPlace ? placeIndex(ref.name) : transitionIndex(ref.name);
}

function refJson(ref) {
  return ref.isPlace ? { place: ref.name } : { transition: ref.name };
}

// A mouse-up on the net in edit mode (app.js's handler asks first): `d` is the drag that it
// ends ({node, moved}); true when the editor used it.
function editMouseUp(d, ev) {
  if (!ed.on || !d) return false;
  if (d.node && d.moved) {
    const node = d.node.isPlace ? net.places[d.node.i] : net.transitions[d.node.i];
    const where = {};
    where[node.name] = [node.x / scale, node.y / scale];
    editOp({ op: 'move', places: d.node.isPlace ? where : {}, transitions: d.node.isPlace ? {} : where });
    return true;
  }
  if (d.moved) return true;
  if (!d.node) {
    if (ed.tool === 'place' || ed.tool === 'exponential' || ed.tool === 'immediate') {
      const rect = $('canvas').getBoundingClientRect();
      const x = (ev.clientX - rect.left - view.x) / view.k / scale;
      const y = (ev.clientY - rect.top - view.y) / view.k / scale;
      const op = ed.tool === 'place'
        ? { op: 'add_place', x, y }
        : { op: 'add_transition', kind: ed.tool, x, y };
      editOp(op).then((ok) => {
        if (!ok) return;
        const list = ed.tool === 'place' ? net.places : net.transitions;
        select({ isPlace: ed.tool === 'place', name: list[list.length - 1].name });
      });
    } else {
      ed.arcFrom = null;
      select(null);
    }
    return true;
  }
  const ref = nodeRef(d.node);
  if (ed.tool === 'arc' || ed.tool === 'inhibitor') {
    if (!ed.arcFrom) {
      ed.arcFrom = ref;
      showSelection();
      editMsg('arc from ' + ref.name + ': click its target');
    } else {
      const from = ed.arcFrom;
      ed.arcFrom = null;
      editOp({ op: 'add_arc', from: refJson(from), to: refJson(ref), inhibitor: ed.tool === 'inhibitor' })
        .then(() => showSelection());
    }
    return true;
  }
  select(ref);
  return true;
}

// ---- selection and properties ------------------------------------------------------------

function select(ref) {
  ed.sel = ref;
  showSelection();
}

function showSelection() {
  for (const g of document.querySelectorAll('[data-edit-selected]')) g.removeAttribute('data-edit-selected');
  for (const [ref, what] of [[ed.sel, 'selected'], [ed.arcFrom, 'arc-from']]) {
    if (!ref) continue;
    const i = nodeIndex(ref);
    if (i >= 0) (ref.isPlace ? placeEls : transEls)[i].setAttribute('data-edit-selected', what);
  }
  $('edit-delete').disabled = !ed.sel;
  canvasDirty();
  showProps();
}

function field(form, label, name, value, attrs) {
  const l = document.createElement('label');
  l.textContent = label + ' ';
  const input = document.createElement(attrs && attrs.options ? 'select' : 'input');
  input.name = name;
  if (attrs && attrs.options) {
    for (const [v, text] of attrs.options) {
      const o = document.createElement('option');
      o.value = v;
      o.textContent = text;
      input.appendChild(o);
    }
  } else {
    input.type = 'text';
    if (attrs && attrs.placeholder) input.placeholder = attrs.placeholder;
  }
  input.value = value === null || value === undefined ? '' : String(value);
  input.dataset.was = input.value;
  l.appendChild(input);
  form.appendChild(l);
  return input;
}

// The fields of the selected node; `apply` (or Enter) sends those that changed.
function showProps() {
  const form = $('props');
  form.textContent = '';
  $('props-arcs').textContent = '';
  $('edit-panel').classList.toggle('hidden', !ed.on);
  if (!ed.sel) {
    form.textContent = 'select a place or a transition (tool “select”, key v)';
    return;
  }
  const i = nodeIndex(ed.sel);
  if (i < 0) return;
  if (ed.sel.isPlace) {
    const p = net.places[i];
    field(form, 'name', 'name', p.name);
    field(form, 'tokens', 'tokens', p.tokens);
    field(form, 'capacity', 'capacity', p.capacity, { placeholder: 'unbounded' });
  } else {
    const t = net.transitions[i];
    field(form, 'name', 'name', t.name);
    const kind = field(form, 'kind', 'kind', t.kind, { options: [['exponential', 'exponential'], ['immediate', 'immediate']] });
    const exp = [
      field(form, 'rate', 'rate', t.kind === 'exponential' ? t.rate : 1),
      field(form, 'servers', 'servers', t.kind === 'exponential' ? t.servers : 'single', { placeholder: 'single, infinite or k' }),
    ];
    const imm = [
      field(form, 'weight', 'weight', t.kind === 'immediate' ? t.weight : 1),
      field(form, 'priority', 'priority', t.kind === 'immediate' ? t.priority : 1),
    ];
    const shown = () => {
      for (const f of exp) f.parentNode.classList.toggle('hidden', kind.value !== 'exponential');
      for (const f of imm) f.parentNode.classList.toggle('hidden', kind.value !== 'immediate');
    };
    kind.addEventListener('change', shown);
    shown();
  }
  const apply = document.createElement('button');
  apply.id = 'props-apply';
  apply.type = 'submit';
  apply.textContent = 'apply';
  const del = document.createElement('button');
  del.type = 'button';
  del.textContent = 'delete';
  del.addEventListener('click', deleteSelection);
  const row = document.createElement('div');
  row.className = 'props-buttons';
  row.append(apply, del);
  form.appendChild(row);
  arcRows($('props-arcs'), i);
}

// The selected node's arcs (outside the form: their fields are not the node's): kind
// (input ⇄ inhibitor), multiplicity, delete.
function arcRows(box, i) {
  const list = (ed.sel.isPlace ? arcsOfPlace : arcsOfTransition)[i];
  if (!list.length) return;
  const h = document.createElement('h4');
  h.textContent = 'arcs';
  box.appendChild(h);
  for (const k of list) {
    const a = net.arcs[k];
    const p = net.places[a.place].name;
    const t = net.transitions[a.transition].name;
    const row = document.createElement('div');
    row.className = 'arc-row';
    row.dataset.arc = a.kind + ' ' + p + ' ' + t;
    const text = document.createElement('span');
    text.className = 'mono';
    text.textContent = a.kind === 'output' ? t + ' → ' + p : a.kind === 'inhibitor' ? p + ' ⊸ ' + t : p + ' → ' + t;
    row.appendChild(text);
    const base = { place: p, transition: t, kind: a.kind };
    if (a.kind !== 'output') {
      const kind = document.createElement('select');
      kind.name = 'kind';
      for (const v of ['input', 'inhibitor']) {
        const o = document.createElement('option');
        o.value = v;
        o.textContent = v === 'input' ? 'normal' : 'inhibitor';
        kind.appendChild(o);
      }
      kind.value = a.kind;
      kind.addEventListener('change', () => editOp(Object.assign({ op: 'set_arc', new_kind: kind.value }, base)));
      row.appendChild(kind);
    }
    const w = document.createElement('input');
    w.name = 'weight';
    w.type = 'text';
    w.size = 3;
    w.value = String(a.weight);
    w.title = 'multiplicity';
    w.addEventListener('change', () => editOp(Object.assign({ op: 'set_arc', weight: w.value }, base)));
    row.appendChild(w);
    const del = document.createElement('button');
    del.type = 'button';
    del.textContent = '✕';
    del.title = 'delete this arc';
    del.addEventListener('click', () => editOp(Object.assign({ op: 'delete_arc' }, base)));
    row.appendChild(del);
    box.appendChild(row);
  }
}

// Sends the fields that changed as one edit of the selected node.
function applyProps(ev) {
  ev.preventDefault();
  if (!ed.sel) return;
  const form = $('props');
  const op = ed.sel.isPlace ? { op: 'set_place', place: ed.sel.name } : { op: 'set_transition', transition: ed.sel.name };
  const changed = (name) => {
    const f = form.elements.namedItem(name);
    return f && f.value !== f.dataset.was ? f.value : undefined;
  };
  const value = (name) => form.elements.namedItem(name).value;
  const newName = changed('name');
  if (newName !== undefined) op.name = newName;
  if (ed.sel.isPlace) {
    if (changed('tokens') !== undefined) op.tokens = value('tokens');
    if (changed('capacity') !== undefined) op.capacity = value('capacity').trim() === '' ? null : value('capacity');
  } else {
    const kind = value('kind');
    const kindChanged = changed('kind') !== undefined;
    if (kindChanged) op.kind = kind;
    const params = kind === 'exponential' ? ['rate', 'servers'] : ['weight', 'priority'];
    for (const p of params) if (kindChanged || changed(p) !== undefined) op[p] = value(p);
  }
  if (Object.keys(op).length === 2) {
    editMsg('nothing changed');
    return;
  }
  const name = newName !== undefined ? newName : ed.sel.name;
  editOp(op).then((ok) => {
    if (ok) select({ isPlace: ed.sel.isPlace, name });
  });
}

function deleteSelection() {
  if (!ed.on || !ed.sel) return;
  const ref = ed.sel;
  editOp({ op: 'delete', node: refJson(ref) }).then((ok) => {
    if (ok) select(null);
  });
}

// ---- mode, tools, keys -------------------------------------------------------------------

function setTool(tool) {
  ed.tool = tool;
  ed.arcFrom = null;
  for (const b of document.querySelectorAll('[data-tool]')) b.setAttribute('aria-pressed', String(b.dataset.tool === tool));
  $('canvas').dataset.tool = tool;
  showSelection();
}

// Nodes dragged before the editor was on are where the page drew them, not yet where the
// server has them: one `move` makes them so (an edit that can be undone).
async function keepDragged() {
  try {
    const served = await api('GET', '/api/net');
    const moved = { places: {}, transitions: {} };
    let n = 0;
    for (const [key, list] of [['places', net.places], ['transitions', net.transitions]]) {
      list.forEach((node, i) => {
        const s = served[key][i];
        if (!s || s.name !== node.name) return;
        const at = [node.x / scale, node.y / scale];
        if (Math.abs(at[0] - s.x) > 1e-6 || Math.abs(at[1] - s.y) > 1e-6) {
          moved[key][node.name] = at;
          n += 1;
        }
      });
    }
    if (n) await editOp(Object.assign({ op: 'move' }, moved));
  } catch (e) {
    offline(e);
  }
}

function setEditing(on) {
  if (on && !ed.editable) return;
  if (on && !ed.on) keepDragged();
  ed.on = on;
  $('edit-mode').setAttribute('aria-pressed', String(on));
  $('edit-bar').classList.toggle('hidden', !on);
  $('canvas').classList.toggle('editing', on);
  if (!on) {
    ed.sel = null;
    ed.arcFrom = null;
  }
  setTool(on ? ed.tool : 'select');
  editMsg('');
  refit();
}

// Called by app.js before the shortcuts are listed: the editor's keys join them.
function setupEdit() {
  const whenEditing = (fn) => () => {
    if (ed.on) fn();
  };
  KEYS.push(['e', 'edit the net: on / off', () => setEditing(!ed.on)]);
  for (const [tool, key, what] of TOOLS) KEYS.push([key, 'edit: ' + what, whenEditing(() => setTool(tool))]);
  KEYS.push(['Delete', 'edit: delete the selected node', whenEditing(deleteSelection)]);
  KEYS.push(['Ctrl-Z', 'undo the last edit', undo]);
  KEYS.push(['Ctrl-Shift-Z', 'redo it (also Ctrl-Y)', redo]);
  document.addEventListener('keydown', (ev) => {
    if (!(ev.ctrlKey || ev.metaKey) || ev.altKey) return;
    const t = ev.target;
    if (t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.tagName === 'SELECT')) return;
    const k = ev.key.toLowerCase();
    if (k === 'z' && !ev.shiftKey) undo();
    else if ((k === 'z' && ev.shiftKey) || k === 'y') redo();
    else return;
    ev.preventDefault();
  });
  document.addEventListener('keydown', (ev) => {
    if (ev.key === 'Escape' && ed.on && ed.arcFrom) {
      ed.arcFrom = null;
      showSelection();
      editMsg('');
    }
  });
  $('edit-mode').addEventListener('click', () => setEditing(!ed.on));
  for (const b of document.querySelectorAll('[data-tool]')) b.addEventListener('click', () => setTool(b.dataset.tool));
  $('undo').addEventListener('click', undo);
  $('redo').addEventListener('click', redo);
  $('edit-delete').addEventListener('click', deleteSelection);
  $('edit-save').addEventListener('click', save);
  $('export-pnpro').addEventListener('click', () => exportAs('pnpro'));
  $('export-pipe').addEventListener('click', () => exportAs('pipe'));
  $('props').addEventListener('submit', applyProps);
}

// After the net is drawn (the token game only: a live run or a replay is not edited).
async function initEdit() {
  try {
    const s = await api('GET', '/api/edit');
    ed.editable = s.editable;
    ed.saveTo = s.save_to;
    $('edit-mode').classList.toggle('hidden', !s.editable);
    $('edit-save').classList.toggle('hidden', !s.save_to);
    if (s.save_to) $('edit-save').title = 'write the net to ' + s.save_to;
    showHistory(s.history);
  } catch (e) {
    status(e.message);
  }
}
