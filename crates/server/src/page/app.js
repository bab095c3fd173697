// indentify serve: the page's script (compiled into the binary; no third-party code).
// It uses only the documented HTTP API (docs/web.md) and draws its curves as SVG.
'use strict';

const $ = (sel) => document.querySelector(sel);
const state = { records: [], record: null, test: 1, laws: {}, run: null, source: null, selected: new Set(), joint: new Map(), indent: null, mapParam: null };

// ---- API ---------------------------------------------------------------------------------
async function api(path, opts = {}) {
  const headers = Object.assign({ 'X-Indentify': '1' }, opts.headers || {});
  const r = await fetch(path, Object.assign({}, opts, { headers, credentials: 'same-origin' }));
  const ct = r.headers.get('content-type') || '';
  const body = ct.includes('json') ? await r.json() : await r.text();
  if (!r.ok) {
    const e = new Error(typeof body === 'object' ? (body.messages || [body.error]).join('\n  ') : String(body));
    e.status = r.status;
    throw e;
  }
  return body;
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v; else if (k === 'text') e.textContent = v; else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

const sig = (v, n = 4) => (v === null || v === undefined || !isFinite(v)) ? '–' : Number(v).toPrecision(n).replace(/\.?0+e/, 'e').replace(/(\.\d*?)0+$/, '$1').replace(/\.$/, '');
const bound = (v) => (v === null || v === undefined) ? '∞' : (isFinite(v) ? sig(v, 3) : (v > 0 ? '∞' : '−∞'));

// ---- SVG plots -----------------------------------------------------------------------------
const SVGNS = 'http://www.w3.org/2000/svg';
function svg(tag, attrs = {}) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  return e;
}

function ticks(lo, hi, n = 5) {
  if (!(hi > lo)) { hi = lo + 1; }
  const step0 = (hi - lo) / n;
  const mag = Math.pow(10, Math.floor(Math.log10(step0)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= step0) || step0;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
  return out;
}

// series: [{x: [], y: [], label, color, dash, dots}]
function plot(container, series, opts = {}) {
  const W = 560, H = 300, L = 62, R = 12, T = 22, B = 40;
  const xs = series.flatMap((s) => s.x).filter(isFinite);
  let ys = series.flatMap((s) => s.y).filter(isFinite);
  if (opts.logy) ys = ys.filter((v) => v > 0).map(Math.log10);
  container.replaceChildren();
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, role: 'img' });
  container.append(root);
  if (!xs.length || !ys.length) { const t = svg('text', { x: W / 2, y: H / 2, 'text-anchor': 'middle' }); t.textContent = 'no data'; root.append(t); return; }
  let [x0, x1] = [Math.min(...xs), Math.max(...xs)];
  let [y0, y1] = [Math.min(...ys), Math.max(...ys)];
  if (x1 === x0) x1 = x0 + 1;
  if (y1 === y0) { y0 -= 1; y1 += 1; }
  const pad = (y1 - y0) * 0.05; y0 -= pad; y1 += pad;
  const px = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const py = (y) => H - B - (y - y0) / (y1 - y0) * (H - T - B);
  for (const t of ticks(x0, x1)) {
    root.append(svg('line', { x1: px(t), x2: px(t), y1: T, y2: H - B, class: 'gridline' }));
    const s = svg('text', { x: px(t), y: H - B + 14, 'text-anchor': 'middle' }); s.textContent = sig(t * (opts.xscale || 1), 3); root.append(s);
  }
  for (const t of ticks(y0, y1)) {
    root.append(svg('line', { x1: L, x2: W - R, y1: py(t), y2: py(t), class: 'gridline' }));
    const s = svg('text', { x: L - 5, y: py(t) + 4, 'text-anchor': 'end' });
    s.textContent = opts.logy ? sig(Math.pow(10, t), 2) : sig(t * (opts.yscale || 1), 3); root.append(s);
  }
  root.append(svg('rect', { x: L, y: T, width: W - L - R, height: H - T - B, class: 'axis' }));
  const xl = svg('text', { x: (L + W - R) / 2, y: H - 6, 'text-anchor': 'middle' }); xl.textContent = opts.xlabel || ''; root.append(xl);
  const yl = svg('text', { x: 12, y: (T + H - B) / 2, 'text-anchor': 'middle', transform: `rotate(-90 12 ${(T + H - B) / 2})` }); yl.textContent = opts.ylabel || ''; root.append(yl);
  if (opts.zero && y0 < 0 && y1 > 0) root.append(svg('line', { x1: L, x2: W - R, y1: py(0), y2: py(0), stroke: '#999', 'stroke-dasharray': '3 3' }));
  let lx = L + 8;
  for (const s of series) {
    const pts = [];
    for (let i = 0; i < s.x.length; i++) {
      let y = s.y[i];
      if (opts.logy) y = y > 0 ? Math.log10(y) : NaN;
      if (isFinite(s.x[i]) && isFinite(y)) pts.push([px(s.x[i]), py(y)]);
    }
    if (s.dots) {
      for (const [a, b] of pts) root.append(svg('circle', { cx: a, cy: b, r: 2.2, fill: s.color }));
    } else if (pts.length) {
      root.append(svg('polyline', { points: pts.map((p) => p.join(',')).join(' '), fill: 'none', stroke: s.color, 'stroke-width': 1.6, 'stroke-dasharray': s.dash || '' }));
    }
    if (s.label) {
      root.append(svg('rect', { x: lx, y: 7, width: 12, height: 4, fill: s.color }));
      const t = svg('text', { x: lx + 16, y: 13 }); t.textContent = s.label; root.append(t);
      lx += 24 + s.label.length * 6.2;
    }
  }
}

function parseCsv(text) {
  const lines = text.trim().split(/\r?\n/).filter((l) => l && !l.startsWith('#'));
  const head = lines.shift().split(',').map((s) => s.trim());
  const cols = Object.fromEntries(head.map((h) => [h, []]));
  for (const l of lines) l.split(',').forEach((v, i) => cols[head[i]] && cols[head[i]].push(parseFloat(v)));
  return cols;
}

// ---- records -------------------------------------------------------------------------------
async function loadRecords(select) {
  const { records } = await api('/api/records');
  state.records = records;
  const sel = $('#record-select');
  const keep = select || sel.value;
  sel.replaceChildren(el('option', { value: '', text: 'none: a reference problem (depth history)' }));
  for (const r of records) sel.append(el('option', { value: r.id, text: `${r.name} (${r.tests.length} test${r.tests.length === 1 ? '' : 's'}, ${r.id})` }));
  sel.value = keep || '';
}

async function upload(files) {
  const status = $('#upload-status');
  for (const f of files) {
    status.textContent = `uploading ${f.name} (${(f.size / 1e6).toFixed(2)} MB)…`;
    status.className = 'muted';
    try {
      const info = await api(`/api/records?name=${encodeURIComponent(f.name)}`, { method: 'POST', body: f });
      status.textContent = `${info.name}: ${info.format}, ${info.tests.length} test(s), id ${info.id}`;
      await loadRecords(info.id);
      await showRecord(info.id);
    } catch (e) {
      status.textContent = e.message;
      status.className = 'error';
    }
  }
}

async function showRecord(id) {
  state.record = null;
  $('#tests tbody').replaceChildren();
  $('#record-plot').replaceChildren();
  $('#prep').replaceChildren();
  $('#record-info').textContent = '';
  if (!id) { await loadTemplate(); return; }
  const r = await api(`/api/records/${id}`);
  state.record = r;
  state.test = 1;
  $('#record-info').textContent = `${r.name}: ${r.format}, ${r.bytes} bytes`;
  renderTests();
  await loadTemplate();
}

function renderTests() {
  const r = state.record;
  const body = $('#tests tbody');
  body.replaceChildren();
  for (const t of r.tests) {
    const radio = el('input', { type: 'radio', name: 'test', value: t.index });
    radio.checked = t.index === state.test;
    const key = `${r.id}:${t.index}`;
    const pick = state.joint.get(key) || { on: false, weight: '' };
    const jbox = el('input', { type: 'checkbox', class: 'joint', 'data-test': t.index });
    jbox.checked = pick.on;
    const wbox = el('input', { type: 'number', class: 'weight', step: 'any', min: '0', placeholder: 'default', 'data-test': t.index });
    wbox.value = pick.weight;
    for (const b of [jbox, wbox]) b.addEventListener('click', (ev) => ev.stopPropagation());
    const keep = () => { state.joint.set(key, { record: r.id, name: r.name, test: t.index, on: jbox.checked, weight: wbox.value }); jointNote(); };
    jbox.addEventListener('change', keep);
    wbox.addEventListener('input', keep);
    const tr = el('tr', { class: 'clickable' + (t.index === state.test ? ' selected' : '') },
      el('td', {}, radio), el('td', { text: t.index }), el('td', { text: t.name }), el('td', { class: 'num', text: t.points }),
      el('td', { class: 'num', text: sig(t.h_max * 1e6) }), el('td', { class: 'num', text: sig(t.f_max * 1e3) }), el('td', { text: t.tip || '–' }),
      el('td', {}, jbox), el('td', {}, wbox));
    tr.addEventListener('click', () => { state.test = t.index; renderTests(); loadTemplate(); });
    body.append(tr);
  }
  const t = r.tests[state.test - 1];
  plot($('#record-plot'), [{ x: t.curve.h, y: t.curve.f, label: t.name, color: '#1f6feb' }],
    { xlabel: 'depth h (nm)', ylabel: 'force F (mN)', xscale: 1e6, yscale: 1e3 });
  const prep = $('#prep');
  prep.replaceChildren();
  if (t.segments.length) {
    prep.append(el('p', { text: 'Segments (file ids): ' + t.segments.map((s) => `${s.id}: ${sig(s.t0, 3)}–${sig(s.t1, 3)} s (${s.samples})`).join('; ') }));
  }
  const ul = el('ul');
  for (const s of t.preprocessing) ul.append(el('li', { text: `${s.step}: ${s.description}` }));
  if (t.preprocessing_error) ul.append(el('li', { class: 'error', text: t.preprocessing_error }));
  prep.append(el('p', { text: 'Default preprocessing (zero point, segments, 60 resampled points):' }), ul);
  jointNote();
}

// the ticked tests of a joint fit, of this record and of others ticked before choosing
// this one (in the order ticked): [{record, test, weight?}] (two or more), or null
function jointPicks() {
  const picks = [...state.joint.values()].filter((p) => p.on)
    .map((p) => (parseFloat(p.weight) > 0 ? { record: p.record, test: p.test, weight: parseFloat(p.weight) } : { record: p.record, test: p.test }));
  return picks.length >= 2 ? picks : null;
}

function jointNote() {
  const p = jointPicks();
  const names = Object.fromEntries([...state.joint.values()].map((x) => [x.record, x.name]));
  $('#joint-note').textContent = p ? `Joint fit (identify, map) of ${p.map((x) => `${names[x.record]} test ${x.test}`).join(', ')}: one law for all, each test with its weight.` :
    'Tick two or more tests (of this record, or of several: choose another record and tick on) for a joint fit.';
}

// ---- configuration -------------------------------------------------------------------------
async function loadLaws() {
  const { laws } = await api('/api/laws');
  for (const l of laws) state.laws[l.name] = l;
  renderLaw();
}

function renderLaw() {
  const l = state.laws[$('#law').value];
  const body = $('#law-params tbody');
  body.replaceChildren();
  if (!l) return;
  for (const p of l.params) body.append(el('tr', {}, el('td', { text: p.name }), el('td', { text: p.unit }), el('td', { text: p.range }), el('td', { text: p.description })));
  const names = l.params.map((p) => p.name).filter((n) => n !== 'nu');
  for (const [sel, k] of [['#map-a', 0], ['#map-b', names.length - 1]]) {
    $(sel).replaceChildren(...names.map((n) => el('option', { value: n, text: n })));
    $(sel).value = names[k];
  }
}

function renderOptions() {
  const c = $('#command').value;
  for (const o of document.querySelectorAll('.opts')) o.hidden = o.dataset.for !== c;
}

async function loadTemplate() {
  const law = $('#command').value === 'design' ? 'design' : $('#law').value;
  const q = new URLSearchParams();
  if (state.record && law !== 'design') {
    q.set('record', state.record.id);
    if (state.record.tests.length > 1) q.set('test', state.test);
    if ($('#tip').value) q.set('tip', $('#tip').value);
  }
  try {
    $('#config').value = await api(`/api/templates/${law}?${q}`);
    $('#submit-error').textContent = '';
  } catch (e) { $('#submit-error').textContent = e.message; }
}

async function submit() {
  const err = $('#submit-error');
  err.textContent = '';
  // the badge must not show the previous run's end while this one is being submitted
  const badge = $('#run-status');
  badge.textContent = 'submitting';
  badge.className = 'badge queued';
  const body = { command: $('#command').value, sets: $('#sets').value.split('\n').map((s) => s.trim()).filter(Boolean) };
  const cfg = $('#config').value;
  if (cfg.trim()) body.config = cfg;
  const maxIter = parseInt($('#max-iter').value, 10);
  if (maxIter > 0 && body.command === 'identify') body.max_iter = maxIter;
  if ($('#no-refine').checked && body.command === 'identify') body.no_refine = true;
  if ($('#profiles').checked && body.command === 'identify') body.profiles = true;
  const starts = parseInt($('#starts').value, 10);
  if (starts > 0 && body.command === 'identify') {
    body.starts = starts;
    const seed = parseInt($('#seed').value, 10);
    if (seed >= 0) body.seed = seed;
  }
  const joint = jointPicks();
  if (joint && ['identify', 'map'].includes(body.command)) {
    body.tests = joint;
    // the one-test configuration in the editor is the first pick's record's template
    body.record = joint.some((p) => state.record && p.record === state.record.id) ? state.record.id : joint[0].record;
  }
  if (body.command === 'map') {
    Object.assign(body, { pair: [$('#map-a').value, $('#map-b').value], grid: parseInt($('#map-grid').value, 10) || 7, through: $('#map-through').value });
  }
  if (body.command === 'batch') {
    if (state.record) body.record = state.record.id;
    if ($('#manifest').value.trim()) body.manifest = $('#manifest').value;
  }
  if (body.command === 'calibrate') {
    for (const k of ['config', 'sets']) delete body[k];
    if (state.record) body.record = state.record.id;
    if (!$('#cal-all').checked && state.record) body.test = state.test;
    body.modulus = parseFloat($('#cal-modulus').value);
    body.nu = parseFloat($('#cal-nu').value);
    const terms = parseInt($('#cal-terms').value, 10);
    if (terms > 0) body.terms = terms;
  }
  if (body.command === 'analyze') {
    for (const k of ['config', 'sets']) delete body[k];
    if (state.record) body.record = state.record.id;
    if (!$('#an-all').checked && state.record) body.test = state.test;
    body.tip = $('#an-tip').value.trim() || 'berkovich';
    body.nu = parseFloat($('#an-nu').value);
  }
  try {
    const { id } = await api('/api/runs', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
    openRun(id);
    loadRuns();
  } catch (e) {
    err.textContent = e.message;
    badge.textContent = 'refused';
    badge.className = 'badge failed';
  }
}

// ---- a run ---------------------------------------------------------------------------------
function openRun(id) {
  if (state.source) state.source.close();
  state.run = id;
  location.hash = `run=${id}`;
  $('#run-id').textContent = id;
  $('#run-error').textContent = '';
  $('#run-message').textContent = '';
  clearResult();
  const es = new EventSource(`/api/runs/${id}/events`);
  state.source = es;
  es.addEventListener('status', (ev) => {
    const m = JSON.parse(ev.data);
    renderProgress(m);
    // how late an iteration reaches the page: an upper bound, as the run's clock starts
    // after `started` (same machine, same wall clock); read by the browser test
    const p = m.progress || {};
    if (m.status === 'running' && typeof p.cost === 'number' && m.started) {
      (window.progressLags = window.progressLags || []).push(Date.now() / 1000 - (m.started + p.elapsed));
    }
    if (['done', 'failed', 'cancelled'].includes(m.status)) {
      es.close();
      if (state.source === es) state.source = null;
      loadResult(id);
      loadRuns();
    }
  });
}

function fmtTime(s) {
  if (s === null || s === undefined || !isFinite(s)) return '–';
  if (s < 60) return `${s.toFixed(1)} s`;
  return `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`;
}

function renderProgress(m) {
  const badge = $('#run-status');
  badge.textContent = m.status;
  badge.className = `badge ${m.status}`;
  const p = m.progress || {};
  $('#cancel').disabled = !(m.status === 'queued' || m.status === 'running');
  let frac = 0;
  let text = `${m.command}: ${p.stage || m.status}`;
  if (m.command === 'batch' && p.max_iterations) {
    frac = Math.min(1, p.iteration / p.max_iterations);
    text += ` — ${p.iteration} of ${p.max_iterations} indents finished, ${fmtTime((Date.now() / 1000) - (m.started || Date.now() / 1000))}`;
  } else if (p.max_iterations) {
    frac = Math.min(1, p.iteration / p.max_iterations);
    text += ` — iteration ${p.iteration} of at most ${p.max_iterations}`;
    if (p.cost !== null && p.cost !== undefined) text += `, J = ${sig(p.cost, 5)} N²`;
    text += `, ${p.forward_solves} forward / ${p.adjoint_solves} adjoint solves, ${fmtTime(p.elapsed)}`;
    if (m.status === 'running' && p.eta !== null && p.eta !== undefined) text += `, at most ${fmtTime(p.eta)} left`;
  }
  if (m.status !== 'running' && m.status !== 'queued') frac = 1;
  $('#progress-bar').style.width = `${(100 * frac).toFixed(1)}%`;
  $('#progress-text').textContent = text;
  const body = $('#progress-params tbody');
  body.replaceChildren();
  (p.names || []).forEach((n, k) => {
    if (p.free && p.free[k] && p.params && p.params.length) body.append(el('tr', {}, el('td', { text: n }), el('td', { class: 'num', text: sig(p.params[k], 6) })));
  });
  if (p.costs && p.costs.length > 1) {
    plot($('#cost-plot'), [{ x: p.costs.map((_, i) => i), y: p.costs, color: '#1f6feb', label: 'J (N²)' }], { logy: true, xlabel: 'iteration', ylabel: 'J' });
  }
  if (p.indents && p.indents.length) drawBatch(m);
  if (m.message) $('#run-message').textContent = m.message;
  if (m.error) $('#run-error').textContent = `${m.error.kind} error: ${m.error.messages.join('\n  ')}`;
}

function clearResult() {
  for (const s of ['#param-table thead', '#param-table tbody', '#identifiability', '#fit-plot', '#residual-plot', '#figures', '#downloads',
    '#analysis', '#design', '#batch-map', '#indent-view', '#costmap', '#profile-plots', '#multistart', '#joint-tests', '#joint-plots', '#calibration']) $(s).replaceChildren();
  $('#result-summary').textContent = '';
}

async function loadResult(id) {
  const run = await api(`/api/runs/${id}`);
  renderProgress(run);
  clearResult();
  const res = run.result;
  const files = run.files || [];
  const has = (n) => files.some((f) => f.name === n);
  if (run.command === 'identify' && res) renderIdentify(run, res);
  if (run.command === 'simulate' && res) renderSimulate(res);
  if (run.command === 'analyze' && res) renderAnalysis(res);
  if (run.command === 'calibrate' && res) renderCalibration(id, res);
  if (run.command === 'identify' && res && res.tests) renderJointTests(res.tests);
  if (run.command === 'design' && res) renderDesign(res);
  if (run.command === 'map' && res) renderCostMap(res);
  if (run.command === 'batch') { drawBatch(run); renderBatchSummary(run); }
  if (run.command === 'identify' && res && res.profiles) renderProfiles(res.profiles);
  if (run.command === 'identify' && res && res.multistart) renderMultistart(res.multistart);
  if (has('fit.csv')) {
    const fit = parseCsv(await api(`/api/runs/${id}/files/fit.csv`));
    if (fit.test) renderJointFits(fit, res);
    plot($('#fit-plot'), [
      { x: fit.h, y: fit.F_data, label: 'data', color: '#222', dots: true },
      { x: fit.h, y: fit.F_start, label: 'start', color: '#999', dash: '4 3' },
      { x: fit.h, y: fit.F_final, label: 'fit', color: '#d62728' },
    ], { xlabel: 'depth h (µm)', ylabel: 'force F (mN)', xscale: 1e3, yscale: 1e3 });
    plot($('#residual-plot'), [{ x: fit.t, y: fit.F_final.map((v, i) => v - fit.F_data[i]), label: 'F_fit − F_data', color: '#d62728', dots: true }],
      { xlabel: 'time t (s)', ylabel: 'residual (mN)', yscale: 1e3, zero: true });
  } else if (has('curve.csv')) {
    const c = parseCsv(await api(`/api/runs/${id}/files/curve.csv`));
    plot($('#fit-plot'), [{ x: c.h, y: c.F, label: 'simulated', color: '#d62728' }], { xlabel: 'depth h (µm)', ylabel: 'force F (mN)', xscale: 1e3, yscale: 1e3 });
  }
  const figs = $('#figures');
  for (const f of files.filter((f) => f.name.endsWith('.svg') && !f.name.startsWith('indents/'))) {
    figs.append(el('figure', {}, el('img', { src: `/api/runs/${id}/files/${f.name}`, alt: f.name, loading: 'lazy' }), el('figcaption', { text: f.name })));
  }
  const dl = $('#downloads');
  for (const f of files.filter((f) => !f.name.startsWith('indents/'))) {
    dl.append(el('li', {}, el('a', { href: `/api/runs/${id}/files/${f.name}`, download: f.name.replace('/', '_'), text: f.name }), ` (${(f.bytes / 1024).toFixed(1)} kB)`));
  }
}

function renderIdentify(run, res) {
  const q = res.fit_quality;
  $('#result-summary').textContent = `${res.law}, ${res.method}: ${res.converged ? 'converged' : 'NOT converged'} (${res.stop_reason}); ` +
    `J = ${sig(res.J, 5)} N² (start ${sig(res.J_start, 4)}), ${res.iterations} iterations, ${sig(res.seconds, 3)} s` +
    (q ? `; R² = ${sig(q.r2, 6)}, RMS residual ${sig(100 * q.rms_rel, 3)}% of F_max` : '');
  const id = res.identifiability;
  const und = new Set(id ? id.undetermined : []);
  const head = $('#param-table thead');
  const cols = ['parameter', 'unit', 'start', 'final', 'σ (std. dev.)', 'σ / value', 'bounds'];
  const hasTruth = res.parameters.some((p) => p.truth !== undefined);
  if (hasTruth) cols.push('truth');
  head.append(el('tr', {}, ...cols.map((c) => el('th', { text: c }))));
  const body = $('#param-table tbody');
  for (const p of res.parameters) {
    let sd = '', rel = '';
    if (!p.free) { sd = 'held'; }
    else if (und.has(p.name)) { sd = 'undetermined'; }
    else if (id) { sd = sig(id.std_dev[p.name], 3); rel = sig(id.rel_std_dev[p.name], 2); }
    const final = sig(p.value, 7) + (p.bound_hit ? ` (at ${p.bound_hit} bound)` : '');
    const cells = [p.name, p.unit, sig(p.start, 6), final, sd, rel, p.free ? `[${bound(p.lower)}, ${bound(p.upper)}]` : ''];
    if (hasTruth) cells.push(p.truth !== undefined ? sig(p.truth, 6) : '');
    const tr = el('tr', { 'data-param': p.name }, ...cells.map((c, i) => el('td', { class: (i >= 2 ? 'num' : '') + (c === 'undetermined' ? ' undetermined' : ''), text: c })));
    body.append(tr);
  }
  const box = $('#identifiability');
  if (id) {
    box.append(el('p', { text: `Singular values of the scaled sensitivity matrix: ${id.singular_values.map((v) => sig(v, 3)).join(', ')}; condition number ${id.condition}.` }));
    if (id.weakest_direction) box.append(el('p', { text: `Weakest direction: ${id.weakest_direction}` }));
    if (id.undetermined.length) box.append(el('p', { class: 'undetermined', text: `Undetermined by these data: ${id.undetermined.map((n) => `${n} (${id.undetermined_reasons[n] || ''})`).join('; ')}` }));
    if (id.names.length > 1) {
      const t = el('table', { class: 'grid' });
      t.append(el('tr', {}, el('th', { text: 'correlation' }), ...id.names.map((n) => el('th', { text: n }))));
      id.names.forEach((a, i) => t.append(el('tr', {}, el('th', { text: a }), ...id.names.map((_, j) => el('td', { class: 'num', text: sig(id.correlation[i][j], 3) })))));
      box.append(t);
    }
  }
  for (const w of res.warnings || []) box.append(el('p', { class: 'error', text: `warning: ${w}` }));
}

function renderSimulate(res) {
  $('#result-summary').textContent = `${res.law} (${(res.params || []).join(', ')}), ${res.punch}; ${res.mesh}; ${res.steps} steps, ` +
    `${res.newton_iterations} Newton iterations; max force ${sig(res.max_force * 1e3, 5)} mN at h = ${sig(res.at_depth * 1e3, 4)} µm; ${sig(res.seconds, 3)} s` +
    (res.failure ? `; stopped: ${res.failure}` : '');
}

// ---- analyze, design, cost map, profiles, batch ------------------------------------------------
function table(id, head, rows) {
  const t = el('table', { class: 'grid', id });
  t.append(el('tr', {}, ...head.map((h) => el('th', { text: h }))));
  for (const r of rows) t.append(el('tr', {}, ...r.map((c, i) => el('td', { class: i ? 'num' : '', text: c }))));
  return t;
}

function renderAnalysis(res) {
  // analysis.json: N, mm, N/mm, MPa
  $('#result-summary').textContent = `Oliver-Pharr analysis of ${res.file} (${res.format}), ν = ${res.nu}; fit range ${sig(100 * res.fit_range.lower, 3)}–${sig(100 * res.fit_range.upper, 3)}% of F_max (${res.fit_range_source})`;
  const rows = res.tests.map((t) => [t.test || `test ${t.index}`, sig(t.E / 1e3, 4), sig(t.H / 1e3, 4), sig(t.Er / 1e3, 4), sig(t.S / 1e3, 4), sig(t.hc * 1e6, 4), sig(t.hmax * 1e6, 4), sig(t.Fmax * 1e3, 4), t.error || '']);
  $('#analysis').append(table('analysis-table', ['test', 'E (GPa)', 'H (GPa)', 'E_r (GPa)', 'S (mN/nm)', 'h_c (nm)', 'h_max (nm)', 'F_max (mN)', 'error'], rows));
}

// a joint fit: each test's share of J and fit quality, and its own fit plot (fit.csv's
// `test` column)
function renderJointTests(tests) {
  const rows = tests.map((t, k) => [`${k + 1}: ${t.name}`, t.data, sig(t.weight, 4) + (t.default_weight ? ' (default)' : ''), sig(t.wJ, 4), t.n,
    t.fit_quality ? sig(t.fit_quality.r2, 6) : '', t.fit_quality ? sig(100 * t.fit_quality.rms_rel, 3) + '%' : '']);
  $('#joint-tests').append(el('h3', { text: 'Tests of the joint fit' }),
    table('joint-table', ['test', 'data', 'weight', 'w·J', 'points', 'R²', 'RMS / F_max'], rows));
}

function renderJointFits(fit, res) {
  const box = $('#joint-plots');
  const ks = [...new Set(fit.test)];
  for (const k of ks) {
    const idx = fit.test.map((v, i) => (v === k ? i : -1)).filter((i) => i >= 0);
    const col = (c) => idx.map((i) => fit[c][i]);
    const d = el('div', { class: 'plot joint-fit' });
    box.append(d);
    const name = res && res.tests && res.tests[k - 1] ? res.tests[k - 1].name : `test ${k}`;
    plot(d, [{ x: col('h'), y: col('F_data'), label: `data, ${name}`, color: '#222', dots: true }, { x: col('h'), y: col('F_final'), label: 'fit', color: '#d62728' }],
      { xlabel: 'depth h (µm)', ylabel: 'force F (mN)', xscale: 1e3, yscale: 1e3 });
  }
}

// calibrate: the frame compliance, the area function's coefficients, A(h_c) of every
// unloading against the fitted ISO function (C0 h² + C1 h + C2 h^½ + ...), and *Save as tip*
function renderCalibration(id, res) {
  const a = res.area;
  $('#result-summary').textContent = `Tip ${res.tip.name}: frame compliance ${sig(res.compliance_used * 1e3, 4)} nm/mN` +
    (res.compliance ? ` (fitted on ${res.compliance.n} unloadings, R² ${sig(res.compliance.r2, 4)})` : ' (given)') +
    `; E_r of the reference ${sig(res.er / 1e3, 4)} GPa; ${a.n} points, RMS area misfit ${sig(100 * a.rms_rel, 3)}%`;
  const box = $('#calibration');
  const rows = a.coefficients.map((c, k) => [`C${k}`, sig(c, 6), k === 0 ? '1' : `mm^${2 - 2 ** (1 - k)}`]);
  box.append(table('calibration-table', ['coefficient', 'value', 'unit'], rows));
  const save = el('button', { type: 'button', id: 'save-tip', text: 'Save as tip (use it in later runs)' });
  const note = el('span', { id: 'save-tip-note', class: 'muted' });
  save.addEventListener('click', async () => {
    try {
      const text = await api(`/api/runs/${id}/files/tip.ron`);
      const t = await api('/api/tips?name=tip.ron', { method: 'POST', body: text });
      $('#config').value = replacePunch($('#config').value, t.punch);
      note.textContent = `stored as tip ${t.id}: punch: ${t.punch} (put into the configuration)`;
    } catch (e) { note.textContent = e.message; note.className = 'error'; }
  });
  box.append(el('div', { class: 'row' }, save, note));
  const d = el('div', { class: 'plot', id: 'calibration-plot' });
  box.append(d);
  const hc = a.points.map((p) => p[0]);
  const lo = Math.min(...hc), hi = Math.max(...hc);
  const xs = Array.from({ length: 60 }, (_, i) => lo + ((hi - lo) * i) / 59);
  const area = (h) => a.coefficients.reduce((s, c, k) => s + c * h ** (2 ** (1 - k)), 0);
  plot(d, [{ x: hc, y: a.points.map((p) => p[1]), label: 'A(h_c) of each unloading', color: '#222', dots: true },
    { x: xs, y: xs.map(area), label: 'fitted area function', color: '#d62728' }],
  { xlabel: 'contact depth h_c (nm)', ylabel: 'area A (µm²)', xscale: 1e6, yscale: 1e6 });
}

function renderDesign(res) {
  $('#result-summary').textContent = `${res.candidates.length} candidate protocols at the nominal parameters, noise ${res.noise}; ranked by the information (log det), with each candidate's largest relative σ.`;
  const names = res.names;
  const rows = res.rank_d.map((k, r) => {
    const c = res.candidates[k];
    const rel = names.map((n) => { const p = c.params.find((q) => q.name === n); return p ? sig(100 * p.rel_std_dev, 3) + '%' : ''; });
    return [String(r + 1), c.name, String(c.n_data), sig(Number(c.log_det), 4), `${c.worst[0]} ${sig(100 * c.worst[1], 3)}%`, ...rel,
      c.undetermined.length ? c.undetermined.map((u) => u[0]).join(', ') : ''];
  });
  const t = table('design-table', ['rank', 'candidate', 'points', 'log det', 'worst σ/value', ...names.map((n) => `σ/${n}`), 'undetermined'], rows);
  for (const tr of [...t.querySelectorAll('tr')].slice(1)) tr.children[1].className = '';
  $('#design').append(t);
}

function colour(v) {
  // 0..1 -> a blue-yellow ramp (perceptually ordered)
  const t = Math.max(0, Math.min(1, v));
  const a = [68, 1, 84], b = [33, 145, 140], c = [253, 231, 37];
  const m = t < 0.5 ? [a, b, t * 2] : [b, c, (t - 0.5) * 2];
  return `rgb(${m[0].map((x, i) => Math.round(x + (m[1][i] - x) * m[2])).join(',')})`;
}

function renderCostMap(res) {
  const [nx, ny] = [res.x.length, res.y.length];
  const W = 560, H = 420, L = 70, R = 80, T = 20, B = 44;
  const J = res.J.map((v) => (v === null ? NaN : v));
  const fin = J.filter((v) => isFinite(v) && v > 0);
  const lo = Math.log10(Math.min(...fin)), hi = Math.log10(Math.max(...fin));
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, role: 'img', id: 'costmap-svg' });
  const cw = (W - L - R) / nx, ch = (H - T - B) / ny;
  for (let j = 0; j < ny; j++) for (let i = 0; i < nx; i++) {
    const v = J[j * nx + i];
    const r = svg('rect', { x: L + i * cw, y: H - B - (j + 1) * ch, width: cw + 0.5, height: ch + 0.5, fill: !isFinite(v) ? '#ccc' : colour(v > 0 ? (Math.log10(v) - lo) / (hi - lo || 1) : 0) });
    const tt = svg('title'); tt.textContent = `${res.names[0]} = ${sig(res.x[i], 4)}, ${res.names[1]} = ${sig(res.y[j], 4)}: J = ${sig(v, 4)} N²`; r.append(tt);
    root.append(r);
  }
  const lab = (x, y, text, anchor = 'middle', rot) => { const t = svg('text', { x, y, 'text-anchor': anchor }); if (rot) t.setAttribute('transform', `rotate(-90 ${x} ${y})`); t.textContent = text; root.append(t); };
  for (const i of [0, Math.floor(nx / 2), nx - 1]) lab(L + (i + 0.5) * cw, H - B + 14, sig(res.x[i], 3));
  for (const j of [0, Math.floor(ny / 2), ny - 1]) lab(L - 4, H - B - (j + 0.5) * ch + 4, sig(res.y[j], 3), 'end');
  lab((L + W - R) / 2, H - 8, `${res.names[0]} (${res.units[0]})`);
  lab(14, (T + H - B) / 2, `${res.names[1]} (${res.units[1]})`, 'middle', true);
  const [cx, cy] = res.centre_pair;
  const px = (x) => L + (res.x.findIndex((v) => v >= cx) + 0.5) * cw;
  root.append(svg('circle', { cx: px(cx), cy: H - B - (res.y.findIndex((v) => v >= cy) + 0.5) * ch, r: 4, fill: 'none', stroke: '#fff', 'stroke-width': 2 }));
  for (let k = 0; k <= 10; k++) root.append(svg('rect', { x: W - R + 16, y: T + (10 - k) * (H - T - B) / 11, width: 14, height: (H - T - B) / 11 + 0.5, fill: colour(k / 10) }));
  lab(W - R + 34, T + 10, sig(Math.pow(10, hi), 2), 'start');
  lab(W - R + 34, H - B, sig(Math.pow(10, lo), 2), 'start');
  lab(W - R + 23, H - B + 14, 'J (N²)');
  $('#costmap').replaceChildren(root);
  $('#result-summary').textContent = `Cost map of ${res.names.join(' × ')} (${nx} × ${ny} points) through ${res.through}: J at the centre ${sig(res.J_centre, 4)} N², lowest grid point ${res.names[0]} = ${sig(res.grid_min[0], 4)}, ${res.names[1]} = ${sig(res.grid_min[1], 4)} (J = ${sig(res.grid_min[2], 4)} N²)` + (res.failed ? `; ${res.failed} points failed to solve (grey)` : '') + '; colour: log J, J = 0 the lowest';
}

// a multi-start: the distinct minima (lowest J first: the first is the reported fit) with
// their parameters, and every start's run
function renderMultistart(ms) {
  const box = $('#multistart');
  box.append(el('h3', { text: `Multi-start: ${ms.n} starts (${ms.sampling}, seed ${ms.seed}), ${ms.minima.length} distinct minim${ms.minima.length === 1 ? 'um' : 'a'} (clustered within ${sig(ms.tol, 2)} in the scaled variables), ${sig(ms.seconds, 3)} s` }));
  const t = el('table', { id: 'minima-table', class: 'grid' });
  t.append(el('tr', {}, ...['minimum', 'J (N²)', 'J / J_best', 'starts', 'converged', 'at a bound', ...ms.names.map((n, k) => `${n} (${ms.units[k]})`)].map((c) => el('th', { text: c }))));
  ms.minima.forEach((m, i) => t.append(el('tr', { 'data-minimum': String(i + 1) },
    el('td', { text: i === 0 ? '1 (the fit)' : String(i + 1) }), el('td', { class: 'num', text: sig(m.J, 5) }),
    el('td', { class: 'num', text: sig(m.cost_ratio, 4) }), el('td', { class: 'num', text: String(m.starts.length) }),
    el('td', { class: 'num', text: `${m.converged} of ${m.starts.length}` }), el('td', { text: m.at_bound.join(', ') }),
    ...m.values.map((v) => el('td', { class: 'num', text: sig(v, 6) })))));
  box.append(t);
  const d = el('details', {}, el('summary', { text: 'every start' }));
  const r = el('table', { class: 'grid' });
  r.append(el('tr', {}, ...['start', 'J (N²)', 'iterations', 'stop', 'minimum', ...ms.names.map((n) => `${n} start`)].map((c) => el('th', { text: c }))));
  for (const x of ms.runs) {
    r.append(el('tr', {}, el('td', { text: String(x.index) }), el('td', { class: 'num', text: sig(x.J, 5) }),
      el('td', { class: 'num', text: String(x.iterations) }), el('td', { text: x.stop_reason }),
      el('td', { class: 'num', text: x.minimum === null || x.minimum === undefined ? '' : String(x.minimum + 1) }),
      ...x.start.map((v) => el('td', { class: 'num', text: sig(v, 4) }))));
  }
  d.append(r);
  box.append(d);
}

function renderProfiles(profiles) {
  const box = $('#profile-plots');
  for (const p of profiles) {
    const div = el('div', { class: 'plot profile', 'data-param': p.name });
    box.append(div);
    const xs = p.points.map((q) => q[0]), js = p.points.map((q) => q[1]);
    plot(div, [
      { x: xs, y: js, label: `J along ${p.name}`, color: '#1f6feb' },
      { x: [Math.min(...xs), Math.max(...xs)], y: [p.J + p.threshold, p.J + p.threshold], label: '95% level', color: '#d62728', dash: '4 3' },
      { x: [p.value], y: [p.J], color: '#222', dots: true },
    ], { xlabel: `${p.name} (${p.unit}): interval ${p.lower.kind === 'crossed' ? sig(p.lower.value, 4) : '(' + p.lower.kind + ')'} – ${p.upper.kind === 'crossed' ? sig(p.upper.value, 4) : '(' + p.upper.kind + ')'}`, ylabel: 'J profile (N²)' });
  }
}

// the batch's map: each indent at (x, y) (or along the manifest), coloured by a parameter
function drawBatch(m) {
  const ind = (m.progress && m.progress.indents) || [];
  if (!ind.length) return;
  const names = [...new Set(ind.flatMap((i) => (i.names || []).filter((_, k) => !i.free || i.free[k])))];
  if (!state.mapParam || !names.includes(state.mapParam)) state.mapParam = names[0] || null;
  const val = (i) => { const k = (i.names || []).indexOf(state.mapParam); return k >= 0 && i.values ? i.values[k] : NaN; };
  const vs = ind.map(val).filter(isFinite);
  const [v0, v1] = [Math.min(...vs), Math.max(...vs)];
  const pos = ind.map((i, k) => [i.x ?? k + 1, i.y ?? 0]);
  const xs = pos.map((p) => p[0]), ys = pos.map((p) => p[1]);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const W = 560, H = 300, L = 50, R = 20, T = 30, B = 40;
  const sx = (x1 - x0) || 1, sy = (y1 - y0) || 1;
  const px = (x) => L + (x - x0) / sx * (W - L - R), py = (y) => (y1 === y0 ? (T + H - B) / 2 : H - B - (y - y0) / sy * (H - T - B));
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, role: 'img', id: 'batch-svg' });
  root.append(svg('rect', { x: L - 12, y: T - 12, width: W - L - R + 24, height: H - T - B + 24, class: 'axis' }));
  ind.forEach((i, k) => {
    const v = val(i);
    const fill = i.state === 'pending' ? '#fff' : (i.state === 'failed' ? '#c62828' : (isFinite(v) ? colour((v - v0) / ((v1 - v0) || 1)) : '#999'));
    const c = svg('circle', { cx: px(pos[k][0]), cy: py(pos[k][1]), r: 9, fill, class: 'pt' + (state.indent === i.id ? ' sel' : ''), 'data-indent': i.id, 'data-state': i.state });
    const tt = svg('title'); tt.textContent = `${i.id}: ${i.state}${isFinite(v) ? `, ${state.mapParam} = ${sig(v, 4)}` : ''}${i.message ? ' — ' + i.message : ''}`; c.append(tt);
    if (i.state !== 'pending') c.addEventListener('click', () => openIndent(m.id, i.id));
    root.append(c);
  });
  const t = svg('text', { x: L, y: 16 });
  const done = ind.filter((i) => i.state !== 'pending').length;
  t.textContent = `${done} of ${ind.length} indents; ${state.mapParam || '–'} ${vs.length ? `${sig(v0, 3)} (dark) to ${sig(v1, 3)} (light)` : ''}; red failed, white pending`;
  root.append(t);
  const sel = el('select', { id: 'batch-param' }, ...names.map((n) => el('option', { value: n, text: n })));
  sel.value = state.mapParam || '';
  sel.addEventListener('change', () => { state.mapParam = sel.value; drawBatch(m); });
  $('#batch-map').replaceChildren(el('label', {}, 'Colour by ', sel), root);
}

function renderBatchSummary(run) {
  const s = run.summary;
  if (!s) return;
  const c = Object.entries(s.counts || {}).map(([k, v]) => `${v} ${k}`).join(', ');
  $('#result-summary').textContent = `Batch: ${s.total} indents, ${s.ran} run here (${c}); click an indent on the map; results.csv (and the maps, when the indents have x and y) among the downloads.`;
}

async function openIndent(run, id) {
  state.indent = id;
  const view = $('#indent-view');
  view.replaceChildren(el('p', { class: 'muted', text: `loading ${id}…` }));
  for (const c of document.querySelectorAll('#batch-svg .pt')) c.classList.toggle('sel', c.dataset.indent === id);
  const base = `/api/runs/${run}/files/indents/${id}`;
  const st = await api(`${base}/status.json`).catch(() => null);
  const res = await api(`${base}/result.json`).catch(() => null);
  view.replaceChildren(el('h3', { text: `Indent ${id}` }));
  if (st) view.append(el('p', { class: st.state === 'failed' ? 'error' : '', text: `${st.state}${st.message ? ': ' + st.message : ''}; ${st.iterations} iterations, ${sig(st.seconds, 3)} s` }));
  if (res) {
    const rows = res.parameters.filter((p) => p.free).map((p) => {
      const id2 = res.identifiability;
      const und = id2 && id2.undetermined.includes(p.name);
      return [p.name, sig(p.value, 6), und ? 'undetermined' : (id2 ? sig(id2.std_dev[p.name], 3) : ''), p.unit];
    });
    view.append(table('indent-table', ['parameter', 'value', 'σ', 'unit'], rows));
    view.append(el('p', { text: `J = ${sig(res.J, 4)} N²${res.fit_quality ? `, R² = ${sig(res.fit_quality.r2, 6)}` : ''}` }));
    const fit = await api(`${base}/fit.csv`).then(parseCsv).catch(() => null);
    if (fit) {
      const d = el('div', { class: 'plot', id: 'indent-fit' });
      view.append(d);
      plot(d, [{ x: fit.h, y: fit.F_data, label: 'data', color: '#222', dots: true }, { x: fit.h, y: fit.F_final, label: 'fit', color: '#d62728' }],
        { xlabel: 'depth h (µm)', ylabel: 'force F (mN)', xscale: 1e3, yscale: 1e3 });
    }
    const links = el('p', {}, 'Files: ');
    for (const n of ['result.json', 'fit.csv', 'status.json']) links.append(el('a', { href: `${base}/${n}`, download: `${id}_${n}`, text: n }), ' ');
    view.append(links);
  }
}

// a calibrated tip (TIP.ron): stored by the server, then the configuration's `punch` value
// (balanced parentheses, one line or several) replaced by Calibrated(file: "../../tips/ID/tip.ron")
async function uploadTip(file) {
  const note = $('#tip-note');
  if (!file) return;
  try {
    const t = await api(`/api/tips?name=${encodeURIComponent(file.name)}`, { method: 'POST', body: await file.arrayBuffer() });
    const cfg = $('#config');
    cfg.value = replacePunch(cfg.value, t.punch);
    note.textContent = `tip ${t.name} stored (${t.id}): punch: ${t.punch}` + (t.frame_compliance ? `, frame compliance ${sig(t.frame_compliance * 1e3, 4)} nm/mN` : '');
    note.className = 'muted';
  } catch (e) { note.textContent = e.message; note.className = 'error'; }
}

function replacePunch(text, punch) {
  const m = /(^|\n)(\s*)punch\s*:\s*/.exec(text);
  if (!m) return text;
  let i = m.index + m[0].length, depth = 0;
  for (; i < text.length; i++) {
    const c = text[i];
    if (c === '(' || c === '[') depth++;
    else if (c === ')' || c === ']') { if (depth === 0) break; depth--; }
    else if ((c === ',' || c === '\n') && depth === 0) break;
  }
  return text.slice(0, m.index + m[0].length) + punch + text.slice(i);
}

async function cancelRun() {
  if (!state.run) return;
  try {
    const m = await api(`/api/runs/${state.run}`, { method: 'DELETE' });
    renderProgress(m);
  } catch (e) { $('#run-message').textContent = e.message; }
}

// ---- runs list and comparison --------------------------------------------------------------
async function loadRuns() {
  const { runs } = await api('/api/runs');
  const body = $('#runs-table tbody');
  body.replaceChildren();
  for (const r of runs) {
    const s = r.summary || {};
    const box = el('input', { type: 'checkbox' });
    box.checked = state.selected.has(r.id);
    box.addEventListener('click', (ev) => { ev.stopPropagation(); if (box.checked) state.selected.add(r.id); else state.selected.delete(r.id); });
    const tr = el('tr', { class: 'clickable' + (r.id === state.run ? ' selected' : ''), 'data-run': r.id },
      el('td', {}, box), el('td', { text: r.id }), el('td', { text: r.command }), el('td', {}, el('span', { class: `badge ${r.status}`, text: r.status })),
      el('td', { text: s.law || '' }), el('td', { class: 'num', text: s.J !== undefined ? sig(s.J, 4) : '' }), el('td', { class: 'num', text: s.r2 ? sig(s.r2, 6) : '' }), el('td', { text: r.record || '' }));
    tr.addEventListener('click', () => { if (['done', 'failed', 'cancelled'].includes(r.status)) { openRunDone(r.id); } else { openRun(r.id); } });
    body.append(tr);
  }
}

function openRunDone(id) {
  if (state.source) { state.source.close(); state.source = null; }
  state.run = id;
  location.hash = `run=${id}`;
  $('#run-id').textContent = id;
  $('#run-error').textContent = '';
  $('#run-message').textContent = '';
  loadResult(id);
}

async function compare() {
  const ids = [...state.selected];
  const view = $('#compare-view');
  view.replaceChildren();
  if (!ids.length) { view.textContent = 'Select runs with the check boxes first.'; return; }
  const runs = await Promise.all(ids.map((id) => api(`/api/runs/${id}`)));
  const names = [...new Set(runs.flatMap((r) => (r.result && r.result.parameters ? r.result.parameters.map((p) => p.name) : [])))];
  const t = el('table', { class: 'grid', id: 'compare-table' });
  t.append(el('tr', {}, el('th', { text: '' }), ...runs.map((r) => el('th', { text: `${r.id} (${r.command})` }))));
  const row = (label, f) => t.append(el('tr', {}, el('th', { text: label }), ...runs.map((r) => el('td', { class: 'num', text: r.result ? f(r.result) : '' }))));
  row('law', (x) => x.law || '');
  row('converged', (x) => (x.converged === undefined ? '' : String(x.converged)));
  row('J (N²)', (x) => sig(x.J, 5));
  row('R²', (x) => (x.fit_quality ? sig(x.fit_quality.r2, 6) : ''));
  for (const n of names) {
    row(n, (x) => {
      const p = (x.parameters || []).find((q) => q.name === n);
      if (!p) return '';
      const id = x.identifiability;
      if (!p.free) return `${sig(p.value, 6)} (held)`;
      if (id && id.undetermined.includes(n)) return `${sig(p.value, 6)} (undetermined)`;
      const sd = id ? id.std_dev[n] : null;
      return sd !== null && sd !== undefined ? `${sig(p.value, 6)} ± ${sig(sd, 2)}` : sig(p.value, 6);
    });
  }
  view.append(t);
}

// ---- start ---------------------------------------------------------------------------------
async function start() {
  try {
    const h = await api('/api/health');
    $('#health').textContent = `v${h.version}, workspace ${h.workspace}, uploads up to ${Math.round(h.max_upload / 1048576)} MB`;
  } catch (e) { $('#health').textContent = e.message; $('#health').className = 'error'; }
  const drop = $('#drop');
  drop.addEventListener('dragover', (ev) => { ev.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (ev) => { ev.preventDefault(); drop.classList.remove('over'); upload(ev.dataTransfer.files); });
  $('#file-input').addEventListener('change', (ev) => upload(ev.target.files));
  $('#tip-input').addEventListener('change', (ev) => uploadTip(ev.target.files[0]));
  $('#record-select').addEventListener('change', (ev) => showRecord(ev.target.value));
  $('#law').addEventListener('change', () => { renderLaw(); loadTemplate(); });
  $('#command').addEventListener('change', () => { renderOptions(); if ($('#command').value === 'design' || state.lastCommand === 'design') loadTemplate(); state.lastCommand = $('#command').value; });
  renderOptions();
  $('#tip').addEventListener('change', loadTemplate);
  $('#load-template').addEventListener('click', loadTemplate);
  $('#run').addEventListener('click', submit);
  $('#cancel').addEventListener('click', cancelRun);
  $('#compare').addEventListener('click', compare);
  await Promise.all([loadLaws(), loadRecords(), loadRuns()]);
  await loadTemplate();
  const m = location.hash.match(/run=([a-z0-9-]+)/);
  if (m) {
    const run = await api(`/api/runs/${m[1]}`).catch(() => null);
    if (run && ['done', 'failed', 'cancelled'].includes(run.status)) openRunDone(m[1]); else if (run) openRun(m[1]);
  }
  document.body.dataset.ready = '1';
}

start();
