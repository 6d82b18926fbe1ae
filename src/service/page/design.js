// What a design office signs and how it sizes its dampers: the serviceability check (criteria from
// the built-ins or a JSON box, a table of verdicts, the profiles over their limits) and the sweep
// of one input (the T-year level at each value with its band).
import * as Charts from './charts.js';
import { format } from './charts.js';
import { $, $$, ApiProblem, UNITS, clearErrors, numberField, session, showProblem } from './client.js';
import { analysisRequest, describeDiverged, describeMarginal, responseLabel, runAnalysis, siteClimate } from './analyses.js';

/** Standard gravity (m/s²): a limit in milli-g is converted with it. */
const STANDARD_GRAVITY = 9.80665;

/** The criteria typed as JSON, accelerations' `limit_milli_g` converted to SI; what is wrong into `errors`. */
function typedCriteria(errors) {
  const text = $('#serviceability-criteria').value.trim();
  if (!text) return [];
  let criteria;
  try {
    criteria = JSON.parse(text);
  } catch (failure) {
    errors.push({ field: 'criteria', detail: `is not JSON: ${failure.message}` });
    return [];
  }
  if (!Array.isArray(criteria)) {
    errors.push({ field: 'criteria', detail: 'must be a JSON array of criteria' });
    return [];
  }
  return criteria.map((criterion) => {
    if (criterion === null || typeof criterion !== 'object' || !('limit_milli_g' in criterion)) return criterion;
    const { limit_milli_g: milliG, ...rest } = criterion;
    return { ...rest, limit: (Number(milliG) * STANDARD_GRAVITY) / 1000 };
  });
}

export async function serviceability(event) {
  event.preventDefault();
  const form = event.target;
  clearErrors(form);
  if (!session.current) {
    $('#serviceability-error').textContent = 'Choose a metamodel first (under Metamodels).';
    return;
  }
  const errors = [];
  const request = {};
  siteClimate('serviceability', request, errors);
  for (const name of ['samples', 'seed']) {
    const value = numberField($(`#serviceability-${name}`), errors, true);
    if (value !== undefined) request[name] = value;
  }
  request.criteria = [...$$('#serviceability-form input[type=checkbox]:checked').map((box) => box.value), ...typedCriteria(errors)];
  if (!request.criteria.length) errors.push({ field: 'criteria', detail: 'choose a built-in criterion or type one' });
  if (errors.length) {
    showProblem(form, 'serviceability', new ApiProblem(422, { title: 'Not sent', detail: 'some fields need attention', errors }));
    return;
  }
  const answer = await runAnalysis(form, 'serviceability', 'serviceability', request);
  if (!answer) return;
  $('#serviceability-table').hidden = false;
  $('#serviceability-table tbody').replaceChildren(...answer.criteria.map((c) => {
    const row = document.createElement('tr');
    const level = (x) => (x === null || x === undefined ? 'beyond the samples' : `${format(x)} ${c.unit}`);
    const cells = [
      `${c.name} (${c.statistic === 'rms' ? 'RMS ' : 'peak '}${c.response.replace('_', ' ')})`,
      `${format(c.return_period_years)} years`,
      String(c.governing_floor),
      level(c.value),
      `[${level(c.lower)}, ${level(c.upper)}]`,
      `${format(c.limit)} ${c.unit}`,
      c.utilisation === null ? '–' : format(c.utilisation),
      c.verdict + (c.strength ? ` (P ${format(c.strength.annual_probability)} a year against ${format(c.strength.target_annual_probability)}, β ${c.strength.beta === null ? '–' : format(c.strength.beta)})` : ''),
    ];
    for (const text of cells) row.insertCell().textContent = text;
    row.dataset.verdict = c.verdict;
    return row;
  }));
  const ratio = (values, limits) => values.map((v, i) => (v === null ? NaN : v / limits[i]));
  $('#serviceability-chart').replaceChildren(Charts.lines({
    title: `T-year level over its limit at every floor, ${answer.samples} storms`, xLabel: 'floor', yLabel: 'level / limit', yMin: 0,
    series: [
      ...answer.criteria.map((c) => ({ name: `${c.name}: ${c.verdict}`, x: c.profile.floors, y: ratio(c.profile.values, c.profile.limits), lower: ratio(c.profile.lower, c.profile.limits), upper: ratio(c.profile.upper, c.profile.limits), points: true })),
      { name: 'the limit', x: answer.criteria[0].profile.floors, y: answer.criteria[0].profile.floors.map(() => 1) },
    ],
    describe: (s, i) => `${s.name}, floor ${s.x[i]}: ${format(s.y[i])}${s.lower ? ` [${format(s.lower[i])}, ${format(s.upper[i])}]` : ''}`,
  }));
  $('#serviceability-notes').textContent = `Bands at ${answer.confidence}; a verdict is pass where every judged floor's band lies within its limit, fail where one lies wholly beyond. Climate: ${describeMarginal(answer.climate)}; its probability outside the calibrated ${format(answer.calibrated_wind_range[0])}–${format(answer.calibrated_wind_range[1])} m/s is ${format(answer.climate_beyond_calibrated_range)}.${answer.diverged_storms ? ` ${answer.diverged_storms} storms diverged (counted as exceeding); the first: ${answer.first_diverged.map(describeDiverged).join('; ')}.` : ''}`;
}

/** The sweep's input choices: the chosen metamodel's random inputs other than the wind speed. */
export function configureSweep() {
  const random = session.current.study.inputs.filter((input) => input.name !== 'wind_speed' && input.marginal.distribution !== 'constant');
  $('#sweep-input').replaceChildren(...random.map((input) => {
    const option = document.createElement('option');
    option.value = input.name;
    option.textContent = `${input.name} (${describeMarginal(input.marginal)})`;
    return option;
  }));
}

export async function sweep(event) {
  event.preventDefault();
  const form = event.target;
  const request = analysisRequest(form, 'sweep');
  if (!request) return;
  const errors = [];
  request.input = $('#sweep-input').value;
  request.values = $('#sweep-values').value.split(/[,\s]+/).filter(Boolean).map(Number);
  if (!request.values.length || request.values.some((v) => !Number.isFinite(v))) errors.push({ field: 'values', detail: 'must be numbers separated by commas' });
  const period = numberField($('#sweep-period'), errors, false);
  if (period !== undefined) request.return_period_years = period;
  if (errors.length) {
    showProblem(form, 'sweep', new ApiProblem(422, { title: 'Not sent', detail: 'some fields need attention', errors }));
    return;
  }
  const answer = await runAnalysis(form, 'sweep', 'sweep', request);
  if (!answer) return;
  const unit = UNITS[answer.response.kind];
  const at = (key) => answer.results.map((p) => (p[key] === null ? NaN : p[key]));
  const [low, high] = answer.calibrated_input_range;
  $('#sweep-chart').replaceChildren(Charts.lines({
    title: `${format(answer.return_period_years)}-year ${responseLabel(answer)} over ${answer.input}, ${answer.samples} storms at every value (calibrated ${format(low)} to ${format(high)})`,
    xLabel: answer.input, yLabel: `${format(answer.return_period_years)}-year level (${unit})`,
    series: [{ name: `level with its band at ${answer.confidence}`, x: answer.results.map((p) => p.input_value), y: at('level'), lower: at('lower'), upper: at('upper'), points: true }],
    describe: (s, i) => `${answer.input} = ${format(s.x[i])}: ${format(s.y[i])} ${unit} [${format(s.lower[i])}, ${format(s.upper[i])}]`,
  }));
}
