// The factory line: the lot (#/lot, or #/lot/YYYY-MM-DD for the units calibrated since that
// day) with its yield and verdicts, each parameter's distribution with the units flagged against
// their siblings, and an individuals control chart per parameter; and one unit looked up by its
// serial (#/units/SERIAL): its records newest first, their verdicts, the one in force, and each
// record's certificate. Every number comes from the daemon (GET /lot, GET
// /units/{serial}/calibrations: the code of `calstand lot` and `calstand calibrations`).
import { get, withToken } from './api.js';
import { controlChart } from './charts.js';
import { el, num, replaceChildren, table } from './dom.js';

// Significant digits of the statistics: enough to tell siblings apart (ppm-level scale factors).
const DIGITS = 5;

function verdictCell(verdict) {
  return verdict ? el('span', { class: `verdict-${verdict}` }, verdict) : el('span', { class: 'muted' }, 'not judged');
}

function unitLink(serial) {
  return el('a', { href: `#/units/${encodeURIComponent(serial)}` }, serial);
}

function certificateLink(id) {
  // Opened by the browser in a tab: no Authorization header, so the token rides in the query.
  return el('a', { href: withToken(`/calibrations/${id}/certificate`), target: '_blank', class: 'certificate' }, 'certificate');
}

/** The serial field that opens a unit's page; on both pages. */
function lookupForm(serial = '') {
  const field = el('input', { id: 'serial', value: serial, placeholder: 'serial, e.g. FX-1003', size: 24 });
  const open = () => {
    const wanted = field.value.trim();
    if (wanted) location.hash = `#/units/${encodeURIComponent(wanted)}`;
  };
  field.addEventListener('keydown', (e) => { if (e.key === 'Enter') open(); });
  return el('section', { class: 'panel' }, el('h3', {}, 'Look up a unit'),
    el('p', {}, el('label', {}, 'Serial ', field), ' ', el('button', { id: 'lookup', onclick: open }, 'Look up')),
    el('p', { class: 'muted' }, 'Its calibration records newest first, their verdicts, the one in force, and each one\'s certificate.'));
}

function outliersCell(p) {
  if (!p.outliers.length) return '–';
  return el('span', { class: 'flagged' }, p.outliers.map((o, i) => [i ? ', ' : '', unitLink(o.serial),
    ` (z ${o.robust_z === null ? '∞' : o.robust_z.toFixed(1)}${o.verdict ? `, ${o.verdict}` : ''})`]));
}

function showLotAnswer(lot, boxes) {
  const v = lot.verdicts;
  replaceChildren(boxes.summary,
    el('p', {}, el('b', { id: 'lot-size' }, String(lot.units.length)), ` unit${lot.units.length === 1 ? '' : 's'}`,
      lot.since ? ` calibrated since ${lot.since}` : ' (every record)', ', each with its newest record',
      lot.records_without_serial ? `; ${lot.records_without_serial} record(s) without a serial left out` : '', '.'),
    el('p', { id: 'verdicts' }, el('span', { class: 'verdict-pass' }, `${v.pass} pass`), ', ',
      el('span', { class: 'verdict-fail' }, `${v.fail} fail`), ', ',
      el('span', { class: 'verdict-indeterminate' }, `${v.indeterminate} indeterminate`), ', ',
      `${v.not_judged} not judged`),
    el('p', {}, 'Yield ', el('span', { class: 'big', id: 'yield' }, lot.yield === null ? '–' : `${(100 * lot.yield).toFixed(1)} %`),
      el('span', { class: 'muted' }, ' passes over judged units')));
  replaceChildren(boxes.units, lot.units.length
    ? table(['serial', 'slot', 'run', 'record', 'calibrated (UTC)', 'verdict', ''], lot.units.map((u) => [
      unitLink(u.serial), u.device, el('a', { href: `#/runs/${u.run}` }, String(u.run)),
      el('a', { href: withToken(`/calibrations/${u.calibration}`), target: '_blank' }, `#${u.calibration}`),
      u.created_utc, verdictCell(u.verdict), certificateLink(u.calibration)]), { id: 'lot-units' })
    : el('p', {}, 'No unit with a serial was calibrated', lot.since ? ` since ${lot.since}` : '', '.'));
  const n = (x) => num(x, DIGITS);
  replaceChildren(boxes.parameters, lot.parameters.length
    ? table(['parameter', 'unit', 'n', 'mean', 'std', 'median', 'min', 'max', 'outliers (robust z > 4)'],
      lot.parameters.map((p) => el('tr', { dataset: { parameter: p.name } }, [p.name, p.unit, String(p.n), n(p.mean), n(p.std),
        n(p.median), n(p.min), n(p.max), outliersCell(p)].map((c, i) => el('td', { class: i >= 2 && i <= 7 ? 'num' : null }, c)))),
      { id: 'lot-parameters' })
    : el('p', { class: 'muted' }, 'No parameters: no unit in this lot.'));
  // The numbers' headers line up with them (right).
  boxes.parameters.querySelectorAll('th').forEach((th, i) => th.classList.toggle('num', i >= 2 && i <= 7));
  // One chart per parameter; the previous lot's are released first.
  for (const chart of boxes.charts) chart.destroy();
  boxes.charts = [];
  replaceChildren(boxes.chartGrid);
  for (const p of lot.parameters) {
    const box = el('div', { class: 'chart control-chart', dataset: { parameter: p.name } });
    boxes.chartGrid.append(el('section', { class: 'panel' }, el('h3', {}, `${p.name} `, el('span', { class: 'muted' }, `[${p.unit}]`)), box));
    boxes.charts.push(controlChart(box, p));
  }
}

/** #/lot[/YYYY-MM-DD]: the lot since a date (every record without one). */
export function showLot(ctx, since = '') {
  const sinceField = el('input', { type: 'date', id: 'since', value: since });
  const everyRecord = el('button', { id: 'every-record' }, 'Every record');
  const boxes = {
    summary: el('div', { id: 'lot-summary' }, 'Reading the lot…'),
    units: el('div', {}),
    parameters: el('div', {}),
    chartGrid: el('div', { class: 'grid', id: 'control-charts' }),
    charts: [],
  };
  ctx.root.append(el('h2', {}, 'Lot'),
    el('div', { class: 'grid' },
      el('section', { class: 'panel' }, el('h3', {}, 'Yield'),
        el('p', {}, el('label', {}, 'Calibrated since ', sinceField), ' ', everyRecord), boxes.summary),
      lookupForm()),
    el('section', { class: 'panel' }, el('h3', {}, 'Units'), boxes.units),
    el('section', { class: 'panel' }, el('h3', {}, 'Parameters across the lot'),
      el('p', { class: 'muted' }, 'A unit more than 4 robust sigmas (1.4826 MAD) from the lot\'s median is flagged, '
        + 'even when it passes: it is unlike its siblings (nobody is flagged below three units).'), boxes.parameters),
    el('h3', {}, 'Control charts'),
    el('p', { class: 'muted' }, 'Individuals charts: each unit\'s value in calibration order, the lot mean, and the '
      + '3-sigma limits from the mean moving range between consecutive units; flagged units ringed.'),
    boxes.chartGrid);
  // The date lives in the address, so that a lot can be linked and Back returns to it.
  sinceField.addEventListener('change', () => {
    location.hash = sinceField.value ? `#/lot/${sinceField.value}` : '#/lot';
  });
  everyRecord.addEventListener('click', () => { location.hash = '#/lot'; });
  get(`/lot${since ? `?since=${encodeURIComponent(since)}` : ''}`)
    .then((lot) => showLotAnswer(lot, boxes))
    .catch((e) => {
      replaceChildren(boxes.summary, el('p', { class: 'state-failed' }, 'The lot is unavailable.'));
      ctx.showMessage(e.message);
    });
  return () => boxes.charts.forEach((c) => c.destroy());
}

/** #/units/SERIAL: one unit's records newest first, with the one in force. */
export function showUnit(ctx, serial) {
  const records = el('section', { class: 'panel' }, el('h3', {}, 'Calibration records, newest first'),
    el('div', { id: 'unit-records' }, 'Reading the records…'));
  const inForce = el('p', { id: 'in-force' });
  ctx.root.append(el('h2', {}, 'Unit ', el('span', { id: 'unit-serial' }, serial)),
    el('p', {}, el('a', { href: '#/lot' }, '← the lot')), inForce, records, lookupForm(serial));
  get(`/units/${encodeURIComponent(serial)}/calibrations`).then((answer) => {
    const list = answer.calibrations;
    const current = list.find((r) => r.in_force);
    replaceChildren(inForce, current
      ? ['In force: ', el('b', {}, `record #${current.id}`), ` of run ${current.run} (${current.created_utc}), `,
        verdictCell(current.verdict), ' · ', certificateLink(current.id)]
      : el('span', { class: 'state-failed' }, list.length
        ? 'No record in force: every record failed its acceptance or was indeterminate.'
        : `No calibration of unit ${serial}.`));
    if (!list.length) {
      replaceChildren(records.querySelector('#unit-records'), el('p', { class: 'muted' }, 'None.'));
      return;
    }
    replaceChildren(records.querySelector('#unit-records'), table(
      ['record', 'run', 'slot', 'created (UTC)', 'model', 'verdict', 'specification', '', ''],
      list.map((r) => el('tr', { class: r.in_force ? 'in-force' : null, dataset: { record: r.id } }, [
        el('a', { href: withToken(`/calibrations/${r.id}`), target: '_blank' }, `#${r.id}`),
        el('a', { href: `#/runs/${r.run}` }, String(r.run)), r.imu, r.created_utc, r.model, verdictCell(r.verdict),
        r.spec || '–', r.in_force ? el('b', {}, 'in force') : '', certificateLink(r.id)].map((c) => el('td', {}, c)))),
      { id: 'records' }));
  }).catch((e) => {
    replaceChildren(records.querySelector('#unit-records'), el('p', { class: 'state-failed' }, 'The records are unavailable.'));
    ctx.showMessage(e.message);
  });
  return () => {};
}
