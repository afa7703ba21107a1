// A standard EventSource client (the npm/Debian package `eventsource`, not calstand's code)
// reading calstandd's GET /events: daemon_sse_client_test.cpp runs it and checks what it prints.
//
//   node sse_standard_client.js BASE_URL PARAMETERS_JSON EVENTS_BEFORE_RECONNECT
//
// Phase 1 connects, submits a six-position run (POST /runs, token from CALSTAND_TOKEN) once the
// station snapshot has arrived, reads EVENTS_BEFORE_RECONNECT events that carry an id and
// closes. Phase 2 reconnects with that Last-Event-ID and reads until the run ends. Every event
// is printed as one JSON line: {"phase", "type", "id" (the client's lastEventId), "data"}; the
// last line is {"done": true, "run": ID}. Exit 0 when done, 2 on an error, 3 on the timeout.
'use strict';
const EventSource = require('eventsource');
const http = require('http');

const [base, parametersJson, beforeReconnectText] = process.argv.slice(2);
const beforeReconnect = Number(beforeReconnectText);
const types = ['station', 'run', 'step', 'telemetry', 'fault', 'event', 'gap', 'message'];
let run = null;

function fail(code, why) {
  process.stderr.write(`sse_standard_client: ${why}\n`);
  process.exit(code);
}
setTimeout(() => fail(3, 'timed out'), 100000).unref();

function submit() {
  const body = JSON.stringify({procedure: 'six-position', parameters: JSON.parse(parametersJson)});
  const req = http.request(`${base}/runs`, {
    method: 'POST',
    headers: {
      'Content-Type': 'application/json',
      'Content-Length': Buffer.byteLength(body),
      'Authorization': `Bearer ${process.env.CALSTAND_TOKEN}`,
    },
  }, (res) => {
    let text = '';
    res.on('data', (chunk) => { text += chunk; });
    res.on('end', () => {
      if (res.statusCode !== 201) fail(2, `POST /runs: HTTP ${res.statusCode} ${text}`);
      run = JSON.parse(text).id;
    });
  });
  req.on('error', (e) => fail(2, `POST /runs: ${e.message}`));
  req.end(body);
}

function read(phase, headers, onEvent) {
  const source = new EventSource(`${base}/events`, {headers});
  let closed = false;  // events of a chunk already received are not printed after close()
  const close = source.close.bind(source);
  source.close = () => { closed = true; close(); };
  source.onerror = (e) => {
    if (source.readyState === EventSource.CLOSED) fail(2, `phase ${phase}: ${e.message || e.status}`);
  };
  for (const type of types) {
    source.addEventListener(type, (e) => {
      if (closed) return;
      process.stdout.write(JSON.stringify({phase, type: e.type, id: e.lastEventId, data: e.data}) + '\n');
      onEvent(source, e);
    });
  }
}

let withId = 0;
read(1, {}, (source, e) => {
  if (e.type === 'station' && run === null && withId === 0) submit();
  if (e.lastEventId !== '') ++withId;
  if (withId < beforeReconnect) return;
  const last = e.lastEventId;
  source.close();
  // Messages go on being published while nobody listens; the reconnection must get them.
  setTimeout(() => {
    read(2, {'Last-Event-ID': last}, (again, m) => {
      if (m.type !== 'run' || run === null) return;
      const data = JSON.parse(m.data);
      if (data.run === run && ['completed', 'aborted', 'failed'].includes(data.state)) {
        again.close();
        process.stdout.write(JSON.stringify({done: true, run}) + '\n');
        process.exit(0);
      }
    });
  }, 700);
});
