// The fleet (#/fleet, or #/fleet/YYYY-MM-DD for what was made since that day), read-only: the
// central database calstandd was started with (--fleet URL, docs/fleet.md): its stations with
// their last run, each calibration parameter's spread per station (every unit's newest record),
// the units with the stations that measured them, and the newest records across the fleet.
// Every number comes from the daemon (GET /fleet, /fleet/parameters, /fleet/units,
// /fleet/calibrations: the code of `calstand fleet`). Nothing here changes anything.
import { get } from './api.js';
import { el, num, replaceChildren, table } from './dom.js';

const DIGITS = 5;
/** The newest records shown: the page is an overview, `calstand fleet calibrations` has all. */
const NEWEST_RECORDS = 50;

function verdict(v) {
  return v ? el('span', { class: `verdict-${v}` }, v) : el('span', { class: 'muted' }, 'not judged');
}

function stationsTable(answer) {
  if (!answer.stations.length) return el('p', { class: 'muted' }, 'No station has synced yet.');
  return table(['station', 'runs', 'units', 'records', 'last run (UTC)', 'its status', 'uuid'],
    answer.stations.map((s) => el('tr', { dataset: { station: s.name } }, [s.name, String(s.runs), String(s.units),
      String(s.calibrations), s.last_run_utc || '–', s.last_run_status || '–', el('span', { class: 'muted' }, s.uuid)]
      .map((c) => el('td', {}, c)))), { id: 'fleet-stations' });
}

function parametersTable(answer) {
  if (!answer.parameters.length) return el('p', { class: 'muted' }, 'No calibration record with a serial.');
  const rows = [];
  for (const p of answer.parameters) {
    p.stations.forEach((s, i) => rows.push(el('tr', { dataset: { parameter: p.name, station: s.station } }, [
      i === 0 ? p.name : '', i === 0 ? p.unit : '', s.station, String(s.n), num(s.mean, DIGITS), num(s.std, DIGITS),
      num(s.min, DIGITS), num(s.max, DIGITS)].map((c, k) => el('td', { class: k >= 3 ? 'num' : null }, c)))));
  }
  return table(['parameter', 'unit', 'station', 'units', 'mean', 'std', 'min', 'max'], rows, { id: 'fleet-parameters' });
}

function unitsTable(answer) {
  if (!answer.units.length) return el('p', { class: 'muted' }, 'No unit with a serial.');
  return table(['serial', 'model', 'runs', 'records', 'verdict of the newest', 'last run (UTC)', 'stations'],
    answer.units.map((u) => el('tr', { dataset: { serial: u.serial } }, [u.serial, u.model, String(u.runs),
      String(u.calibrations), verdict(u.latest_verdict), u.last_run_utc, u.stations.join(', ')]
      .map((c) => el('td', {}, c)))), { id: 'fleet-units' });
}

function recordsTable(answer) {
  const list = answer.calibrations.slice(0, NEWEST_RECORDS);
  if (!list.length) return el('p', { class: 'muted' }, 'No calibration record.');
  return table(['station', 'run', 'slot', 'serial', 'created (UTC)', 'verdict', ''],
    list.map((r) => el('tr', { class: r.in_force ? 'in-force' : null }, [r.station, String(r.run), r.imu,
      r.serial || '–', r.created_utc, verdict(r.verdict), r.in_force ? el('b', {}, 'in force') : '']
      .map((c) => el('td', {}, c)))), { id: 'fleet-records' });
}

/** #/fleet[/YYYY-MM-DD] */
export function showFleet(ctx, since = '') {
  const sinceField = el('input', { type: 'date', id: 'fleet-since', value: since });
  const boxes = {
    stations: el('div', {}, 'Reading the fleet…'),
    parameters: el('div', {}),
    units: el('div', {}),
    records: el('div', {}),
  };
  ctx.root.append(el('h2', {}, 'Fleet'),
    el('p', { class: 'muted' }, 'The central database, read-only: what the stations have synced (ended runs, their ',
      'records and verdicts). ', el('label', {}, 'Made since ', sinceField)),
    el('section', { class: 'panel' }, el('h3', {}, 'Stations'), boxes.stations),
    el('section', { class: 'panel' }, el('h3', {}, 'Each parameter across the stations'),
      el('p', { class: 'muted' }, 'Every unit counted once, with its newest record, under the station that made it.'),
      boxes.parameters),
    el('section', { class: 'panel' }, el('h3', {}, 'Units'), boxes.units),
    el('section', { class: 'panel' }, el('h3', {}, `Newest records (at most ${NEWEST_RECORDS})`), boxes.records));
  sinceField.addEventListener('change', () => {
    location.hash = sinceField.value ? `#/fleet/${sinceField.value}` : '#/fleet';
  });
  const query = since ? `?since=${encodeURIComponent(since)}` : '';
  Promise.all([get('/fleet'), get(`/fleet/parameters${query}`), get(`/fleet/units${query}`),
    get(`/fleet/calibrations${query}`)])
    .then(([stations, parameters, units, records]) => {
      replaceChildren(boxes.stations, stationsTable(stations));
      replaceChildren(boxes.parameters, parametersTable(parameters));
      boxes.parameters.querySelectorAll('th').forEach((th, i) => th.classList.toggle('num', i >= 3));
      replaceChildren(boxes.units, unitsTable(units));
      replaceChildren(boxes.records, recordsTable(records));
    })
    .catch((e) => {
      replaceChildren(boxes.stations, el('p', { class: 'state-failed' }, 'The fleet is unavailable.'));
      ctx.showMessage(e.message);
    });
  return () => {};
}
