// windmeta's page: a client of the public API like any other. Every action is an API call; long
// work (calibrations, validations, analyses) goes through operations whose progress arrives on the
// event stream, so nothing on the page waits on a long request.
'use strict';

const $ = (selector, root = document) => root.querySelector(selector);
const $$ = (selector, root = document) => Array.from(root.querySelectorAll(selector));

/** What the page holds for this browser tab. */
const session = {
  /** The API key, kept for the browser session only. */
  key: sessionStorage.getItem('windmeta.key') || '',
  /** The chosen metamodel: {id, metamodel, study}. */
  current: null,
  /** The API description, read once for the advanced box's checks. */
  spec: null,
  /** Operations on the page by id: {operation, row, waiters, followed}. */
  operations: new Map(),
  /** The explorer's curves: the latest and the one kept for comparison. */
  curves: { latest: null, kept: null },
};

const UNITS = { displacement: 'm', drift: 'm', acceleration: 'm/s²', damper_force: 'N', damper_stroke: 'm' };
const UNIT_TAGS = { displacement: 'm', drift: 'm', acceleration: 'm_s2', damper_force: 'n', damper_stroke: 'm' };
const format = (value) => Charts.format(value);

/** A refused request: the problem document the API sent. */
class ApiProblem extends Error {
  constructor(status, problem) {
    super(problem.detail || problem.title || `HTTP ${status}`);
    this.status = status;
    this.problem = problem;
  }
}

async function api(method, path, body, headers = {}) {
  const init = { method, headers: { Accept: 'application/json', ...headers } };
  if (session.key) init.headers.Authorization = `Bearer ${session.key}`;
  if (body !== undefined) {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (error) {
    throw new ApiProblem(0, { title: 'The server did not answer', detail: String(error) });
  }
  const type = response.headers.get('Content-Type') || '';
  const payload = response.status === 204 ? null : type.includes('json') ? await response.json() : await response.text();
  if (response.status === 401) askForKey('This server needs an API key.');
  if (!response.ok) {
    throw new ApiProblem(response.status, typeof payload === 'object' && payload ? payload : { title: response.statusText, detail: String(payload) });
  }
  return { status: response.status, body: payload, headers: response.headers };
}

// ---- The API key -------------------------------------------------------------------------------

function askForKey(message) {
  $('#key-form').hidden = false;
  $('#key-status').textContent = message;
}

function setUpKey() {
  if (session.key) {
    $('#key-form').hidden = false;
    $('#api-key').value = session.key;
  }
  $('#key-form').addEventListener('submit', (event) => {
    event.preventDefault();
    session.key = $('#api-key').value.trim();
    sessionStorage.setItem('windmeta.key', session.key);
    $('#key-status').textContent = '';
    loadEverything();
  });
}

// ---- Errors next to their fields ---------------------------------------------------------------

function clearErrors(form) {
  $$('.error', form).forEach((node) => { node.textContent = ''; });
  $$('[aria-invalid]', form).forEach((node) => node.removeAttribute('aria-invalid'));
}

/** Shows a problem's field errors next to the fields `prefix-<field>` and the rest above the form. */
function showProblem(form, prefix, error) {
  const general = $(`#${prefix}-error`);
  if (!(error instanceof ApiProblem)) {
    general.textContent = String(error);
    return;
  }
  const fields = error.problem.errors || [];
  const unplaced = [];
  for (const { field, detail } of fields) {
    const name = field.split(/[.[]/)[0];
    const slot = $(`#${prefix}-${name}-error`);
    const input = $(`#${prefix}-${name}`);
    if (slot) {
      slot.textContent = detail.startsWith(field) ? detail : `${field}: ${detail}`;
      if (input) input.setAttribute('aria-invalid', 'true');
    } else {
      unplaced.push(`${field}: ${detail}`);
    }
  }
  if (!fields.length || unplaced.length) {
    general.textContent = [`${error.problem.title || 'Refused'}: ${error.problem.detail || ''}`, ...unplaced].join(' — ');
  }
  if (fields.length) {
    const first = $('[aria-invalid="true"]', form);
    if (first) first.focus();
  }
}

/** A number field's value: undefined when empty, an error when it is not a number. */
function numberField(input, errors, integer) {
  if (input.validity.badInput) {
    errors.push({ field: input.name, detail: 'is not a number' });
    return undefined;
  }
  if (input.value.trim() === '') return undefined;
  const value = Number(input.value);
  if (integer && !Number.isInteger(value)) errors.push({ field: input.name, detail: 'must be a whole number' });
  return value;
}

// ---- A check of JSON against the API's own schemas ---------------------------------------------

async function apiSpec() {
  if (!session.spec) session.spec = (await api('GET', '/openapi.json')).body;
  return session.spec;
}

/** The errors of `value` against an OpenAPI schema (the parts of JSON Schema the API uses). */
function checkSchema(schema, value, path, spec, errors) {
  if (schema.$ref) return checkSchema(spec.components.schemas[schema.$ref.split('/').pop()], value, path, spec, errors);
  if (schema.oneOf || schema.anyOf) {
    const options = schema.oneOf || schema.anyOf;
    const attempts = options.map((option) => { const e = []; checkSchema(option, value, path, spec, e); return e; });
    if (!attempts.some((e) => e.length === 0)) errors.push(...attempts.reduce((a, b) => (b.length < a.length ? b : a)));
    return;
  }
  if (schema.allOf) { schema.allOf.forEach((part) => checkSchema(part, value, path, spec, errors)); return; }
  const field = path || 'request';
  const types = schema.type === undefined ? null : [].concat(schema.type);
  const kind = value === null ? 'null' : Array.isArray(value) ? 'array' : Number.isInteger(value) ? 'integer' : typeof value;
  if (types && !types.includes(kind) && !(kind === 'integer' && types.includes('number'))) {
    errors.push({ field, detail: `must be ${types.join(' or ')}, not ${kind}` });
    return;
  }
  if (schema.enum && !schema.enum.includes(value)) errors.push({ field, detail: `must be one of ${schema.enum.join(', ')}` });
  if (typeof value === 'number') {
    if (schema.minimum !== undefined && value < schema.minimum) errors.push({ field, detail: `must be at least ${schema.minimum}` });
    if (schema.maximum !== undefined && value > schema.maximum) errors.push({ field, detail: `must be at most ${schema.maximum}` });
    if (schema.exclusiveMinimum !== undefined && value <= schema.exclusiveMinimum) errors.push({ field, detail: `must be above ${schema.exclusiveMinimum}` });
    if (schema.exclusiveMaximum !== undefined && value >= schema.exclusiveMaximum) errors.push({ field, detail: `must be below ${schema.exclusiveMaximum}` });
  }
  if (Array.isArray(value)) {
    if (schema.minItems !== undefined && value.length < schema.minItems) errors.push({ field, detail: `needs at least ${schema.minItems} items` });
    if (schema.maxItems !== undefined && value.length > schema.maxItems) errors.push({ field, detail: `takes at most ${schema.maxItems} items` });
    if (schema.items) value.forEach((item, i) => checkSchema(schema.items, item, `${field}[${i}]`, spec, errors));
  }
  if (kind === 'object') {
    const known = schema.properties || {};
    for (const [name, item] of Object.entries(value)) {
      const inner = path ? `${path}.${name}` : name;
      if (known[name]) checkSchema(known[name], item, inner, spec, errors);
      else if (schema.additionalProperties === false) errors.push({ field: inner, detail: 'is not a field of this request' });
      else if (typeof schema.additionalProperties === 'object') checkSchema(schema.additionalProperties, item, inner, spec, errors);
      if (schema.propertyNames && schema.propertyNames.pattern && !new RegExp(schema.propertyNames.pattern).test(name)) {
        errors.push({ field: inner, detail: 'is not a name this field takes' });
      }
    }
    for (const name of schema.required || []) if (!(name in value)) errors.push({ field: path ? `${path}.${name}` : name, detail: 'is required' });
  }
}

// ---- Operations: a live list ---------------------------------------------------------------------

function describeProgress(progress) {
  if (!progress) return '';
  if (progress.stage === 'experiments') return `reference runs ${progress.done} of ${progress.total}`;
  if (progress.stage === 'samples') return `storms ${progress.done} of ${progress.total}`;
  if (progress.stage === 'structure') return `mode ${progress.mode}: choosing the NARX terms`;
  if (progress.stage === 'expansion') return `mode ${progress.mode}: fitting the expansions`;
  return progress.stage;
}

function operationRow(id) {
  let entry = session.operations.get(id);
  if (!entry) {
    const row = document.createElement('li');
    row.dataset.operation = id;
    row.innerHTML = '<span class="kind"></span> <span class="state"></span> <progress max="1" value="0"></progress> <span class="progress-text"></span> <span class="timing hint"></span> <button type="button" class="secondary cancel">Cancel</button> <span class="detail error"></span>';
    $('.cancel', row).addEventListener('click', () => cancelOperation(id));
    $('#operation-list').prepend(row);
    entry = { operation: null, row, waiters: [], followed: false };
    session.operations.set(id, entry);
  }
  return entry;
}

function showOperation(operation) {
  const entry = operationRow(operation.id);
  entry.operation = operation;
  const { row } = entry;
  row.dataset.state = operation.state;
  $('.kind', row).textContent = `${operation.kind} ${operation.id.slice(0, 8)}`;
  const state = $('.state', row);
  state.textContent = operation.state;
  state.className = `state ${operation.state}`;
  const bar = $('progress', row);
  const progress = operation.progress;
  bar.setAttribute('aria-label', `progress of ${operation.kind} ${operation.id.slice(0, 8)}`);
  if (operation.state === 'succeeded') { bar.max = 1; bar.value = 1; } else if (progress && progress.total) { bar.max = progress.total; bar.value = progress.done; } else if (!operation.done) bar.removeAttribute('value');
  $('.progress-text', row).textContent = operation.done ? '' : describeProgress(progress);
  $('.timing', row).textContent = operation.seconds !== null && operation.seconds !== undefined ? `${format(operation.seconds)} s` : new Date(operation.created_at_ms).toLocaleTimeString();
  $('.cancel', row).hidden = operation.done;
  $('.detail', row).textContent = operation.error || '';
  if (operation.done) {
    entry.waiters.splice(0).forEach((resolve) => resolve(operation));
  }
}

/** Reads the operation's event stream (with the key, which EventSource cannot send). */
async function streamOperation(id) {
  const headers = { Accept: 'text/event-stream' };
  if (session.key) headers.Authorization = `Bearer ${session.key}`;
  const response = await fetch(`/v1/operations/${id}/events`, { headers });
  if (!response.ok || !response.body) throw new Error(`event stream: HTTP ${response.status}`);
  const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
  let buffer = '';
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    buffer += value;
    let end;
    while ((end = buffer.indexOf('\n\n')) >= 0) {
      const record = buffer.slice(0, end);
      buffer = buffer.slice(end + 2);
      const data = record.split('\n').filter((line) => line.startsWith('data:')).map((line) => line.slice(5).trimStart()).join('\n');
      if (data) showOperation(JSON.parse(data));
    }
  }
}

/** Follows an operation to its end: the event stream, then polling if the stream breaks off. */
async function follow(id) {
  const entry = operationRow(id);
  if (entry.followed) return;
  entry.followed = true;
  try {
    await streamOperation(id);
  } catch (error) {
    console.warn(error);
  }
  while (!(entry.operation && entry.operation.done)) {
    try {
      showOperation((await api('GET', `/v1/operations/${id}`)).body);
    } catch (error) {
      $('.detail', entry.row).textContent = error.message;
    }
    if (!entry.operation || !entry.operation.done) await new Promise((resolve) => setTimeout(resolve, 1500));
  }
}

/** The operation once it is done (succeeded, failed or cancelled). */
function finished(operation) {
  showOperation(operation);
  const entry = operationRow(operation.id);
  const done = entry.operation.done ? Promise.resolve(entry.operation) : new Promise((resolve) => entry.waiters.push(resolve));
  follow(operation.id);
  return done;
}

async function cancelOperation(id) {
  try {
    showOperation((await api('POST', `/v1/operations/${id}/cancel`)).body);
  } catch (error) {
    $('.detail', operationRow(id).row).textContent = error.message;
  }
}

async function loadOperations() {
  const { body } = await api('GET', '/v1/operations?limit=20');
  body.operations.slice().reverse().forEach((operation) => {
    showOperation(operation);
    if (!operation.done) follow(operation.id);
  });
  return body.operations;
}

/** Runs `work` (which starts an operation) with a status line, and gives the finished operation's result. */
async function throughOperation(form, prefix, start) {
  const status = $(`#${prefix}-status`);
  const button = $('button[type="submit"]', form);
  clearErrors(form);
  button.disabled = true;
  status.textContent = 'Sending…';
  try {
    const operation = (await start()).body;
    status.textContent = `Running as operation ${operation.id.slice(0, 8)} (progress under Operations)…`;
    const update = setInterval(() => {
      const current = session.operations.get(operation.id);
      if (current && current.operation && !current.operation.done) status.textContent = `Running: ${describeProgress(current.operation.progress) || current.operation.state}`;
    }, 500);
    const done = await finished(operation);
    clearInterval(update);
    if (done.state !== 'succeeded') throw new ApiProblem(0, { title: `The operation ${done.state}`, detail: done.error || '' });
    status.textContent = `Done in ${format(done.seconds)} s.`;
    return done;
  } catch (error) {
    status.textContent = '';
    showProblem(form, prefix, error);
    return null;
  } finally {
    button.disabled = false;
  }
}

// ---- Calibration ---------------------------------------------------------------------------------

async function loadPresets() {
  const { body } = await api('GET', '/v1/presets');
  const select = $('#calibration-preset');
  select.replaceChildren(...body.presets.map((preset) => new Option(`${preset.name} — ${preset.floors} floors`, preset.name)));
  session.presets = body.presets;
  const preferred = body.presets.find((preset) => preset.default);
  if (preferred) select.value = preferred.name;
  showPreset();
}

function showPreset() {
  const preset = session.presets.find((p) => p.name === $('#calibration-preset').value);
  if (!preset) return;
  $('#calibration-preset-about').textContent = `${preset.description} ${preset.floors} floors, ${format(preset.roof_height_m)} m; first frequencies ${preset.frequencies_rad_s.map((w) => format(w / (2 * Math.PI))).join(', ')} Hz.`;
  const defaults = preset.default_calibration;
  for (const name of ['experiments', 'duration_s', 'seed']) {
    const input = $(`#calibration-${name}`);
    input.placeholder = defaults[name] ?? '';
  }
}

async function calibrate(event) {
  event.preventDefault();
  const form = event.target;
  clearErrors(form);
  const errors = [];
  const request = { preset: $('#calibration-preset').value };
  for (const name of ['experiments', 'duration_s', 'seed']) {
    const value = numberField($(`#calibration-${name}`), errors, name !== 'duration_s');
    if (value !== undefined) request[name] = value;
  }
  let advanced;
  try {
    advanced = JSON.parse($('#calibration-advanced').value || '{}');
    if (advanced === null || typeof advanced !== 'object' || Array.isArray(advanced)) throw new Error('must be a JSON object');
  } catch (error) {
    errors.push({ field: 'advanced', detail: error.message });
  }
  if (advanced) {
    Object.assign(request, advanced);
    const found = [];
    checkSchema({ $ref: '#/components/schemas/CalibrationRequest' }, request, '', await apiSpec(), found);
    const formFields = ['preset', 'experiments', 'duration_s', 'seed'];
    errors.push(...found.map((e) => (formFields.includes(e.field.split(/[.[]/)[0]) && !(e.field.split(/[.[]/)[0] in advanced) ? e : { field: 'advanced', detail: `${e.field} ${e.detail}` })));
  }
  if (errors.length) {
    showProblem(form, 'calibration', new ApiProblem(422, { title: 'Not sent', detail: 'some fields need attention', errors }));
    return;
  }
  const done = await throughOperation(form, 'calibration', () => api('POST', '/v1/calibrations', request));
  if (done && done.metamodel_id) {
    await loadMetamodels();
    await choose(done.metamodel_id);
  }
}

// ---- Metamodels ----------------------------------------------------------------------------------

async function loadMetamodels() {
  const { body } = await api('GET', '/v1/metamodels?limit=100');
  const rows = body.metamodels.map((m) => {
    const row = document.createElement('tr');
    row.dataset.metamodel = m.id;
    row.innerHTML = '<td><code></code></td><td></td><td></td><td><button type="button" class="secondary">Use</button></td>';
    row.cells[0].firstChild.textContent = m.id;
    row.cells[1].textContent = m.preset;
    row.cells[2].textContent = new Date(m.created_at_ms).toLocaleString();
    const button = $('button', row);
    button.setAttribute('aria-label', `Use metamodel ${m.id}`);
    button.addEventListener('click', () => choose(m.id));
    if (session.current && session.current.id === m.id) row.classList.add('selected');
    return row;
  });
  $('#metamodel-table tbody').replaceChildren(...rows);
  if (!rows.length) {
    const row = document.createElement('tr');
    row.innerHTML = '<td colspan="4">None yet: start a calibration.</td>';
    $('#metamodel-table tbody').append(row);
  }
  return body.metamodels;
}

async function choose(id) {
  const [metamodel, study] = await Promise.all([api('GET', `/v1/metamodels/${id}`), api('GET', `/v1/metamodels/${id}/study`)]);
  session.current = { id, metamodel: metamodel.body, study: study.body };
  $$('#metamodel-table tr[data-metamodel]').forEach((row) => row.classList.toggle('selected', row.dataset.metamodel === id));
  $$('[data-current-metamodel]').forEach((node) => { node.textContent = `${id.slice(0, 8)} (${study.body.preset}, ${study.body.floors} floors)`; });
  showDiagnostics();
  configureAnalyses();
  $('#validation-result').hidden = true;
  const validations = (await loadOperations()).filter((op) => op.kind === 'validation' && op.state === 'succeeded' && op.metamodel_id === id);
  if (validations.length) showValidation(validations[0].result);
}

function showDiagnostics() {
  const { id, metamodel } = session.current;
  const calibration = metamodel.calibration;
  $('#metamodel-detail').hidden = false;
  $('#metamodel-detail-id').textContent = id;
  $('#metamodel-summary').textContent = `${calibration.options.experiments} experiments; mean relative error over the experiments: NARX ${format(calibration.narx_mean_relative_error)}, PC-NARX ${format(calibration.pc_narx_mean_relative_error)}.`;
  $('#diagnostics-table tbody').replaceChildren(...calibration.modes.map((mode) => {
    const row = document.createElement('tr');
    const cells = [mode.mode, mode.selected_terms.join(', '), format(mode.narx_mean_relative_error), format(mode.pc_narx_mean_relative_error), mode.coefficient_pce_terms.join(' '), mode.diverged_experiments];
    for (const cell of cells) row.insertCell().textContent = cell;
    return row;
  }));
}

async function validate(event) {
  event.preventDefault();
  const form = event.target;
  if (!session.current) return;
  const errors = [];
  const request = {};
  for (const name of ['samples', 'seed']) {
    const value = numberField($(`#validation-${name}`), errors, true);
    if (value !== undefined) request[name] = value;
  }
  if (errors.length) { showProblem(form, 'validation', new ApiProblem(422, { title: 'Not sent', detail: '', errors })); return; }
  const id = session.current.id;
  const done = await throughOperation(form, 'validation', () => api('POST', `/v1/metamodels/${id}/validations`, request));
  if (done && session.current && session.current.id === id) showValidation(done.result);
}

function showValidation(report) {
  $('#validation-result').hidden = false;
  $('#validation-table tbody').replaceChildren(...(report.responses || []).map((r) => {
    const row = document.createElement('tr');
    const cells = [r.response, r.floor, format(r.peak_correlation), `${format(100 * r.median_peak_relative_error)} %`, `${format(100 * r.p95_peak_relative_error)} %`, format(r.max_exceedance_gap), `${format(r.mean_reference_peak)} ${r.unit}`];
    for (const cell of cells) row.insertCell().textContent = cell;
    return row;
  }));
  const chart = Charts.lines({
    title: `Roof peak displacement: metamodel against reference (${report.samples} fresh storms)`,
    xLabel: 'reference peak (m)', yLabel: 'metamodel peak (m)', diagonal: true,
    series: [{ name: `correlation ${format(report.peak_correlation)}`, x: report.reference_peak, y: report.metamodel_peak, line: false, points: true }],
    describe: (s, i) => `reference ${format(s.x[i])} m, metamodel ${format(s.y[i])} m`,
  });
  $('#validation-chart').replaceChildren(chart);
}

async function deleteMetamodel() {
  if (!session.current) return;
  const id = session.current.id;
  if (!window.confirm(`Delete metamodel ${id}? Its coefficients are removed for every user of this server.`)) return;
  try {
    await api('DELETE', `/v1/metamodels/${id}`);
    session.current = null;
    $('#metamodel-detail').hidden = true;
    $$('[data-current-metamodel]').forEach((node) => { node.textContent = 'none chosen'; });
    await loadMetamodels();
  } catch (error) {
    $('#validation-error').textContent = error.message;
  }
}

// ---- The analyses' shared fields ---------------------------------------------------------------

/** Adds the response, floor, group, samples, seed and confidence fields to each analysis form. */
function setUpAnalysisForms() {
  for (const form of $$('form.analysis')) {
    const prefix = form.id.replace(/-form$/, '');
    const fields = $('#response-fields').content.cloneNode(true);
    $$('[data-name]', fields).forEach((input) => {
      input.id = `${prefix}-${input.dataset.name}`;
      input.name = input.dataset.name;
      input.setAttribute('aria-describedby', `${prefix}-${input.dataset.name}-error`);
    });
    $$('[data-for]', fields).forEach((label) => label.setAttribute('for', `${prefix}-${label.dataset.for}`));
    $$('[data-error]', fields).forEach((slot) => { slot.id = `${prefix}-${slot.dataset.error}-error`; });
    $(`#${prefix}-samples`, fields).value = form.dataset.samples;
    form.prepend(fields);
  }
}

/** Bounds of the chosen metamodel's study on the analyses' fields. */
function configureAnalyses() {
  const { study } = session.current;
  for (const form of $$('form.analysis')) {
    const prefix = form.id.replace(/-form$/, '');
    $(`#${prefix}-floor`).max = study.floors;
    $(`#${prefix}-floor`).placeholder = `roof (${study.floors})`;
    $(`#${prefix}-group`).max = study.damper_groups;
    $(`#${prefix}-group`).placeholder = study.damper_groups ? `1 to ${study.damper_groups}` : 'no dampers';
  }
  const wind = study.inputs.find((input) => input.name === 'wind_speed');
  const slider = $('#explore-wind');
  const [low, high] = wind.calibrated_range;
  slider.min = Math.ceil(low * 10) / 10;
  slider.max = Math.floor(high * 10) / 10;
  slider.step = 0.1;
  slider.value = Math.round(((low + high) / 2) * 10) / 10;
  $('#explore-wind-value').textContent = slider.value;
  $('#explore-wind-range').textContent = `From ${format(low)} to ${format(high)} m/s: the speeds of the calibration's experiments (the metamodel extrapolates beyond them). Marginal: ${describeMarginal(wind.marginal)}.`;
}

function describeMarginal(marginal) {
  const parameters = Object.entries(marginal).filter(([key]) => key !== 'distribution').map(([key, value]) => `${key} ${format(value)}`);
  return `${marginal.distribution} (${parameters.join(', ')})`;
}

/** The request fields shared by the analyses, or null after showing what is wrong. */
function analysisRequest(form, prefix) {
  clearErrors(form);
  if (!session.current) {
    $(`#${prefix}-error`).textContent = 'Choose a metamodel first (under Metamodels).';
    return null;
  }
  const errors = [];
  const request = { response: $(`#${prefix}-response`).value };
  for (const name of ['floor', 'group', 'samples', 'seed', 'confidence']) {
    const value = numberField($(`#${prefix}-${name}`), errors, name !== 'confidence');
    if (value !== undefined) request[name] = value;
  }
  if (errors.length) {
    showProblem(form, prefix, new ApiProblem(422, { title: 'Not sent', detail: 'some fields need attention', errors }));
    return null;
  }
  return request;
}

function responseLabel(answer) {
  const r = answer.response;
  const where = r.group ? `damper group ${r.group}` : `floor ${r.floor}`;
  return `${r.kind.replace('_', ' ')}, ${where}`;
}

/** Starts an analysis as an operation and gives its answer. */
async function runAnalysis(form, prefix, path, request) {
  const id = session.current.id;
  const done = await throughOperation(form, prefix, () => api('POST', `/v1/metamodels/${id}/${path}`, request, { Prefer: 'respond-async' }));
  return done && done.result;
}

function download(anchor, name, type, content) {
  if (anchor.href) URL.revokeObjectURL(anchor.href);
  anchor.href = URL.createObjectURL(new Blob([content], { type }));
  anchor.download = name;
  anchor.hidden = false;
}

// ---- The exceedance explorer ---------------------------------------------------------------------

async function explore(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'explore');
  if (!request) return;
  if ($('#explore-hold-wind').checked) request.fixed = { wind_speed: Number($('#explore-wind').value) };
  const answer = await runAnalysis(form, 'explore', 'exceedance', request);
  if (!answer) return;
  const wind = request.fixed ? `${request.fixed.wind_speed} m/s` : 'wind speed random';
  session.curves.latest = { answer, name: `${responseLabel(answer)}, ${wind}` };
  $('#explore-keep').disabled = false;
  drawExceedance();
}

function curveSeries(curve) {
  const { answer } = curve;
  return { name: curve.name, x: answer.thresholds, y: answer.probabilities, lower: answer.lower, upper: answer.upper };
}

function drawExceedance() {
  const { latest, kept } = session.curves;
  if (!latest) return;
  const unit = UNITS[latest.answer.response.kind];
  const series = [curveSeries(latest), ...(kept ? [curveSeries(kept)] : [])];
  const chart = Charts.lines({
    title: `P(peak > x), ${latest.answer.samples} storms, ${format(100 * latest.answer.confidence)} % band`,
    xLabel: `peak ${latest.answer.response.kind.replace('_', ' ')} x (${unit})`, yLabel: 'probability of exceedance', yLog: true, yMax: 1,
    series,
    describe: (s, i) => `${s.name}: x = ${format(s.x[i])} ${unit}, P = ${format(s.y[i])} [${format(s.lower[i])}, ${format(s.upper[i])}]`,
  });
  $('#explore-chart').replaceChildren(chart);
  const answer = latest.answer;
  $('#explore-table').hidden = false;
  $('#explore-table thead th').textContent = `Threshold (${unit})`;
  $('#explore-table tbody').replaceChildren(...answer.thresholds.map((threshold, i) => {
    const row = document.createElement('tr');
    for (const cell of [threshold, answer.probabilities[i], answer.lower[i], answer.upper[i]]) row.insertCell().textContent = format(cell);
    return row;
  }));
  const csv = [`threshold_${UNIT_TAGS[answer.response.kind]},probability,lower,upper`, ...answer.thresholds.map((t, i) => `${t},${answer.probabilities[i]},${answer.lower[i]},${answer.upper[i]}`)].join('\n') + '\n';
  download($('#explore-csv'), 'exceedance.csv', 'text/csv', csv);
  download($('#explore-json'), 'exceedance.json', 'application/json', JSON.stringify(answer, null, 2));
  download($('#explore-svg'), 'exceedance.svg', 'image/svg+xml', Charts.serialize(chart));
}

// ---- Annual curve, fragility, sensitivity ----------------------------------------------------------

async function hazard(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'hazard');
  if (!request) return;
  const answer = await runAnalysis(form, 'hazard', 'hazard', request);
  if (!answer) return;
  const unit = UNITS[answer.response.kind];
  $('#hazard-chart').replaceChildren(Charts.lines({
    title: `Annual exceedance: ${responseLabel(answer)}`, xLabel: `peak x (${unit})`, yLabel: 'annual probability of exceedance', yLog: true,
    series: [{ name: `${answer.samples} storms`, x: answer.thresholds, y: answer.annual_probability, lower: answer.lower, upper: answer.upper }],
    describe: (s, i) => `x = ${format(s.x[i])} ${unit}: ${format(s.y[i])} a year [${format(s.lower[i])}, ${format(s.upper[i])}], return period ${format(1 / s.y[i])} years`,
  }));
  $('#hazard-table').hidden = false;
  $('#hazard-table tbody').replaceChildren(...answer.return_levels.map((level) => {
    const row = document.createElement('tr');
    row.insertCell().textContent = `${format(level.return_period_years)} years`;
    for (const value of [level.value, level.lower, level.upper]) row.insertCell().textContent = value === null || value === undefined ? 'beyond the samples' : `${format(value)} ${unit}`;
    return row;
  }));
  $('#hazard-notes').textContent = `Calibrated wind speeds ${format(answer.calibrated_wind_range[0])}–${format(answer.calibrated_wind_range[1])} m/s; the climate's probability outside them ${format(answer.climate_beyond_calibrated_range)}. Climate: ${describeMarginal(answer.climate)}.`;
}

async function fragility(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'fragility');
  if (!request) return;
  const thresholds = $('#fragility-thresholds').value.trim();
  if (thresholds) {
    request.thresholds = thresholds.split(/[,\s]+/).filter(Boolean).map(Number);
    if (request.thresholds.some((t) => !Number.isFinite(t))) {
      showProblem(form, 'fragility', new ApiProblem(422, { title: 'Not sent', detail: '', errors: [{ field: 'thresholds', detail: 'must be numbers separated by commas' }] }));
      return;
    }
  }
  const answer = await runAnalysis(form, 'fragility', 'fragility', request);
  if (!answer) return;
  const unit = UNITS[answer.response.kind];
  $('#fragility-chart').replaceChildren(Charts.lines({
    title: `Fragility: ${responseLabel(answer)}, ${answer.samples_per_speed} storms per speed`, xLabel: 'wind speed at 10 m (m/s)', yLabel: 'P(peak > threshold | speed)', yMin: 0, yMax: 1,
    series: answer.curves.map((curve) => ({
      name: `${format(curve.threshold)} ${unit}${curve.lognormal ? ` (θ ${format(curve.lognormal.median_speed)} m/s, β ${format(curve.lognormal.dispersion)})` : ''}`,
      x: answer.wind_speeds, y: curve.probability, lower: curve.lower, upper: curve.upper, points: true,
    })),
    describe: (s, i) => `${s.name}: ${format(s.x[i])} m/s → ${format(s.y[i])} [${format(s.lower[i])}, ${format(s.upper[i])}]`,
  }));
}

async function sensitivity(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'sensitivity');
  if (!request) return;
  const answer = await runAnalysis(form, 'sensitivity', 'sensitivity', request);
  if (!answer) return;
  const indices = answer.indices;
  $('#sensitivity-chart').replaceChildren(Charts.bars({
    title: `Sobol indices: ${responseLabel(answer)}, ${answer.evaluations} runs`, yLabel: 'share of the variance',
    categories: indices.map((index) => index.name),
    groups: [
      { name: 'first order', values: indices.map((i) => i.first_order), lower: indices.map((i) => i.first_order_ci[0]), upper: indices.map((i) => i.first_order_ci[1]) },
      { name: 'total', values: indices.map((i) => i.total), lower: indices.map((i) => i.total_ci[0]), upper: indices.map((i) => i.total_ci[1]) },
    ],
  }));
  $('#sensitivity-table').hidden = false;
  $('#sensitivity-table tbody').replaceChildren(...indices.map((index) => {
    const row = document.createElement('tr');
    const cells = [index.name, format(index.first_order), `${format(index.first_order_ci[0])} – ${format(index.first_order_ci[1])}`, format(index.total), `${format(index.total_ci[0])} – ${format(index.total_ci[1])}`];
    for (const cell of cells) row.insertCell().textContent = cell;
    return row;
  }));
}

// ---- Start ---------------------------------------------------------------------------------------

async function loadEverything() {
  try {
    await loadPresets();
    await loadOperations();
    await loadMetamodels();
  } catch (error) {
    $('#calibration-error').textContent = error.message;
  }
}

function start() {
  session.presets = [];
  setUpKey();
  setUpAnalysisForms();
  $('#calibration-preset').addEventListener('change', showPreset);
  $('#calibration-form').addEventListener('submit', calibrate);
  $('#operations-refresh').addEventListener('click', () => loadOperations().catch((e) => { $('#calibration-error').textContent = e.message; }));
  $('#metamodels-refresh').addEventListener('click', () => loadMetamodels().catch((e) => { $('#calibration-error').textContent = e.message; }));
  $('#validation-form').addEventListener('submit', validate);
  $('#metamodel-delete').addEventListener('click', deleteMetamodel);
  $('#explore-form').addEventListener('submit', explore);
  $('#explore-hold-wind').addEventListener('change', (event) => { $('#explore-wind').disabled = !event.target.checked; });
  $('#explore-wind').addEventListener('input', (event) => { $('#explore-wind-value').textContent = event.target.value; });
  $('#explore-keep').addEventListener('click', () => {
    session.curves.kept = session.curves.latest;
    $('#explore-clear').hidden = false;
    drawExceedance();
  });
  $('#explore-clear').addEventListener('click', () => {
    session.curves.kept = null;
    $('#explore-clear').hidden = true;
    drawExceedance();
  });
  $('#hazard-form').addEventListener('submit', hazard);
  $('#fragility-form').addEventListener('submit', fragility);
  $('#sensitivity-form').addEventListener('submit', sensitivity);
  loadEverything();
}

start();
