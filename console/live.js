// The daemon's live stream (GET /events, server-sent events) shared by every page: one
// EventSource for the whole console, messages handed to whoever subscribed to their type.
// EventSource reconnects by itself and sends Last-Event-ID, so nothing is lost across a short
// outage; a `gap` message says when something was, and pages re-read what they show.

import { withToken } from './api.js';

const TYPES = ['station', 'run', 'step', 'telemetry', 'fault', 'event', 'gap'];
const listeners = new Map(TYPES.map((t) => [t, new Set()]));
const stateListeners = new Set();
let source = null;

function setState(state) {
  for (const fn of stateListeners) fn(state);
}

/** Opens the stream (once). EventSource cannot send an Authorization header: the token goes
 *  in the query (api.js withToken). */
export function connect() {
  if (source) return;
  source = new EventSource(withToken('/events'));
  source.addEventListener('open', () => setState('live'));
  source.addEventListener('error', () => setState(source.readyState === EventSource.CLOSED ? 'closed' : 'reconnecting'));
  for (const type of TYPES) {
    source.addEventListener(type, (e) => {
      let data;
      try {
        data = JSON.parse(e.data);
      } catch {
        return;  // not ours: the stream carries JSON only
      }
      for (const fn of listeners.get(type)) fn(data, e.lastEventId);
    });
  }
}

/** Opens the stream again, e.g. with the token just entered (a stream refused without one
 *  stays closed). Listeners stay subscribed. */
export function reconnect() {
  if (source) source.close();
  source = null;
  connect();
}

/** Calls fn(data, id) for each message of `type`; returns the function that unsubscribes. */
export function subscribe(type, fn) {
  listeners.get(type).add(fn);
  return () => listeners.get(type).delete(fn);
}

/** Calls fn('live' | 'reconnecting' | 'closed') when the stream's state changes. */
export function onStreamState(fn) {
  stateListeners.add(fn);
}
