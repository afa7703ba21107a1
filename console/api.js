// The daemon's HTTP API (schemas/api.md) as the console uses it: JSON in and out, the bearer
// token on every request (a daemon beyond loopback wants it for reads too), and errors turned
// into messages an operator can act on.

const TOKEN_KEY = 'calstand.token';

/** The token typed into the token field; kept for this browser tab only (sessionStorage), so
 *  that it is not left behind on a shared station screen. */
export function token() {
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

export function setToken(value) {
  if (value) sessionStorage.setItem(TOKEN_KEY, value);
  else sessionStorage.removeItem(TOKEN_KEY);
}

/** `path` carrying the token as ?access_token= (GET only): for what the browser fetches by
 *  itself, which cannot carry an Authorization header: the live stream's EventSource, and the
 *  links to reports, records and exports opened in a tab. */
export function withToken(path) {
  const t = token();
  if (!t) return path;
  return `${path}${path.includes('?') ? '&' : '?'}access_token=${encodeURIComponent(t)}`;
}

/** An answer other than 2xx: `status`, the daemon's `{"error", "where", "violations"?}` body. */
export class ApiError extends Error {
  constructor(status, body) {
    super(ApiError.describe(status, body));
    this.status = status;
    this.body = body || {};
  }

  static describe(status, body) {
    const why = (body && body.error) || `HTTP ${status}`;
    if (status === 401) {
      return 'Refused (401): this needs the station token. Enter it in the Token field at the top and try again.';
    }
    if (status === 403) {
      return 'Refused (403): the token entered may only read; this action needs an operator token.';
    }
    const where = body && body.where ? ` (${body.where})` : '';
    return `${why}${where}`;
  }
}

async function answer(response) {
  const type = response.headers.get('Content-Type') || '';
  const body = type.includes('application/json') ? await response.json() : await response.text();
  if (!response.ok) throw new ApiError(response.status, typeof body === 'object' ? body : { error: body });
  return body;
}

function authorized(headers) {
  const t = token();
  if (t) headers.Authorization = `Bearer ${t}`;
  return headers;
}

export async function get(path) {
  return answer(await fetch(path, { headers: authorized({ Accept: 'application/json' }) }));
}

export async function post(path, body = {}) {
  const headers = authorized({ 'Content-Type': 'application/json', 'X-Calstand-Operator': 'console' });
  return answer(await fetch(path, { method: 'POST', headers, body: JSON.stringify(body) }));
}
