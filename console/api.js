// The daemon's HTTP API (schemas/api.md) as the console uses it: JSON in and out, the bearer
// token on every POST, and errors turned into messages an operator can act on.

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
      return 'Refused (401): this action needs the station token. Enter it in the Token field at the top and try again.';
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

export async function get(path) {
  return answer(await fetch(path, { headers: { Accept: 'application/json' } }));
}

export async function post(path, body = {}) {
  const headers = { 'Content-Type': 'application/json', 'X-Calstand-Operator': 'console' };
  const t = token();
  if (t) headers.Authorization = `Bearer ${t}`;
  return answer(await fetch(path, { method: 'POST', headers, body: JSON.stringify(body) }));
}
