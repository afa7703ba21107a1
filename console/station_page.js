// Station page: the devices with their states and fault counters, the table and chamber now,
// each IMU's stream, and live plots, from GET /station and the event stream's telemetry.
import { get } from './api.js';
import { liveSeries } from './charts.js';
import { el, num, replaceChildren, table } from './dom.js';
import { subscribe } from './live.js';

// Devices and queue change rarely and are not on the stream: re-read them this often.
const STATION_REFRESH_MS = 3000;

function stateCell(state) {
  return el('span', { class: `state-${state}` }, state);
}

function devicesTable(devices) {
  return table(['device', 'kind', 'backend', 'state', 'fault counters'], devices.map((d) => [
    d.name, d.kind, d.backend, stateCell(d.state),
    Object.entries(d.fault_counters || {}).map(([k, v]) => `${k} ${v}`).join(', ') || '–',
  ]), { id: 'devices' });
}

function axisRow(name, axis) {
  if (!axis) return [name, '–', '–', '–', '–'];
  return [name, el('span', { class: 'num', id: `table-${name}-angle` }, num(axis.angle_deg, 6)),
    el('span', { id: `table-${name}-rate` }, num(axis.rate_dps, 5)), axis.mode,
    axis.fault ? el('span', { class: 'state-fault' }, axis.fault_text || 'fault') : (axis.in_position ? 'in position' : 'moving')];
}

export function showStation({ root, showMessage }) {
  const summary = el('section', { class: 'panel', id: 'station-summary' }, 'Reading the station…');
  const tablePanel = el('section', { class: 'panel' }, el('h3', {}, 'Table and chamber'), el('div', { id: 'now' }));
  const imuPanel = el('section', { class: 'panel' }, el('h3', {}, 'IMU streams'),
    el('div', { id: 'imu-streams', class: 'muted' }, 'No samples yet: IMUs stream during a run\'s captures.'));
  const tempBox = el('div', { class: 'chart' });
  const gyroBox = el('div', { class: 'chart' });
  const accelBox = el('div', { class: 'chart' });
  const counter = el('span', { id: 'telemetry-count' }, '0');
  root.append(
    el('h2', {}, 'Station'), summary,
    el('div', { class: 'grid' }, tablePanel, imuPanel),
    el('p', { class: 'muted' }, 'Live telemetry messages received: ', counter),
    el('div', { class: 'grid' },
      el('section', { class: 'panel' }, tempBox),
      el('section', { class: 'panel' }, gyroBox),
      el('section', { class: 'panel' }, accelBox)));

  const temperature = liveSeries(tempBox, { title: 'Temperature', labels: ['chamber air', 'setpoint', 'IMU'], yLabel: 'degC' });
  const gyro = liveSeries(gyroBox, { title: 'Gyro (first IMU, mean per message)', labels: ['gx', 'gy', 'gz'], yLabel: 'deg/s' });
  const accel = liveSeries(accelBox, { title: 'Accelerometer (first IMU, mean per message)', labels: ['ax', 'ay', 'az'], yLabel: 'm/s²' });
  let received = 0;

  function showNow(tel) {
    const t = tel.table || {};
    const c = tel.chamber;
    replaceChildren(tablePanel.querySelector('#now'),
      table(['axis', 'angle [deg]', 'rate [deg/s]', 'mode', 'state'], [axisRow('outer', t.outer), axisRow('inner', t.inner)]),
      el('p', {}, 'Chamber air ', el('b', { id: 'chamber-air' }, c ? `${num(c.air_c, 4)} °C` : '–'),
        ', setpoint ', el('b', { id: 'chamber-setpoint' }, c ? `${num(c.setpoint_c, 4)} °C` : '–'),
        c ? ` (${c.mode}${c.fault ? `, fault: ${c.fault_text || ''}` : ''})` : ''));
  }

  function showStationDoc(doc) {
    const progress = doc.progress
      ? el('p', {}, `Run ${doc.run}: step ${doc.progress.step + 1} of ${doc.progress.steps} (${doc.progress.label}), `,
        `${doc.progress.phase}, `, stateCell(doc.progress.state))
      : el('p', { class: 'muted' }, doc.held ? `Run ${doc.held} is held: resume or abort it on the Runs page.` : 'No run on the station.');
    // Why the next run waits (a full disk, a latched interlock): it starts by itself once the
    // cause is gone.
    const waiting = doc.waiting ? el('p', { class: 'field-error', id: 'station-waiting' }, `Next run waiting: ${doc.waiting}`) : null;
    replaceChildren(summary, el('div', {}, el('b', {}, doc.name), ` · queue: ${doc.queue.length} run(s)`),
      progress, waiting, devicesTable(doc.devices));
    if (doc.telemetry) showNow(doc.telemetry);
  }

  function showImus(imus) {
    if (!imus || imus.length === 0) return;
    replaceChildren(imuPanel.querySelector('#imu-streams'), table(['IMU', 'samples', 'rate [Hz]', 'temperature [°C]'],
      imus.map((i) => [i.device, String(i.samples), num(i.rate_hz, 4), num(i.temperature_c, 4)])));
  }

  async function refresh() {
    try {
      showStationDoc(await get('/station'));
    } catch (e) {
      showMessage(`Cannot read the station: ${e.message}`);
    }
  }

  const unsubscribe = [
    subscribe('station', showStationDoc),
    subscribe('telemetry', (tel) => {
      received += 1;
      counter.textContent = String(received);
      showNow(tel);
      showImus(tel.imus);
      const c = tel.chamber;
      const imu = (tel.imus || []).find((i) => i.samples > 0);
      if (c) temperature.push(c.time_s, [c.air_c, c.setpoint_c, imu ? imu.temperature_c : null]);
      if (imu) {
        gyro.push(imu.time_s, imu.gyro_dps);
        accel.push(imu.time_s, imu.accel_mps2);
      }
    }),
    subscribe('fault', (f) => showMessage(`Fault (${f.source}): ${f.message}`)),
  ];
  refresh();
  const timer = setInterval(refresh, STATION_REFRESH_MS);
  return () => {
    clearInterval(timer);
    unsubscribe.forEach((u) => u());
    [temperature, gyro, accel].forEach((c) => c.destroy());
  };
}
