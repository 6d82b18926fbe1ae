// Operations as a live list: each followed on its event stream to the end, with progress, cancel
// and error text; forms that start one wait for it here.
import { format } from './charts.js';
import { $, ApiProblem, api, clearErrors, session, showProblem } from './client.js';

function describeProgress(progress) {
  if (!progress) return '';
  if (progress.stage === 'experiments') return `reference runs ${progress.done} of ${progress.total}`;
  if (progress.stage === 'samples') return `storms ${progress.done} of ${progress.total}`;
  if (progress.stage === 'reference_storms') return `reference storms ${progress.done} of ${progress.total}`;
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

export async function loadOperations() {
  const { body } = await api('GET', '/v1/operations?limit=20');
  body.operations.slice().reverse().forEach((operation) => {
    showOperation(operation);
    if (!operation.done) follow(operation.id);
  });
  return body.operations;
}

/** Runs `work` (which starts an operation) with a status line, and gives the finished operation's result. */
export async function throughOperation(form, prefix, start) {
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
