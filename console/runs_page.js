// Runs page: the queue and history, a submission form (plan preview first, violations shown
// at their field), and one run's steps, events, progress and ETA, live, with the operator
// actions (pause, resume, abort, skip).
import { get, post, withToken } from './api.js';
import { duration, el, num, replaceChildren, table } from './dom.js';
import { subscribe } from './live.js';

// Stream messages come in bursts (every step of a fast simulated run): re-read at most this often.
const REFRESH_COALESCE_MS = 300;

function stateCell(state) {
  return el('span', { class: `state-${state}` }, state);
}

// A parameter field's text as the JSON value the API takes.
function parseField(spec, text) {
  if (spec.type === 'number') return Number(text);
  if (spec.type === 'string') return text;
  try {
    return JSON.parse(text);
  } catch {
    return spec.type === 'string_list' ? text.split(',').map((s) => s.trim()).filter(Boolean) : text;
  }
}

function fieldText(value) {
  return typeof value === 'string' ? value : JSON.stringify(value);
}

function submitForm(ctx, procedures) {
  const select = el('select', { id: 'procedure' }, procedures.map((p) => el('option', { value: p.name }, p.name)));
  const description = el('p', { class: 'muted' });
  const fields = el('form', { class: 'params', id: 'params' });
  const planBox = el('div', { id: 'plan' });
  const previewButton = el('button', { type: 'button', id: 'preview' }, 'Preview plan');
  const submitButton = el('button', { type: 'button', id: 'submit', class: 'primary', disabled: true }, 'Submit run');
  let inputs = new Map();

  function body() {
    const p = procedures.find((x) => x.name === select.value);
    const parameters = {};
    for (const spec of p.parameters) {
      const text = inputs.get(spec.name).value.trim();
      if (text !== '' && text !== fieldText(spec.default)) parameters[spec.name] = parseField(spec, text);
    }
    return { procedure: p.name, parameters };
  }

  function showFields() {
    const p = procedures.find((x) => x.name === select.value);
    description.textContent = p.description || '';
    inputs = new Map();
    replaceChildren(fields, p.parameters.map((spec) => {
      const input = el('input', { name: spec.name, value: fieldText(spec.default), id: `param-${spec.name}` });
      input.addEventListener('input', () => { submitButton.disabled = true; });
      inputs.set(spec.name, input);
      const range = spec.min !== null || spec.max !== null ? ` [${spec.min ?? ''} .. ${spec.max ?? ''}]` : '';
      return el('label', {}, el('span', {}, spec.name, el('br'), el('span', { class: 'muted' }, spec.type + range)),
        input, el('span', {}, el('span', { class: 'muted' }, spec.description || ''),
          el('div', { class: 'field-error', id: `error-${spec.name}` })));
    }));
    replaceChildren(planBox);
    submitButton.disabled = true;
  }

  // Violations named `--set NAME` (or `parameters.NAME`) go to that field; the rest under the plan.
  function showViolations(violations) {
    for (const input of inputs.values()) input.classList.remove('invalid');
    fields.querySelectorAll('.field-error').forEach((e) => { e.textContent = ''; });
    const general = [];
    for (const v of violations) {
      const m = /^(?:--set |parameters\.)([A-Za-z0-9_]+)/.exec(v.path || '');
      const input = m && inputs.get(m[1]);
      if (input) {
        input.classList.add('invalid');
        fields.querySelector(`#error-${m[1]}`).textContent = v.message;
      } else {
        general.push(`${v.path}: ${v.message}`);
      }
    }
    return general;
  }

  async function preview() {
    ctx.clearMessage();
    submitButton.disabled = true;
    try {
      const plan = await post('/plan', body());
      const general = showViolations(plan.violations);
      const env = plan.envelope || {};
      replaceChildren(planBox,
        el('p', {}, el('b', { id: 'plan-duration' }, duration(plan.total_s)), ` of station time, ${plan.steps.length} steps; `,
          `${env.captures ?? '–'} recordings (${duration(env.capture_s)}).`),
        el('p', { class: 'muted' }, `Envelope: outer ≤ ${num(env.outer?.max_rate_dps)} deg/s, inner ≤ ${num(env.inner?.max_rate_dps)} deg/s, `,
          env.min_temperature_c !== undefined && env.min_temperature_c !== null
            ? `chamber ${num(env.min_temperature_c)} .. ${num(env.max_temperature_c)} °C, ramp ≤ ${num(env.max_ramp_c_per_min)} °C/min`
            : 'chamber untouched'),
        plan.ok ? el('p', { class: 'state-completed', id: 'plan-ok' }, 'Within the station\'s limits.')
          : el('div', { id: 'plan-violations' }, el('p', { class: 'state-failed' }, `${plan.violations.length} violation(s)`),
            general.length ? el('ul', {}, general.map((g) => el('li', {}, g))) : null));
      submitButton.disabled = !plan.ok;
    } catch (e) {
      if (e.body && e.body.violations) {
        const general = showViolations(e.body.violations);
        ctx.showMessage(`${e.message}${general.length ? `: ${general.join('; ')}` : ''}`);
      } else {
        ctx.showMessage(e.message);
      }
    }
  }

  async function submit() {
    try {
      const { id } = await post('/runs', body());
      location.hash = `#/runs/${id}`;
    } catch (e) {
      ctx.showMessage(e.message);
    }
  }

  select.addEventListener('change', showFields);
  previewButton.addEventListener('click', preview);
  submitButton.addEventListener('click', submit);
  showFields();
  return el('section', { class: 'panel' }, el('h3', {}, 'Submit a procedure'),
    el('label', {}, 'Procedure ', select), description, fields, el('p', {}, previewButton, ' ', submitButton), planBox);
}

function runsList(runs, queue) {
  const queued = new Map(queue.map((q) => [q.run, q]));
  return table(['run', 'procedure', 'status', 'steps', 'created', 'ended', ''], runs.map((r) => [
    el('a', { href: `#/runs/${r.id}` }, String(r.id)), r.procedure, stateCell(r.status),
    `${r.steps_done} / ${r.steps_total}`, r.created_utc || '–', r.ended_utc || (queued.has(r.id) ? `queued by ${queued.get(r.id).submitted_by}` : '–'),
    el('a', { href: `#/loop/${r.id}` }, 'loop'),
  ]), { id: 'runs' });
}

function showRunList(ctx) {
  const listBox = el('section', { class: 'panel' }, el('h3', {}, 'Queue and history'), el('div', { id: 'run-list' }, 'Loading…'));
  const formBox = el('div', {}, 'Loading the procedure library…');
  ctx.root.append(el('h2', {}, 'Runs'), el('div', { class: 'grid' }, formBox, listBox));
  let timer = null;
  async function refresh() {
    try {
      const [runs, station] = await Promise.all([get('/runs?limit=50'), get('/station')]);
      replaceChildren(listBox.querySelector('#run-list'), runsList(runs, station.queue));
    } catch (e) {
      ctx.showMessage(`Cannot read the runs: ${e.message}`);
    }
  }
  const later = () => { if (!timer) timer = setTimeout(() => { timer = null; refresh(); }, REFRESH_COALESCE_MS); };
  get('/procedures').then((procs) => replaceChildren(formBox, submitForm(ctx, procs)))
    .catch((e) => ctx.showMessage(`Cannot read the procedure library: ${e.message}`));
  refresh();
  const unsubscribe = [subscribe('run', later), subscribe('step', later)];
  return () => { clearTimeout(timer); unsubscribe.forEach((u) => u()); };
}

// The operator actions, built once per page (a refresh must not eat a reason being typed or
// a click in flight); `current()` is the run as last read.
function actionButtons(ctx, id, current, refresh) {
  const act = (action, body) => async () => {
    ctx.clearMessage();
    try {
      await post(`/runs/${id}/${action}`, body());
      ctx.showMessage(`${action} requested for run ${id}`, 'info');
      refresh();
    } catch (e) {
      ctx.showMessage(e.message);
    }
  };
  const reason = el('input', { id: 'action-reason', placeholder: 'reason (recorded)' });
  const why = () => reason.value.trim() || undefined;
  const skip = el('button', { id: 'skip', onclick: act('skip', () => {
    const step = current()?.current_step?.index;
    return step === undefined ? { reason: why() } : { step, reason: why() };
  }) }, 'Skip step');
  const pause = el('button', { id: 'pause', onclick: act('pause', () => ({})) }, 'Pause at step end');
  const pauseNow = el('button', { id: 'pause-now', onclick: act('pause', () => ({ immediate: true })) }, 'Pause now');
  const resume = el('button', { id: 'resume', onclick: act('resume', () => ({})) }, 'Resume');
  const abort = el('button', { id: 'abort', onclick: act('abort', () => ({ reason: why() })) }, 'Abort');
  const box = el('p', { id: 'actions' }, pause, ' ', pauseNow, ' ', resume, ' ', skip, ' ', abort, ' ', reason);
  return {
    box,
    // Only what applies to the run as it is (the daemon refuses the rest with 409 anyway).
    update(run) {
      const s = run.status;
      skip.textContent = run.current_step ? `Skip step ${run.current_step.index}` : 'Skip step';
      pause.disabled = pauseNow.disabled = s !== 'running';
      resume.disabled = !(s === 'paused' || s === 'held');
      skip.disabled = !(s === 'running' || s === 'paused');
      abort.disabled = !['queued', 'running', 'paused', 'held', 'interrupted'].includes(s);
    },
  };
}

function showRun(ctx, id) {
  const head = el('section', { class: 'panel', id: 'run-head' }, 'Loading…');
  const headBody = el('div', {});
  let lastRun = null;
  let refresh = null;
  const actions = actionButtons(ctx, id, () => lastRun, () => refresh());
  const runLinks = el('p', {}, el('a', { href: `#/loop/${id}` }, 'Fit and diagnose this run'), ' · ',
    el('a', { href: withToken(`/runs/${id}/report`), target: '_blank' }, 'report'), ' · ',
    el('a', { href: withToken(`/runs/${id}/export`) }, 'export (tar)'));
  replaceChildren(head, headBody, actions.box, runLinks);
  const stepsBox = el('section', { class: 'panel' }, el('h3', {}, 'Steps'), el('div', { id: 'run-steps' }));
  const eventsBox = el('section', { class: 'panel' }, el('h3', {}, 'Events'), el('div', { id: 'run-events' }));
  ctx.root.append(el('h2', {}, `Run ${id}`), head, el('div', { class: 'grid' }, stepsBox, eventsBox));
  let timer = null;
  refresh = async () => {
    try {
      const [run, steps, events] = await Promise.all([get(`/runs/${id}`), get(`/runs/${id}/steps`), get(`/runs/${id}/events`)]);
      lastRun = run;
      actions.update(run);
      const live = run.live;
      replaceChildren(headBody,
        el('p', {}, el('b', {}, run.procedure), ' · ', el('span', { id: 'run-status', class: `state-${run.status}` }, run.status),
          ` · ${run.steps_done} / ${run.steps_total} steps`,
          live ? ` · ${live.phase} · station time ${duration(live.station_time_s)}` : '',
          ' · ETA ', el('span', { id: 'run-eta' }, duration(run.eta_s)),
          run.exit_reason ? ` · ${run.exit_reason}` : ''),
        el('div', { class: 'progress' }, el('div', { style: `width: ${(100 * run.progress).toFixed(1)}%` })),
        run.current_step ? el('p', {}, `Current step ${run.current_step.index}: ${run.current_step.label}`) : null);
      replaceChildren(stepsBox.querySelector('#run-steps'), table(['#', 'kind', 'label', 'status', 'attempts', 'reason'],
        steps.map((s) => [String(s.index), s.kind, s.label, stateCell(s.status), String(s.attempts), s.reason || ''])));
      replaceChildren(eventsBox.querySelector('#run-events'), table(['time [s]', 'kind', 'source', 'message'],
        events.map((e) => [num(e.time_s, 6), stateCell(e.kind), e.source, e.message])));
    } catch (e) {
      ctx.showMessage(`Cannot read run ${id}: ${e.message}`);
    }
  };
  const mine = (m) => m.run === id;
  const later = (m) => { if (mine(m) && !timer) timer = setTimeout(() => { timer = null; refresh(); }, REFRESH_COALESCE_MS); };
  refresh();
  const unsubscribe = ['run', 'step', 'event', 'fault'].map((t) => subscribe(t, later));
  // ETA and station time move between step messages: follow them with the telemetry too.
  unsubscribe.push(subscribe('telemetry', later));
  return () => { clearTimeout(timer); unsubscribe.forEach((u) => u()); };
}

export function showRuns(ctx, runId) {
  return runId ? showRun(ctx, runId) : showRunList(ctx);
}
