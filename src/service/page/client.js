// The page's API client: requests with the key, refusals shown next to the fields they name, and
// a check of JSON against the API's own schemas before it is sent.

export const $ = (selector, root = document) => root.querySelector(selector);
export const $$ = (selector, root = document) => Array.from(root.querySelectorAll(selector));

/** What the page holds for this browser tab. */
export const session = {
  /** The API key, kept for the browser session only. */
  key: sessionStorage.getItem('windmeta.key') || '',
  /** The chosen metamodel: {id, metamodel, study}. */
  current: null,
  /** The server's built-in studies. */
  presets: [],
  /** The API description, read once for the advanced box's checks. */
  spec: null,
  /** Operations on the page by id: {operation, row, waiters, followed}. */
  operations: new Map(),
  /** The explorer's curves: the latest and the one kept for comparison. */
  curves: { latest: null, kept: null },
};

export const UNITS = { displacement: 'm', drift: 'm', acceleration: 'm/s²', rms_acceleration: 'm/s²', damper_force: 'N', damper_stroke: 'm' };
export const UNIT_TAGS = { displacement: 'm', drift: 'm', acceleration: 'm_s2', rms_acceleration: 'm_s2', damper_force: 'n', damper_stroke: 'm' };

/** A refused request: the problem document the API sent. */
export class ApiProblem extends Error {
  constructor(status, problem) {
    super(problem.detail || problem.title || `HTTP ${status}`);
    this.status = status;
    this.problem = problem;
  }
}

export async function api(method, path, body, headers = {}) {
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

/** The key form; `onKey` runs once a key has been entered. */
export function setUpKey(onKey) {
  if (session.key) {
    $('#key-form').hidden = false;
    $('#api-key').value = session.key;
  }
  $('#key-form').addEventListener('submit', (event) => {
    event.preventDefault();
    session.key = $('#api-key').value.trim();
    sessionStorage.setItem('windmeta.key', session.key);
    $('#key-status').textContent = '';
    onKey();
  });
}

// ---- Errors next to their fields ---------------------------------------------------------------

export function clearErrors(form) {
  $$('.error', form).forEach((node) => { node.textContent = ''; });
  $$('[aria-invalid]', form).forEach((node) => node.removeAttribute('aria-invalid'));
}

/**
 * Shows a problem's field errors next to their fields (the slot `[data-error-for=<field>]` of a
 * generated field, else `prefix-<field>-error`) and the rest above the form.
 */
export function showProblem(form, prefix, error) {
  const general = $(`#${prefix}-error`);
  if (!(error instanceof ApiProblem)) {
    general.textContent = String(error);
    return;
  }
  const fields = error.problem.errors || [];
  const unplaced = [];
  for (const { field, detail } of fields) {
    const name = field.split(/[.[]/)[0];
    const generated = $(`[data-error-for="${CSS.escape(field)}"]`, form);
    const slot = generated || $(`#${prefix}-${name}-error`);
    const input = generated ? $(`[name="${CSS.escape(field)}"]`, form) : $(`#${prefix}-${name}`);
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
export function numberField(input, errors, integer) {
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

export async function apiSpec() {
  if (!session.spec) session.spec = (await api('GET', '/openapi.json')).body;
  return session.spec;
}

/** The errors of `value` against an OpenAPI schema (the parts of JSON Schema the API uses). */
export function checkSchema(schema, value, path, spec, errors) {
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
