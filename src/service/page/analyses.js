// The analyses of the chosen metamodel: their shared fields, the exceedance explorer (curves kept
// for comparison, downloads), the annual curve with return levels, fragility and Sobol indices.
import * as Charts from './charts.js';
import { format } from './charts.js';
import { $, $$, ApiProblem, UNITS, UNIT_TAGS, api, clearErrors, numberField, session, showProblem } from './client.js';
import { throughOperation } from './operations.js';

/** Adds the response, floor, group, samples, seed and confidence fields to each analysis form. */
export function setUpAnalysisForms() {
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
    if ('certify' in form.dataset) form.insertBefore(certifyFields(prefix), $('.actions', form));
  }
}

/** The fields of a certified answer (reference storms and model), named for the form `prefix`. */
function certifyFields(prefix) {
  const fields = $('#certify-fields').content.cloneNode(true);
  $$('[data-name]', fields).forEach((input) => {
    input.id = `${prefix}-${input.dataset.name}`;
    input.name = input.dataset.field;
  });
  $$('[data-for]', fields).forEach((label) => label.setAttribute('for', `${prefix}-${label.dataset.for}`));
  $$('[data-hint-of]', fields).forEach((hint) => { hint.id = `${prefix}-${hint.dataset.hintOf}-hint`; });
  $$('[data-error]', fields).forEach((slot) => { slot.id = `${prefix}-${slot.dataset.error}-error`; });
  $(`#${prefix}-certify`, fields).setAttribute('aria-describedby', `${prefix}-certify-hint ${prefix}-certify-error`);
  return fields;
}

/** The certification a form asks for into `request`; false after showing what is wrong. */
function certifyField(form, prefix, request) {
  const errors = [];
  const referenceStorms = numberField($(`#${prefix}-certify`), errors, true);
  if (errors.length) {
    showProblem(form, prefix, new ApiProblem(422, { title: 'Not sent', detail: '', errors }));
    return false;
  }
  if (referenceStorms !== undefined) request.certify = { reference_storms: referenceStorms, order: $(`#${prefix}-certify-order`).value };
  return true;
}

/** Bounds of the chosen metamodel's study on the analyses' fields. */
export function configureAnalyses() {
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
  showHeldInputs(study.inputs);
}

/** A field per input other than the wind speed: a box to hold it and its value. */
function showHeldInputs(inputs) {
  const rows = inputs.filter((input) => input.name !== 'wind_speed').map((input) => {
    const [low, high] = input.calibrated_range;
    const field = document.createElement('div');
    field.className = 'field';
    field.innerHTML = '<span class="field check"><input type="checkbox"><label></label></span><input type="number" step="any" disabled><span class="hint"></span><span class="error"></span>';
    const [box, value] = $$('input', field);
    box.id = `explore-hold-${input.name}`;
    value.id = `explore-held-${input.name}`;
    value.dataset.input = input.name;
    value.name = `fixed.${input.name}`;
    $('label', field).setAttribute('for', box.id);
    $('label', field).textContent = `Hold ${input.name}`;
    value.setAttribute('aria-label', `${input.name} held at`);
    const error = $('.error', field);
    error.id = `explore-held-${input.name}-error`;
    error.dataset.errorFor = value.name;
    value.setAttribute('aria-describedby', error.id);
    value.min = low;
    value.max = high;
    value.value = Number(((low + high) / 2).toPrecision(4));
    $('.hint', field).textContent = `${format(low)} to ${format(high)}; ${describeMarginal(input.marginal)}`;
    box.addEventListener('change', () => { value.disabled = !box.checked; });
    return field;
  });
  $('#explore-held').replaceChildren(...rows);
}

/** The inputs held fixed in the explorer, by name, or null after showing what is wrong. */
function heldInputs(form) {
  const fixed = {};
  if ($('#explore-hold-wind').checked) fixed.wind_speed = Number($('#explore-wind').value);
  const errors = [];
  for (const value of $$('#explore-held input[data-input]')) {
    if (value.disabled) continue;
    const number = numberField(value, errors, false);
    if (number === undefined) errors.push({ field: value.name, detail: 'needs a value' });
    else fixed[value.dataset.input] = number;
  }
  if (errors.length) {
    showProblem(form, 'explore', new ApiProblem(422, { title: 'Not sent', detail: '', errors }));
    return null;
  }
  return fixed;
}

export function describeMarginal(marginal) {
  const parameters = Object.entries(marginal).filter(([key]) => key !== 'distribution').map(([key, value]) => `${key} ${format(value)}`);
  return `${marginal.distribution} (${parameters.join(', ')})`;
}

/** The request fields shared by the analyses, or null after showing what is wrong. */
export function analysisRequest(form, prefix) {
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

export function responseLabel(answer) {
  const r = answer.response;
  const where = r.group ? `damper group ${r.group}` : `floor ${r.floor}`;
  return `${r.kind.replace('_', ' ')}, ${where}`;
}

/** Starts an analysis as an operation and gives its answer. */
export async function runAnalysis(form, prefix, path, request) {
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

export async function explore(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'explore');
  if (!request) return;
  const fixed = heldInputs(form);
  if (!fixed) return;
  if (Object.keys(fixed).length) request.fixed = fixed;
  if (!certifyField(form, 'explore', request)) return;
  const answer = await runAnalysis(form, 'explore', 'exceedance', request);
  if (!answer) return;
  const others = Object.entries(fixed).filter(([name]) => name !== 'wind_speed').map(([name, value]) => `${name} ${format(value)}`);
  const wind = [fixed.wind_speed === undefined ? 'wind speed random' : `${fixed.wind_speed} m/s`, ...others].join(', ');
  session.curves.latest = { answer, name: `${responseLabel(answer)}, ${wind}` };
  $('#explore-keep').disabled = false;
  drawExceedance();
}

/** A kept or latest curve's series: a certified one with the metamodel's own curve beside it. */
function curveSeries(curve) {
  const { answer } = curve;
  const c = answer.certification;
  const own = { name: c ? `${curve.name}, certified with ${c.reference_storms} reference storms` : curve.name, x: answer.thresholds, y: answer.probabilities, lower: answer.lower, upper: answer.upper };
  if (!c) return [own];
  return [own, { name: `${curve.name}, metamodel alone`, x: answer.thresholds, y: c.metamodel_probabilities, lower: c.metamodel_lower, upper: c.metamodel_upper }];
}

export function drawExceedance() {
  const { latest, kept } = session.curves;
  if (!latest) return;
  const unit = UNITS[latest.answer.response.kind];
  const series = [...curveSeries(latest), ...(kept ? curveSeries(kept) : [])];
  const chart = Charts.lines({
    title: `P(peak > x), ${latest.answer.samples} storms, ${format(100 * latest.answer.confidence)} % band`,
    xLabel: `${latest.answer.response.kind === 'rms_acceleration' ? 'RMS acceleration' : `peak ${latest.answer.response.kind.replace('_', ' ')}`} x (${unit})`, yLabel: 'probability of exceedance', yLog: true, yMax: 1,
    series,
    describe: (s, i) => `${s.name}: x = ${format(s.x[i])} ${unit}, P = ${format(s.y[i])} [${format(s.lower[i])}, ${format(s.upper[i])}]`,
  });
  $('#explore-chart').replaceChildren(chart);
  const answer = latest.answer;
  $('#explore-table').hidden = false;
  $('#explore-table thead th').textContent = `Threshold (${unit})`;
  const c = answer.certification;
  $('#explore-table tbody').replaceChildren(...answer.thresholds.map((threshold, i) => {
    const row = document.createElement('tr');
    for (const cell of [threshold, answer.probabilities[i], answer.lower[i], answer.upper[i]]) row.insertCell().textContent = format(cell);
    for (const cell of c ? [c.metamodel_probabilities[i], c.mismatch_rate[i]] : ['—', '—']) row.insertCell().textContent = c ? format(cell) : cell;
    return row;
  }));
  // The server's CSV columns: a certified curve adds the metamodel's own probability and the correction.
  const header = `threshold_${UNIT_TAGS[answer.response.kind]},probability,lower,upper${c ? ',metamodel_probability,mismatch_rate,correction,correction_lower,correction_upper' : ''}`;
  const rows = answer.thresholds.map((t, i) => [t, answer.probabilities[i], answer.lower[i], answer.upper[i],
    ...(c ? [c.metamodel_probabilities[i], c.mismatch_rate[i], c.correction[i], c.correction_lower[i], c.correction_upper[i]] : [])].join(','));
  const csv = [header, ...rows].join('\n') + '\n';
  download($('#explore-csv'), 'exceedance.csv', 'text/csv', csv);
  download($('#explore-json'), 'exceedance.json', 'application/json', JSON.stringify(answer, null, 2));
  download($('#explore-svg'), 'exceedance.svg', 'image/svg+xml', Charts.serialize(chart));
}

// ---- Annual curve, fragility, sensitivity ----------------------------------------------------------

export async function hazard(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'hazard');
  if (!request || !hazardFields(form, request) || !certifyField(form, 'hazard', request)) return;
  const answer = await runAnalysis(form, 'hazard', 'hazard', request);
  if (!answer) return;
  const unit = UNITS[answer.response.kind];
  const reliability = answer.reliability;
  $('#hazard-reliability').textContent = reliability
    ? `At the limit ${format(reliability.limit)} ${unit}: ${format(reliability.annual_probability)} a year [${format(reliability.lower)}, ${format(reliability.upper)}], β = ${reliability.beta === null ? (reliability.annual_probability > 0 ? '−∞' : '+∞') : format(reliability.beta)}.`
    : '';
  $('#hazard-chart').replaceChildren(Charts.lines({
    title: `Annual exceedance: ${responseLabel(answer)}`, xLabel: `${answer.response.kind === 'rms_acceleration' ? 'RMS' : 'peak'} x (${unit})`, yLabel: 'annual probability of exceedance', yLog: true,
    series: [
      ...hazardSeries(answer),
      { name: `of which from speeds outside the calibrated ${format(answer.calibrated_wind_range[0])}–${format(answer.calibrated_wind_range[1])} m/s`, x: answer.thresholds, y: answer.probability_beyond_calibrated_range },
    ],
    describe: (s, i) => `x = ${format(s.x[i])} ${unit}: ${format(s.y[i])} a year [${format(s.lower[i])}, ${format(s.upper[i])}], return period ${s.y[i] > 0 && s.y[i] < 1 ? format(-1 / Math.log1p(-s.y[i])) : '–'} years`,
  }));
  $('#hazard-table').hidden = false;
  $('#hazard-table tbody').replaceChildren(...answer.return_levels.map((level) => {
    const row = document.createElement('tr');
    row.insertCell().textContent = `${format(level.return_period_years)} ${level.return_period_years === 1 ? 'year' : 'years'}`;
    for (const value of [level.value, level.lower, level.upper]) row.insertCell().textContent = value === null || value === undefined ? 'beyond the samples' : `${format(value)} ${unit}`;
    return row;
  }));
  $('#hazard-notes').textContent = `Calibrated wind speeds ${format(answer.calibrated_wind_range[0])}–${format(answer.calibrated_wind_range[1])} m/s; the climate's probability outside them ${format(answer.climate_beyond_calibrated_range)}, where the metamodel extrapolates (the second curve: the part of each annual probability from those speeds). Climate: ${describeMarginal(answer.climate)}.${answer.diverged_storms ? ` ${answer.diverged_storms} storms diverged (counted as exceeding every threshold); the first: ${answer.first_diverged.map(describeDiverged).join('; ')}.` : ''}`;
}

/** The annual curve's series: a certified one with the metamodel's own curve beside it. */
function hazardSeries(answer) {
  const c = answer.certification;
  const own = { name: c ? `certified with ${c.reference_storms} reference storms (${c.reference_storms_per_stratum.join(', ')} by stratum)` : `${answer.samples} storms`, x: answer.thresholds, y: answer.annual_probability, lower: answer.lower, upper: answer.upper };
  if (!c) return [own];
  return [own, { name: `metamodel alone, ${answer.samples} storms`, x: answer.thresholds, y: c.metamodel_probabilities, lower: c.metamodel_lower, upper: c.metamodel_upper }];
}

/** A diverged storm with the inputs it was run with. */
export function describeDiverged(storm) {
  return `storm ${storm.storm} (${Object.entries(storm.inputs).map(([name, value]) => `${name} = ${format(value)}`).join(', ')})`;
}

/**
 * The hazard form's own fields into `request`: the site climate from two return-period speeds
 * (both or neither) and the limit; false after showing what is wrong.
 */
function hazardFields(form, request) {
  const errors = [];
  siteClimate('hazard', request, errors);
  const limit = numberField($('#hazard-limit'), errors, false);
  if (limit !== undefined) request.limit = limit;
  if (errors.length) {
    showProblem(form, 'hazard', new ApiProblem(422, { title: 'Not sent', detail: 'some fields need attention', errors }));
    return false;
  }
  return true;
}

/**
 * The site climate of form `prefix` into `request`: a Gumbel law through its 50- and 700-year
 * speeds (both or neither); what is wrong into `errors`.
 */
export function siteClimate(prefix, request, errors) {
  const speeds = ['50', '700'].map((years) => [years, numberField($(`#${prefix}-speed-${years}`), errors, false)]);
  const given = speeds.filter(([, speed]) => speed !== undefined);
  if (given.length === 1) errors.push({ field: 'climate', detail: 'give both speeds, or neither for the metamodel\'s wind law' });
  if (given.length === 2) request.climate = { return_period_speeds: Object.fromEntries(given) };
}

export async function fragility(event) {
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
  if (!certifyField(form, 'fragility', request)) return;
  const answer = await runAnalysis(form, 'fragility', 'fragility', request);
  if (!answer) return;
  const unit = UNITS[answer.response.kind];
  $('#fragility-chart').replaceChildren(Charts.lines({
    title: `Fragility: ${responseLabel(answer)}, ${answer.samples_per_speed} storms per speed`, xLabel: 'wind speed at 10 m (m/s)', yLabel: 'P(peak > threshold | speed)', yMin: 0, yMax: 1,
    series: answer.curves.flatMap((curve) => fragilitySeries(answer, curve, unit)),
    describe: (s, i) => `${s.name}: ${format(s.x[i])} m/s → ${format(s.y[i])} [${format(s.lower[i])}, ${format(s.upper[i])}]`,
  }));
}

/** A threshold's fragility series: a certified one with the metamodel's own beside it. */
function fragilitySeries(answer, curve, unit) {
  const c = curve.certification;
  const fit = curve.lognormal ? ` (θ ${format(curve.lognormal.median_speed)} m/s, β ${format(curve.lognormal.dispersion)})` : '';
  const own = { name: `${format(curve.threshold)} ${unit}${fit}${c ? `, certified with ${c.reference_storms} reference storms per speed` : ''}`, x: answer.wind_speeds, y: curve.probability, lower: curve.lower, upper: curve.upper, points: true };
  if (!c) return [own];
  return [own, { name: `${format(curve.threshold)} ${unit}, metamodel alone`, x: answer.wind_speeds, y: c.metamodel_probabilities, lower: c.metamodel_lower, upper: c.metamodel_upper, points: true }];
}

export async function sensitivity(event) {
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
