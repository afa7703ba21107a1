-- The calstand database schema: the one source of truth for every table, index and view.
--
-- Versioned migrations. Each block starts with a line `-- migration N: title` (N = 1, 2, ...
-- without gaps) and runs in its own transaction, after which PRAGMA user_version = N. A
-- database is brought to the latest version when opened (store/src/migrations.cpp); a database
-- whose user_version is newer than the last block here is refused. Never edit a released
-- block: append a new one.
--
-- Conventions: times on the station clock are REAL seconds in columns ending `_clock_s` or
-- `time_s`; wall-clock times are UTC ISO-8601 text (`2024-05-01T12:34:56.789Z`) in columns
-- ending `_utc`; JSON documents are TEXT. Units are in the column names.

-- migration 1: stations, runs, steps, samples, telemetry, events, calibrations
PRAGMA application_id = 1129530434;  -- 0x43534442, 'CSDB': marks a calstand database

-- One row per station configuration name; `config` is the station JSON as last registered.
CREATE TABLE stations (
  id          INTEGER PRIMARY KEY,
  name        TEXT NOT NULL UNIQUE,
  config      TEXT NOT NULL CHECK (json_valid(config)),
  updated_utc TEXT NOT NULL
);

-- Devices of a station: kind 'table', 'chamber' or 'imu'; backend e.g. 'sim', 'modbus'.
CREATE TABLE devices (
  id         INTEGER PRIMARY KEY,
  station_id INTEGER NOT NULL REFERENCES stations(id) ON DELETE CASCADE,
  kind       TEXT NOT NULL,
  name       TEXT NOT NULL,
  backend    TEXT NOT NULL,
  UNIQUE (station_id, name)
);

-- One campaign. `status` is the run engine's state name (running, paused, completed, aborted,
-- failed, ...) or 'imported'. `station_snapshot` is the station JSON at creation time (for an
-- imported run: the import's meta.json), so a run stays interpretable when the station changes.
CREATE TABLE runs (
  id               INTEGER PRIMARY KEY,
  station_id       INTEGER REFERENCES stations(id),
  procedure_name   TEXT NOT NULL,
  procedure_text   TEXT NOT NULL,
  procedure_sha256 TEXT NOT NULL,
  parameters       TEXT NOT NULL CHECK (json_valid(parameters)),
  station_snapshot TEXT NOT NULL CHECK (json_valid(station_snapshot)),
  status           TEXT NOT NULL,
  exit_reason      TEXT,
  created_utc      TEXT NOT NULL,
  started_utc      TEXT,
  started_clock_s  REAL,
  ended_utc        TEXT,
  ended_clock_s    REAL
);

-- The expanded steps of a run, idx = 0, 1, ... `commanded` is the commanded state (JSON),
-- `origin` the JSON path in the procedure the step was expanded from (e.g. `steps[3].steps[1]`).
-- `attempts` counts started attempts; `good_attempt` is the attempt whose samples are the
-- step's data (set on completion).
CREATE TABLE steps (
  id              INTEGER PRIMARY KEY,
  run_id          INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  idx             INTEGER NOT NULL,
  kind            TEXT NOT NULL,
  label           TEXT NOT NULL,
  commanded       TEXT NOT NULL CHECK (json_valid(commanded)),
  origin          TEXT NOT NULL,
  status          TEXT NOT NULL DEFAULT 'pending'
                  CHECK (status IN ('pending', 'running', 'completed', 'failed', 'skipped',
                                    'invalidated')),
  reason          TEXT,
  attempts        INTEGER NOT NULL DEFAULT 0,
  good_attempt    INTEGER,
  started_utc     TEXT,
  started_clock_s REAL,
  ended_utc       TEXT,
  ended_clock_s   REAL,
  UNIQUE (run_id, idx)
);

-- IMU samples, a chunk of consecutive samples of one device and one step attempt per row.
-- `data` is the binary layout of store/include/store/sample_codec.hpp (README: "Reading the
-- database"); count, encoding and the receive-time span repeat the header for plain SQL.
CREATE TABLE sample_chunks (
  id                   INTEGER PRIMARY KEY,
  run_id               INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  step_id              INTEGER NOT NULL REFERENCES steps(id) ON DELETE CASCADE,
  attempt              INTEGER NOT NULL,
  device               TEXT NOT NULL,
  first_receive_time_s REAL NOT NULL,
  last_receive_time_s  REAL NOT NULL,
  count                INTEGER NOT NULL CHECK (count > 0),
  encoding             INTEGER NOT NULL CHECK (encoding IN (1, 2)),
  data                 BLOB NOT NULL
);
CREATE INDEX sample_chunks_by_step ON sample_chunks (step_id, attempt, device, id);
CREATE INDEX sample_chunks_by_run ON sample_chunks (run_id);

-- Per step attempt and device: sample count, time span, mean and standard deviation of every
-- channel, written by the capture writer when the step is committed (from the full-precision
-- samples). What the solver averages, readable with plain SQL.
CREATE TABLE step_means (
  run_id               INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  step_id              INTEGER NOT NULL REFERENCES steps(id) ON DELETE CASCADE,
  attempt              INTEGER NOT NULL,
  device               TEXT NOT NULL,
  count                INTEGER NOT NULL,
  first_receive_time_s REAL NOT NULL,
  last_receive_time_s  REAL NOT NULL,
  gx_dps REAL, gy_dps REAL, gz_dps REAL,
  ax_mps2 REAL, ay_mps2 REAL, az_mps2 REAL,
  temperature_c REAL,
  std_gx_dps REAL, std_gy_dps REAL, std_gz_dps REAL,
  std_ax_mps2 REAL, std_ay_mps2 REAL, std_az_mps2 REAL,
  std_temperature_c REAL,
  PRIMARY KEY (step_id, attempt, device)
);
CREATE INDEX step_means_by_run ON step_means (run_id);

-- Table state, decimated (about 10 Hz during a run; one row per sample for imported data, then
-- linked to its step).
CREATE TABLE table_telemetry (
  id             INTEGER PRIMARY KEY,
  run_id         INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  step_id        INTEGER REFERENCES steps(id) ON DELETE CASCADE,
  time_s         REAL NOT NULL,
  outer_deg      REAL NOT NULL,
  inner_deg      REAL NOT NULL,
  outer_rate_dps REAL NOT NULL,
  inner_rate_dps REAL NOT NULL,
  outer_mode     TEXT,
  inner_mode     TEXT
);
CREATE INDEX table_telemetry_by_run_time ON table_telemetry (run_id, time_s);
CREATE INDEX table_telemetry_by_step ON table_telemetry (step_id) WHERE step_id IS NOT NULL;

-- Chamber state, decimated.
CREATE TABLE chamber_telemetry (
  id           INTEGER PRIMARY KEY,
  run_id       INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  time_s       REAL NOT NULL,
  air_c        REAL NOT NULL,
  setpoint_c   REAL NOT NULL,
  mode         TEXT
);
CREATE INDEX chamber_telemetry_by_run_time ON chamber_telemetry (run_id, time_s);

-- Faults, interlocks, operator actions and information, per run (run_id NULL: station-wide).
CREATE TABLE events (
  id       INTEGER PRIMARY KEY,
  run_id   INTEGER REFERENCES runs(id) ON DELETE CASCADE,
  time_s   REAL NOT NULL,
  wall_utc TEXT NOT NULL,
  kind     TEXT NOT NULL CHECK (kind IN ('fault', 'interlock', 'operator', 'info')),
  source   TEXT NOT NULL,
  message  TEXT NOT NULL,
  detail   TEXT CHECK (detail IS NULL OR json_valid(detail))
);
CREATE INDEX events_by_run ON events (run_id, id);

-- Calibration records the solver produces (issue 4).
CREATE TABLE calibrations (
  id          INTEGER PRIMARY KEY,
  run_id      INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  imu         TEXT NOT NULL,
  model       TEXT NOT NULL,
  record      TEXT NOT NULL CHECK (json_valid(record)),
  created_utc TEXT NOT NULL
);
CREATE INDEX calibrations_by_run ON calibrations (run_id);

-- Views for the sqlite3 shell.

-- Per step, device and attempt: chunks, samples and the receive-time span.
CREATE VIEW step_sample_summary AS
SELECT s.run_id, s.idx AS step, s.label, s.status, c.device, c.attempt,
       (c.attempt IS s.good_attempt) AS is_good_attempt,
       COUNT(*) AS chunks, SUM(c.count) AS samples,
       MIN(c.first_receive_time_s) AS first_receive_time_s,
       MAX(c.last_receive_time_s) AS last_receive_time_s
FROM sample_chunks c JOIN steps s ON s.id = c.step_id
GROUP BY c.step_id, c.device, c.attempt;

-- The means of the step data: the good attempt of each completed step.
CREATE VIEW step_means_view AS
SELECT s.run_id, s.idx AS step, s.label, s.kind, s.commanded, m.device, m.attempt, m.count,
       m.first_receive_time_s, m.last_receive_time_s,
       m.gx_dps, m.gy_dps, m.gz_dps, m.ax_mps2, m.ay_mps2, m.az_mps2, m.temperature_c,
       m.std_gx_dps, m.std_gy_dps, m.std_gz_dps, m.std_ax_mps2, m.std_ay_mps2, m.std_az_mps2,
       m.std_temperature_c
FROM step_means m JOIN steps s ON s.id = m.step_id AND m.attempt IS s.good_attempt;

-- One line per run, as `calstand runs` shows it.
CREATE VIEW run_overview AS
SELECT r.id, r.procedure_name, r.status,
       (SELECT COUNT(*) FROM steps s WHERE s.run_id = r.id AND s.status = 'completed')
         AS steps_done,
       (SELECT COUNT(*) FROM steps s WHERE s.run_id = r.id) AS steps_total,
       r.started_utc, r.ended_utc, r.exit_reason
FROM runs r;

-- migration 2: fit history
-- Every fit of a run (calstand fit, diagnose, calibrate): the model and how well it fitted, so
-- that `calstand history` shows the error falling as effects are added.
CREATE TABLE fits (
  id               INTEGER PRIMARY KEY,
  run_id           INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  device           TEXT NOT NULL,
  command          TEXT NOT NULL,
  model            TEXT NOT NULL,
  custom_terms     TEXT NOT NULL CHECK (json_valid(custom_terms)),
  sensors          TEXT NOT NULL,
  parameters       INTEGER NOT NULL,
  chi2_dof         REAL,
  rms_gyro_dps     REAL,
  rms_accel_mps2   REAL,
  created_utc      TEXT NOT NULL
);
CREATE INDEX fits_by_run ON fits (run_id, id);

-- migration 3: run queue of the station daemon
-- Runs submitted to calstandd wait here (runs.status = 'queued') until the station is free;
-- the daemon takes them oldest first, so a queue survives a restart. `submitted_by` is who
-- asked (the API's operator name and address).
CREATE TABLE run_queue (
  run_id        INTEGER PRIMARY KEY REFERENCES runs(id) ON DELETE CASCADE,
  submitted_utc TEXT NOT NULL,
  submitted_by  TEXT NOT NULL
);

-- migration 4: fit history of runs without a table
-- A run recorded without a table (calstand-import/2 without `table`) is fitted by the gravity
-- norm and the integration between static poses: its gyro residual is the gravity direction
-- after each turn [deg], not a rate. rms_accel_mps2 then holds |calibrated f| - g.
ALTER TABLE fits ADD COLUMN rms_turn_deg REAL;

-- migration 5: units with identities, acceptance verdicts
-- The unit in each IMU slot of a run (`imu` is the slot's name at the station): its model and
-- serial, and where the serial came from: read from the device ('device'), given when the run
-- was submitted ('submitted'), or fixed in the station file ('station').
CREATE TABLE run_units (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  imu    TEXT NOT NULL,
  model  TEXT NOT NULL,
  serial TEXT NOT NULL,
  source TEXT NOT NULL CHECK (source IN ('device', 'submitted', 'station')),
  PRIMARY KEY (run_id, imu)
);
CREATE INDEX run_units_by_serial ON run_units (serial, run_id);
-- A record's unit, so that `calstand calibrations --serial` finds it without parsing JSON.
ALTER TABLE calibrations ADD COLUMN serial TEXT NOT NULL DEFAULT '';
CREATE INDEX calibrations_by_serial ON calibrations (serial, id);
-- The verdict of a record against a specification (`calstand accept`): `result` is the whole
-- outcome (every check with value, sigma, limit and verdict, the decision rule, as-found).
CREATE TABLE acceptances (
  id             INTEGER PRIMARY KEY,
  calibration_id INTEGER NOT NULL REFERENCES calibrations(id) ON DELETE CASCADE,
  spec_name      TEXT NOT NULL,
  spec_sha256    TEXT NOT NULL,
  verdict        TEXT NOT NULL CHECK (verdict IN ('pass', 'fail', 'indeterminate')),
  result         TEXT NOT NULL CHECK (json_valid(result)),
  created_utc    TEXT NOT NULL
);
CREATE INDEX acceptances_by_calibration ON acceptances (calibration_id, id);

-- migration 6: station identity for the fleet
-- The station's identity across a fleet (docs/fleet.md): a random UUID (version 4) made once,
-- when the database is created or first brought to this version. The central database knows
-- a run as (station uuid, local run id), never by the local id alone. A copied database file
-- copies the identity too: make a fresh database for a new station.
CREATE TABLE station_identity (
  only_row    INTEGER PRIMARY KEY CHECK (only_row = 1),
  uuid        TEXT NOT NULL CHECK (length(uuid) = 36),
  created_utc TEXT NOT NULL
);
INSERT INTO station_identity (only_row, uuid, created_utc)
SELECT 1,
       lower(substr(h, 1, 8) || '-' || substr(h, 9, 4) || '-4' || substr(h, 14, 3) || '-' ||
             substr('89ab', 1 + (abs(random()) % 4), 1) || substr(h, 18, 3) || '-' ||
             substr(h, 21, 12)),
       strftime('%Y-%m-%dT%H:%M:%fZ', 'now')
FROM (SELECT hex(randomblob(16)) AS h);

-- migration 7: the step residuals of a calibration, for its certificate
-- What a certificate draws from the fit that made a record (its residual per step against the
-- step's noise), stored when the record is: the certificate reads them instead of fitting the
-- model again. `steps` is {"format": "calstand-step-residuals/1", "steps": [{"index", "label",
-- "residual": [gx, gy, gz, ax, ay, az], "sigma": [...]}]} in deg/s and m/s^2. A record made
-- before this migration has no row; its certificate refits as before. A calibration without a
-- table (no steps to fit) has none either.
CREATE TABLE calibration_residuals (
  calibration_id INTEGER PRIMARY KEY REFERENCES calibrations(id) ON DELETE CASCADE,
  steps          TEXT NOT NULL CHECK (json_valid(steps))
);
