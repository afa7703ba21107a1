// The loop, on a completed or imported run: pick catalogue and custom terms, fit on the
// server, see chi2/dof overall and per group of steps, the step residuals coloured by group and
// against the signals, diagnose and add a candidate with one click, and follow the history of
// fits as the falling curve. Every number comes from the daemon (the CLI's code path).
import { get, post, withToken } from './api.js';
import { groupedPoints, logCurve } from './charts.js';
import { el, num, replaceChildren, table } from './dom.js';

// The CLI's default --model (README: the classical model).
const CLASSICAL_MODEL = ['gyro_bias', 'gyro_scale', 'gyro_misalignment', 'earth_rate', 'accel_bias',
  'accel_scale', 'accel_misalignment'];
const CHANNELS = ['gx', 'gy', 'gz', 'ax', 'ay', 'az'];
// What a step's residual can be drawn against when the fit's steps do not carry their signals:
// the time in the run, and series the daemon downsamples (GET /runs/{id}/series).
const STEP_SIGNALS = [
  { name: 'temp_c', label: 'IMU temperature [degC]' },
  { name: 'elapsed', label: 'time in the run [s]' },
  { name: 'table_outer_rate_dps', label: 'outer axis rate [deg/s]' },
  { name: 'table_inner_rate_dps', label: 'inner axis rate [deg/s]' },
  { name: 'table_outer_deg', label: 'outer axis angle [deg]' },
  { name: 'table_inner_deg', label: 'inner axis angle [deg]' },
];
// A diagnosis signal (error-model.md names) as the closest of STEP_SIGNALS.
function stepSignalFor(signal) {
  if (signal.includes('temperature')) return 'temp_c';
  if (signal.includes('elapsed')) return 'elapsed';
  return null;
}
const FINISHED = new Set(['completed', 'aborted', 'failed']);
// Candidates shown at once; the rest (ranked below, usually without evidence) folded away.
const TOP_CANDIDATES = 5;

// "gyro_temp_bias:2" -> {name: "gyro_temp_bias", order: 2}; no suffix -> order null.
function splitTerm(term) {
  const [name, order] = term.split(':');
  return { name, order: order === undefined ? null : Number(order) };
}

function groupFamily(group) {
  return group.split(':')[0];
}

function chooseRun(ctx) {
  const box = el('section', { class: 'panel' }, 'Loading runs…');
  ctx.root.append(el('h2', {}, 'The loop'), el('p', { class: 'muted' }, 'Pick a run with steps to fit (a finished or an imported run).'), box);
  get('/runs?limit=100').then((runs) => {
    const usable = runs.filter((r) => FINISHED.has(r.status) || r.status === 'imported' || r.steps_done > 0);
    replaceChildren(box, usable.length
      ? table(['run', 'procedure', 'status', 'steps', 'ended'], usable.map((r) => [
        el('a', { href: `#/loop/${r.id}` }, String(r.id)), r.procedure, r.status, `${r.steps_done} / ${r.steps_total}`, r.ended_utc || '–']))
      : el('p', {}, 'No run has steps to fit yet.'));
  }).catch((e) => ctx.showMessage(e.message));
  return () => {};
}

export function showLoop(ctx, runId) {
  if (!runId) return chooseRun(ctx);
  const state = { catalogue: null, terms: new Map(), custom: [], fit: null, diagnosis: null, runSteps: [] };
  for (const t of CLASSICAL_MODEL) state.terms.set(t, null);

  const termsBox = el('div', { class: 'terms', id: 'terms' }, 'Loading the catalogue…');
  const customBox = el('textarea', { id: 'custom', rows: 3, cols: 60, placeholder: 'custom terms, one per line: k=gyro.z:force_z^2' });
  const sensorSelect = el('select', { id: 'sensor' }, ['both', 'gyro', 'accel'].map((s) => el('option', { value: s }, s)));
  const whiteNoise = el('input', { type: 'checkbox', id: 'white-noise' });
  const fitButton = el('button', { class: 'primary', id: 'fit' }, 'Fit');
  const diagnoseButton = el('button', { id: 'diagnose' }, 'Diagnose');
  const busy = el('span', { class: 'muted', id: 'busy' });
  const quality = el('section', { class: 'panel', id: 'quality' }, el('p', { class: 'muted' }, 'No fit yet.'));
  const residualControls = el('p', {});
  const residualBox = el('div', { class: 'chart' });
  const signalControls = el('p', {});
  const signalBox = el('div', { class: 'chart' });
  const diagnosisBox = el('section', { class: 'panel', id: 'diagnosis' }, el('h3', {}, 'Diagnosis'),
    el('p', { class: 'muted' }, 'Diagnose to rank the terms the model lacks.'));
  const historyBox = el('div', { class: 'chart' });
  const historyTable = el('div', { id: 'history' });
  const parametersBox = el('section', { class: 'panel', id: 'parameters' });
  const links = el('p', { id: 'run-links' });

  ctx.root.append(
    el('h2', {}, `The loop: run ${runId}`), links,
    el('section', { class: 'panel' }, el('h3', {}, 'Model'), termsBox,
      el('p', {}, el('label', {}, 'Custom terms', el('br'), customBox)),
      el('p', {}, el('label', {}, 'Sensor ', sensorSelect), ' ',
        el('label', {}, whiteNoise, ' white-noise weights (plain weighted least squares)'), ' ',
        fitButton, ' ', diagnoseButton, ' ', busy)),
    el('div', { class: 'grid' }, quality, diagnosisBox),
    el('div', { class: 'grid' },
      el('section', { class: 'panel' }, el('h3', {}, 'Step residuals'), residualControls, residualBox),
      el('section', { class: 'panel' }, el('h3', {}, 'Residual against a signal'), signalControls, signalBox)),
    el('section', { class: 'panel' }, el('h3', {}, 'History of fits'), historyBox, historyTable),
    parametersBox);

  const residualChart = groupedPoints(residualBox, { title: '', xLabel: 'step', yLabel: 'residual / sigma' });
  const signalChart = groupedPoints(signalBox, { title: '', xLabel: 'signal', yLabel: 'residual / sigma' });
  const historyChart = logCurve(historyBox, { title: '', xLabel: 'fit', yLabel: 'chi2/dof', label: 'chi2/dof' });
  const channelSelect = el('select', { id: 'residual-channel' }, CHANNELS.map((c) => el('option', { value: c }, c)));
  const familySelect = el('select', { id: 'group-family' });
  const signalSelect = el('select', { id: 'signal' }, STEP_SIGNALS.map((c) => el('option', { value: c.name }, c.label)));
  replaceChildren(residualControls, el('label', {}, 'Channel ', channelSelect), ' ', el('label', {}, 'coloured by ', familySelect));
  replaceChildren(signalControls, el('label', {}, 'Signal ', signalSelect),
    el('span', { class: 'muted', id: 'signal-note' }));

  function modelTerms() {
    return [...state.terms.entries()].map(([name, order]) => (order ? `${name}:${order}` : name));
  }

  function customTerms() {
    return customBox.value.split('\n').map((s) => s.trim()).filter(Boolean);
  }

  function requestBody() {
    return { model: modelTerms(), custom: customTerms(), sensor: sensorSelect.value, white_noise: whiteNoise.checked };
  }

  function showCatalogue() {
    const entries = state.catalogue.terms.map((term) => {
      const box = el('input', { type: 'checkbox', id: `term-${term.name}`, checked: state.terms.has(term.name) });
      const order = term.ordered ? el('input', { type: 'number', min: 1, max: 5, size: 2, id: `order-${term.name}`,
        value: state.terms.get(term.name) ?? '', placeholder: 'N', title: 'polynomial order in temperature' }) : null;
      box.addEventListener('change', () => {
        if (box.checked) state.terms.set(term.name, order && order.value ? Number(order.value) : null);
        else state.terms.delete(term.name);
      });
      if (order) order.addEventListener('change', () => { if (state.terms.has(term.name)) state.terms.set(term.name, order.value ? Number(order.value) : null); });
      return el('label', {}, box, ' ', el('b', {}, term.name), order ? [' order ', order] : null,
        el('span', { class: 'muted' }, ` ${term.sensor}, ${term.unit}`), el('span', { class: 'effect' }, term.effect));
    });
    replaceChildren(termsBox, entries);
  }

  // A term from diagnose ("gyro_temp_bias" or the next order "gyro_temp_bias:2") into the model.
  function addTerm(term) {
    const { name, order } = splitTerm(term);
    state.terms.set(name, order);
    if (state.catalogue) showCatalogue();
  }

  function addCustom(custom) {
    const lines = customTerms();
    if (!lines.includes(custom)) customBox.value = [...lines, custom].join('\n');
  }

  function residualPoints(fit, family, valueOf) {
    const channel = CHANNELS.indexOf(channelSelect.value);
    const groupOf = new Map();
    for (const g of fit.groups || []) {
      if (groupFamily(g.group) !== family) continue;
      for (const s of g.steps) groupOf.set(s, g.group);
    }
    return fit.steps.map((s) => ({ x: valueOf(s), y: (s.z || s.residual)[channel], group: groupOf.get(s.step) || 'other' }));
  }

  // Each step's value of `signal`, by step index: from the fit when its steps carry their
  // signals; the time in the run from the steps themselves; else the mean of the run's
  // downsampled series (GET /runs/{id}/series, seconds since the run's first sample) over the
  // step's span (steps' clock times shifted to the first step that has samples).
  async function stepSignalValues(fit, signal) {
    if (fit.steps.length && fit.steps[0].signals && signal in fit.steps[0].signals) {
      return new Map(fit.steps.map((s) => [s.step, s.signals[signal]]));
    }
    const fitted = new Set(fit.steps.map((s) => s.step));
    const spans = state.runSteps.filter((s) => fitted.has(s.index) && s.started_clock_s !== null && s.ended_clock_s !== null);
    if (!spans.length) return new Map();
    const t0 = Math.min(...spans.map((s) => s.started_clock_s));
    if (signal === 'elapsed') return new Map(spans.map((s) => [s.index, (s.started_clock_s + s.ended_clock_s) / 2 - t0]));
    const series = await get(`/runs/${runId}/series?signal=${encodeURIComponent(signal)}&max_points=8000`);
    const values = new Map();
    for (const step of spans) {
      const from = step.started_clock_s - t0, to = step.ended_clock_s - t0;
      let sum = 0, n = 0;
      series.t_s.forEach((t, i) => {
        if (t >= from && t <= to && Number.isFinite(series.mean[i])) {
          sum += series.mean[i];
          n += 1;
        }
      });
      if (n) values.set(step.index, sum / n);
    }
    return values;
  }

  function showResiduals() {
    const fit = state.fit;
    if (!fit || fit.method) return;  // a table-free fit has no steps (showTableFreeFit)
    // The signal choices: the fit's own per-step signals when it has them, else STEP_SIGNALS.
    const own = fit.steps.length && fit.steps[0].signals ? Object.keys(fit.steps[0].signals) : [];
    const choices = own.length ? own.map((n) => ({ name: n, label: n })) : STEP_SIGNALS;
    if (signalSelect.options.length !== choices.length) {
      const previous = signalSelect.value;
      replaceChildren(signalSelect, choices.map((c) => el('option', { value: c.name }, c.label)));
      if (choices.some((c) => c.name === previous)) signalSelect.value = previous;
    }
    const family = familySelect.value;
    const groupOrder = [...new Set((fit.groups || []).filter((g) => groupFamily(g.group) === family).map((g) => g.group)), 'other'];
    residualChart.set(residualPoints(fit, family, (s) => s.step), groupOrder);
    const signal = signalSelect.value;
    if (!signal) return;
    stepSignalValues(fit, signal).then((values) => {
      signalChart.set(residualPoints(fit, family, (s) => values.get(s.step)), groupOrder, signal);
      document.getElementById('signal-note').textContent = values.size ? '' : ' (no values of this signal for the fitted steps)';
    }).catch((e) => { document.getElementById('signal-note').textContent = ` (${e.message})`; });
  }

  // A run recorded without a table (an import without `table`): the table-free fit's JSON
  // (method gravity_norm or ferraris). No steps to draw: each static pose's |f| - g and each
  // turn's gravity direction, both over their noise, stand in for the step residuals.
  function showTableFreeFit(fit) {
    const q = fit.quality || {};
    replaceChildren(quality, el('h3', {}, 'Fit quality (no table: orientation unknown)'),
      el('p', {}, 'chi2/dof ', el('span', { class: 'big', id: 'chi2-dof' }, num(fit.chi2_dof, 4)),
        ` (dof ${fit.dof}; method ${fit.method})`),
      el('p', {}, `|f| - g rms ${num(q.rms_norm_residual_mps2 / 9.80665e-3, 3)} mg`,
        q.rms_turn_residual_deg == null ? '' : `, gravity direction after the turns ${num(q.rms_turn_residual_deg, 3)} deg rms`),
      el('p', { class: 'muted' }, `model: ${(fit.model || []).join(', ')}`),
      (fit.notes || []).map((n) => el('p', { class: 'muted' }, n)),
      el('p', { class: 'muted' }, `frame: ${fit.frame}`));
    replaceChildren(parametersBox, el('h3', {}, 'Parameters'),
      table(['parameter', 'value', '1 sigma', 'unit', ''], (fit.parameters || []).map((p) => [p.name, num(p.value, 5),
        p.status === 'estimated' ? num(p.sigma, 3) : '–', p.unit, p.status === 'estimated' ? '' : p.status])));
    replaceChildren(familySelect, el('option', { value: 'pose' }, 'pose'));
    const poses = (fit.accel?.poses || []).map((p) => ({ x: p.interval, y: p.sigma_mg > 0 ? p.residual_mg / p.sigma_mg : 0, group: 'pose |f| - g' }));
    residualChart.set(poses, ['pose |f| - g']);
    const turns = (fit.gyro?.turns || []).map((t, i) => ({ x: i + 1, y: t.sigma_deg > 0 ? t.residual_deg / (Math.SQRT2 * t.sigma_deg) : 0, group: 'turn' }));
    signalChart.set(turns, ['turn'], 'turn');
    document.getElementById('signal-note').textContent = turns.length ? ' gravity direction after each turn, over its noise' : '';
  }

  function showFit(fit) {
    state.fit = fit;
    if (fit.method) {
      showTableFreeFit(fit);
      return;
    }
    const bySensor = fit.by_sensor || {};
    const groups = [...(fit.groups || [])].sort((a, b) => b.chi2_dof - a.chi2_dof);
    replaceChildren(quality, el('h3', {}, 'Fit quality'),
      el('p', {}, 'chi2/dof ', el('span', { class: 'big', id: 'chi2-dof' }, num(fit.chi2_dof, 4)),
        ` (gyro ${num(bySensor.gyro?.chi2_dof, 3)}, accelerometer ${num(bySensor.accel?.chi2_dof, 3)}; dof ${fit.dof})`),
      el('p', { class: 'muted' }, `model: ${(fit.model || []).join(', ')}`),
      groups.length ? table(['group of steps', 'chi2/dof', 'steps'], groups.map((g) => [g.group, num(g.chi2_dof, 3), String(g.steps.length)]), { id: 'groups' }) : null);
    const families = [...new Set(groups.map((g) => groupFamily(g.group)))];
    const previous = familySelect.value;
    replaceChildren(familySelect, families.map((f) => el('option', { value: f }, f)));
    familySelect.value = families.includes(previous) ? previous : (groups[0] ? groupFamily(groups[0].group) : '');
    replaceChildren(parametersBox, el('h3', {}, 'Parameters'),
      table(['parameter', 'value', '1 sigma', 'unit'], (fit.parameters || []).map((p) => [p.name, num(p.value, 5), num(p.sigma, 3), p.unit])),
      (fit.unidentifiable || []).length ? [el('h3', {}, 'Not determined by this run'),
        table(['parameter', 'why'], fit.unidentifiable.map((u) => [u.name, u.reason]))] : null);
    showResiduals();
  }

  function showDiagnosis(d) {
    state.diagnosis = d;
    const recommended = d.recommended || '';
    const candidates = (d.candidates || []).map((c) => [
      c.term === recommended ? el('b', {}, c.term, ' (recommended)') : c.term, num(c.delta_bic, 4),
      c.delta_bic_against_wander == null ? '–' : num(c.delta_bic_against_wander, 4), num(c.p_value, 2), num(c.chi2_dof_after, 4),
      c.explanation || '', el('button', { id: `add-${c.term.replace(':', '-')}`, class: c.term === recommended ? 'primary' : '',
        onclick: () => addAndFit(() => addTerm(c.term)) }, 'Add and fit')]);
    const suggestions = (d.suggestions || []).map((s, i) => [s.custom, num(s.delta_bic, 4), num(s.chi2_dof_after, 4),
      s.held_out ? `${s.held_out.method}: ${num(s.held_out.chi2_dof_before, 3)} → ${num(s.held_out.chi2_dof_after, 3)}` : '',
      s.explanation || '', el('button', { id: `add-suggestion-${i}`, onclick: () => addAndFit(() => addCustom(s.custom)) }, 'Add and fit')]);
    replaceChildren(diagnosisBox, el('h3', {}, 'Diagnosis'),
      el('p', { id: 'advice' }, d.advice || ''),
      el('p', {}, d.explained === false ? el('span', { class: 'state-failed' }, 'No catalogue term explains the residual.') : null),
      candidates.length ? table(['candidate', 'ΔBIC', 'ΔBIC vs wander', 'p', 'chi2/dof after', 'effect', ''], candidates.slice(0, TOP_CANDIDATES), { id: 'candidates' }) : el('p', {}, 'No candidate term left to test.'),
      candidates.length > TOP_CANDIDATES ? el('details', {}, el('summary', {}, `${candidates.length - TOP_CANDIDATES} more candidates, ranked lower`),
        table(['candidate', 'ΔBIC', 'ΔBIC vs wander', 'p', 'chi2/dof after', 'effect', ''], candidates.slice(TOP_CANDIDATES), { id: 'more-candidates' })) : null,
      suggestions.length ? [el('h3', {}, 'Custom terms tried'), table(['custom term', 'ΔBIC vs wander', 'chi2/dof after', 'held out', 'why', ''], suggestions, { id: 'suggestions' })] : null,
      (d.signals || []).length ? [el('h3', {}, 'Signals the residual follows'),
        table(['signal', 'channel', 'correlation'], d.signals.slice(0, 8).map((s) => [s.signal, s.channel, num(s.correlation, 3)]))] : null);
    // Draw the residual against the signal it follows most, when the page can show that one.
    const top = (d.signals || [])[0];
    if (top) {
      const base = top.signal.replace(/^(abs|sq)\(|\)$|\^2$/g, '');
      const choice = [...signalSelect.options].some((o) => o.value === base) ? base : stepSignalFor(base);
      if (choice) signalSelect.value = choice;
    }
    showResiduals();
  }

  async function showHistory() {
    try {
      const answer = await get(`/runs/${runId}/history`);
      const fits = Array.isArray(answer) ? answer : answer.fits || [];
      const chi = fits.map((f) => f.chi2_dof);
      historyChart.set(fits.map((_, i) => i + 1), chi);
      replaceChildren(historyTable, table(['fit', 'command', 'chi2/dof', 'parameters', 'model'], fits.map((f, i) => [
        String(i + 1), f.command, num(f.chi2_dof, 4), String(f.parameters ?? ''),
        [f.model, ...(f.custom_terms || []).map((c) => `(${c})`)].join(' ')])));
    } catch (e) {
      replaceChildren(historyTable, el('p', { class: 'muted' }, `History unavailable: ${e.message}`));
    }
  }

  async function withBusy(label, work) {
    ctx.clearMessage();
    fitButton.disabled = diagnoseButton.disabled = true;
    busy.textContent = label;
    const started = performance.now();
    try {
      await work();
      busy.textContent = `${label.replace('…', '')} took ${((performance.now() - started) / 1000).toFixed(2)} s`;
    } catch (e) {
      busy.textContent = '';
      ctx.showMessage(e.message);
    } finally {
      fitButton.disabled = diagnoseButton.disabled = false;
    }
  }

  const runFit = () => withBusy('fitting…', async () => {
    const body = requestBody();
    showFit(await post(`/runs/${runId}/fits`, body));
    // The report of the model just fitted (GET /runs/{id}/report takes it as ?model=&custom=).
    const report = document.getElementById('report-link');
    if (report) {
      const query = new URLSearchParams({ model: body.model.join(','), sensor: body.sensor });
      body.custom.forEach((c) => query.append('custom', c));
      report.href = withToken(`/runs/${runId}/report?${query}`);
      report.textContent = 'HTML report of this model';
    }
    // A diagnosis of another model no longer describes this fit: say so rather than hide it.
    const stale = state.diagnosis && JSON.stringify(state.diagnosis.model) !== JSON.stringify(state.fit.model);
    diagnosisBox.classList.toggle('stale', Boolean(stale));
    const note = diagnosisBox.querySelector('#stale-note');
    if (stale && !note) diagnosisBox.querySelector('h3').after(el('p', { id: 'stale-note', class: 'muted' }, 'This diagnosis is of the previous model: diagnose again.'));
    if (!stale && note) note.remove();
    await showHistory();
  });
  const runDiagnose = () => withBusy('diagnosing…', async () => showDiagnosis(await post(`/runs/${runId}/diagnose`, requestBody())));
  function addAndFit(change) {
    change();
    runFit();
  }

  fitButton.addEventListener('click', runFit);
  diagnoseButton.addEventListener('click', runDiagnose);
  channelSelect.addEventListener('change', showResiduals);
  familySelect.addEventListener('change', showResiduals);
  signalSelect.addEventListener('change', showResiduals);

  get('/catalogue').then((catalogue) => {
    state.catalogue = catalogue;
    showCatalogue();
  }).catch((e) => {
    replaceChildren(termsBox, el('p', { class: 'state-failed' }, `The catalogue is unavailable: ${e.message}`));
  });
  // The run's header, then its calibration records into it (the header must exist first).
  get(`/runs/${runId}`).then((run) => {
    const records = el('span', { id: 'calibrations' }, 'calibration records: …');
    replaceChildren(links, `${run.procedure} · ${run.status} · `, el('a', { href: `#/runs/${runId}` }, 'steps and events'), ' · ',
      el('a', { href: withToken(`/runs/${runId}/report`), target: '_blank', id: 'report-link' }, 'HTML report'), ' · ', records);
    return get(`/runs/${runId}/calibrations`).then((answer) => {
      const list = Array.isArray(answer) ? answer : answer.calibrations || [];
      replaceChildren(records, 'calibration records: ', list.length
        ? list.map((r, i) => [i ? ', ' : '', el('a', { href: withToken(`/calibrations/${r.id}`), target: '_blank' }, `#${r.id} ${r.imu || ''}`)])
        : 'none');
    }).catch(() => replaceChildren(records, 'calibration records: unavailable'));
  }).catch((e) => ctx.showMessage(e.message));
  get(`/runs/${runId}/steps`).then((steps) => { state.runSteps = steps; }).catch(() => {});
  showHistory();
  return () => [residualChart, signalChart, historyChart].forEach((c) => c.destroy());
}
