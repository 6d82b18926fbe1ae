// Calibration (presets, the form, the advanced box) and the stored metamodels (diagnostics,
// validations and their scatter, delete).
import { configureAnalyses } from './analyses.js';
import { configureSweep } from './design.js';
import * as Charts from './charts.js';
import { format } from './charts.js';
import { $, $$, ApiProblem, api, apiSpec, checkSchema, clearErrors, numberField, session, showProblem } from './client.js';
import { loadOperations, throughOperation } from './operations.js';

export async function loadPresets() {
  const { body } = await api('GET', '/v1/presets');
  const select = $('#calibration-preset');
  select.replaceChildren(...body.presets.map((preset) => new Option(`${preset.name} — ${preset.floors} floors`, preset.name)));
  session.presets = body.presets;
  const preferred = body.presets.find((preset) => preset.default);
  if (preferred) select.value = preferred.name;
  showPreset();
}

export function showPreset() {
  const preset = session.presets.find((p) => p.name === $('#calibration-preset').value);
  if (!preset) return;
  $('#calibration-preset-about').textContent = `${preset.description} ${preset.floors} floors, ${format(preset.roof_height_m)} m; first frequencies ${preset.frequencies_rad_s.map((w) => format(w / (2 * Math.PI))).join(', ')} Hz.`;
  const defaults = preset.default_calibration;
  for (const name of ['experiments', 'duration_s', 'seed']) {
    const input = $(`#calibration-${name}`);
    input.placeholder = defaults[name] ?? '';
  }
}

export async function calibrate(event) {
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

export async function loadMetamodels() {
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
  configureSweep();
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
    const cells = [mode.mode, mode.selected_terms.join(', '), format(mode.narx_mean_relative_error), format(mode.pc_narx_mean_relative_error), mode.coefficient_pce_terms.join(' '), mode.diverged_experiments, refinementsAtCap(mode.refinement)];
    for (const cell of cells) row.insertCell().textContent = cell;
    return row;
  }));
}

/** Refinements that stopped at their iteration cap, out of those run (none run: a dash). */
function refinementsAtCap(r) {
  const run = r.converged + r.iteration_cap + r.no_improving_step + r.undefined_start;
  return run ? `${r.iteration_cap} of ${run}` : '—';
}

export async function validate(event) {
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
    const cells = [r.response, r.floor, format(r.peak_correlation), `${format(100 * r.median_peak_relative_error)} %`, `${format(100 * r.p95_peak_relative_error)} %`, format(r.max_exceedance_gap), `${format(r.mean_reference_peak)} ${r.unit}`, `${format(r.mean_metamodel_peak)} ${r.unit} (${format(r.mean_metamodel_peak / r.mean_reference_peak)}×)`];
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

export async function deleteMetamodel() {
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
