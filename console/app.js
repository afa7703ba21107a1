// The console's entry point: the token field, the message banner, the live stream indicator,
// and the router that shows one page per location hash (#/station, #/runs, #/runs/ID,
// #/loop/ID, #/lot, #/lot/YYYY-MM-DD, #/units/SERIAL, #/fleet, #/fleet/YYYY-MM-DD).
import { setToken, token } from './api.js';
import { showFleet } from './fleet_page.js';
import { connect, onStreamState, reconnect } from './live.js';
import { showLot, showUnit } from './lot_page.js';
import { showLoop } from './loop_page.js';
import { showRuns } from './runs_page.js';
import { showStation } from './station_page.js';

const messageBox = document.getElementById('message');

/** Shows `text` in the banner (kind 'error' or 'info') until the next page or message. */
export function showMessage(text, kind = 'error') {
  messageBox.textContent = text;
  messageBox.className = kind;
  messageBox.hidden = false;
}

export function clearMessage() {
  messageBox.hidden = true;
  messageBox.textContent = '';
}

// A percent-encoded part of the address as text; a malformed one (typed by hand) as it stands.
function decoded(text) {
  try {
    return decodeURIComponent(text);
  } catch {
    return text;
  }
}

// Pages return a function that releases what they hold (subscriptions, charts) when left.
let leavePage = () => {};

function route() {
  const [, page = 'station', id] = (location.hash || '#/station').split('/');
  // A unit's page belongs to the lot's tab.
  const tab = page === 'units' ? 'lot' : page;
  for (const name of ['station', 'runs', 'loop', 'lot', 'fleet']) {
    document.getElementById(`nav-${name}`).classList.toggle('current', name === tab);
  }
  leavePage();
  clearMessage();
  const root = document.getElementById('page');
  root.replaceChildren();
  const ctx = { root, showMessage, clearMessage };
  const runId = id ? Number(id) : null;
  if (page === 'runs') leavePage = showRuns(ctx, runId);
  else if (page === 'loop') leavePage = showLoop(ctx, runId);
  else if (page === 'lot') leavePage = showLot(ctx, id || '');
  else if (page === 'fleet') leavePage = showFleet(ctx, id || '');
  // The serial is percent-encoded in the address (a '/' in it would split it).
  else if (page === 'units' && id) leavePage = showUnit(ctx, decoded(id));
  else if (page === 'units') leavePage = showLot(ctx);
  else leavePage = showStation(ctx);
}

const tokenField = document.getElementById('token');
tokenField.value = token();
tokenField.addEventListener('input', () => setToken(tokenField.value.trim()));
// Beyond loopback reads need the token too: while the stream is refused, a token entered (the
// field left) reopens it and reads the page again. A live stream means reads work already, and
// reading the page again would lose what it shows (a fit) and the click that left the field.
let streamState = 'connecting';
tokenField.addEventListener('change', () => {
  if (streamState === 'live') return;
  reconnect();
  route();
});

const streamBadge = document.getElementById('stream-state');
onStreamState((state) => {
  streamState = state;
  streamBadge.textContent = state === 'live' ? 'live' : state;
  streamBadge.className = `stream-state ${state}`;
});

connect();
window.addEventListener('hashchange', route);
route();
