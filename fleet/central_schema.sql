-- The fleet's central PostgreSQL database: the one source of truth for its tables, roles and
-- row-level security (docs/fleet.md).
--
-- Versioned migrations, in the form of store/schema.sql: each block starts with a line
-- `-- migration N: title` (N = 1, 2, ... without gaps) and runs in its own transaction, run by
-- the database's owner (`calstand fleet migrate`), which records it in calstand_schema. A
-- station syncs only to a database at exactly its own version (fleet/src/central_schema.cpp
-- says which side to update). Never edit a released block: append a new one.
--
-- Conventions as in the station's file: times on a station clock are double precision seconds
-- in columns ending `_clock_s` or `time_s`; wall-clock times are the station's UTC ISO-8601 text
-- in columns ending `_utc` (compared as text, as on the station); JSON documents are jsonb.
-- Every row carries its station's uuid; `local_id` is the row's id in the station's file.

-- migration 1: stations, runs, records, samples, sync cursors, roles and row-level security
-- Group roles: a station's login role is a member of calstand_station (inserts and reads its
-- own rows only, and moves its own cursors); dashboards and `calstand fleet` log in as members
-- of calstand_reader (reads everything). Roles belong to the whole server: made only when
-- missing.
DO $$
BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calstand_station') THEN
    CREATE ROLE calstand_station NOLOGIN;
  END IF;
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calstand_reader') THEN
    CREATE ROLE calstand_reader NOLOGIN;
  END IF;
END
$$;

-- A station as it registered on its first sync: `db_role` is the login role it syncs as, the
-- key of row-level security below.
CREATE TABLE stations (
  uuid           uuid PRIMARY KEY,
  name           text NOT NULL,
  db_role        name NOT NULL DEFAULT current_user,
  store_schema   integer NOT NULL,
  registered_utc text NOT NULL
);

CREATE TABLE runs (
  id               bigserial PRIMARY KEY,
  station          uuid NOT NULL REFERENCES stations (uuid),
  local_id         bigint NOT NULL,
  procedure_name   text NOT NULL,
  procedure_text   text NOT NULL,
  procedure_sha256 text NOT NULL,
  parameters       jsonb NOT NULL,
  station_snapshot jsonb NOT NULL,
  status           text NOT NULL,
  exit_reason      text,
  created_utc      text NOT NULL,
  started_utc      text,
  started_clock_s  double precision,
  ended_utc        text,
  ended_clock_s    double precision,
  UNIQUE (station, local_id)
);
CREATE INDEX runs_by_created ON runs (created_utc);

CREATE TABLE steps (
  station         uuid NOT NULL REFERENCES stations (uuid),
  local_id        bigint NOT NULL,
  run_id          bigint NOT NULL REFERENCES runs (id),
  idx             integer NOT NULL,
  kind            text NOT NULL,
  label           text NOT NULL,
  commanded       jsonb NOT NULL,
  origin          text NOT NULL,
  status          text NOT NULL,
  reason          text,
  attempts        integer NOT NULL,
  good_attempt    integer,
  started_utc     text,
  started_clock_s double precision,
  ended_utc       text,
  ended_clock_s   double precision,
  PRIMARY KEY (station, local_id),
  UNIQUE (run_id, idx)
);

CREATE TABLE events (
  station  uuid NOT NULL REFERENCES stations (uuid),
  local_id bigint NOT NULL,
  run_id   bigint NOT NULL REFERENCES runs (id),
  time_s   double precision NOT NULL,
  wall_utc text NOT NULL,
  kind     text NOT NULL,
  source   text NOT NULL,
  message  text NOT NULL,
  detail   jsonb,
  PRIMARY KEY (station, local_id)
);
CREATE INDEX events_by_run ON events (run_id);

CREATE TABLE run_units (
  station uuid NOT NULL REFERENCES stations (uuid),
  run_id  bigint NOT NULL REFERENCES runs (id),
  imu     text NOT NULL,
  model   text NOT NULL,
  serial  text NOT NULL,
  source  text NOT NULL,
  PRIMARY KEY (run_id, imu)
);
CREATE INDEX run_units_by_serial ON run_units (serial);

CREATE TABLE calibrations (
  id          bigserial PRIMARY KEY,
  station     uuid NOT NULL REFERENCES stations (uuid),
  local_id    bigint NOT NULL,
  run_id      bigint NOT NULL REFERENCES runs (id),
  imu         text NOT NULL,
  model       text NOT NULL,
  record      jsonb NOT NULL,
  created_utc text NOT NULL,
  serial      text NOT NULL,
  UNIQUE (station, local_id)
);
CREATE INDEX calibrations_by_serial ON calibrations (serial);
CREATE INDEX calibrations_by_created ON calibrations (created_utc);

CREATE TABLE acceptances (
  id             bigserial PRIMARY KEY,
  station        uuid NOT NULL REFERENCES stations (uuid),
  local_id       bigint NOT NULL,
  calibration_id bigint NOT NULL REFERENCES calibrations (id),
  spec_name      text NOT NULL,
  spec_sha256    text NOT NULL,
  verdict        text NOT NULL,
  result         jsonb NOT NULL,
  created_utc    text NOT NULL,
  UNIQUE (station, local_id)
);
CREATE INDEX acceptances_by_calibration ON acceptances (calibration_id, id);

CREATE TABLE fits (
  station        uuid NOT NULL REFERENCES stations (uuid),
  local_id       bigint NOT NULL,
  run_id         bigint NOT NULL REFERENCES runs (id),
  device         text NOT NULL,
  command        text NOT NULL,
  model          text NOT NULL,
  custom_terms   jsonb NOT NULL,
  sensors        text NOT NULL,
  parameters     integer NOT NULL,
  chi2_dof       double precision,
  rms_gyro_dps   double precision,
  rms_accel_mps2 double precision,
  rms_turn_deg   double precision,
  created_utc    text NOT NULL,
  PRIMARY KEY (station, local_id)
);

-- Sample chunks exactly as the station stores them (store/sample_codec.hpp), so a central
-- analysis can refit; `step_idx` is the step's index in its run.
CREATE TABLE sample_chunks (
  station              uuid NOT NULL REFERENCES stations (uuid),
  local_id             bigint NOT NULL,
  run_id               bigint NOT NULL REFERENCES runs (id),
  step_idx             integer NOT NULL,
  attempt              integer NOT NULL,
  device               text NOT NULL,
  first_receive_time_s double precision NOT NULL,
  last_receive_time_s  double precision NOT NULL,
  count                integer NOT NULL,
  encoding             integer NOT NULL,
  data                 bytea NOT NULL,
  PRIMARY KEY (station, local_id)
);
CREATE INDEX sample_chunks_by_run ON sample_chunks (run_id, step_idx);

-- How far each station's sync has come in each of its streams: every local id up to
-- `last_local_id` is here (runs: ended and copied). Moved in the transaction that copies.
CREATE TABLE sync_cursors (
  station       uuid NOT NULL REFERENCES stations (uuid),
  stream        text NOT NULL,
  last_local_id bigint NOT NULL,
  PRIMARY KEY (station, stream)
);

-- Samples: a cursor per run (local chunk id), `complete` once every chunk of the ended run is
-- here.
CREATE TABLE sample_cursors (
  station       uuid NOT NULL REFERENCES stations (uuid),
  run_id        bigint PRIMARY KEY REFERENCES runs (id),
  last_local_id bigint NOT NULL,
  complete      boolean NOT NULL
);

-- Row-level security: a station's role sees and inserts only rows of a station registered to
-- it (stations.db_role = its login role); readers see everything; the owner, who runs the
-- migrations, is not subject to the policies (the table owner bypasses them).
ALTER TABLE stations ENABLE ROW LEVEL SECURITY;
CREATE POLICY station_own ON stations TO calstand_station
  USING (db_role = current_user) WITH CHECK (db_role = current_user);
CREATE POLICY reader_all ON stations FOR SELECT TO calstand_reader USING (true);

DO $$
DECLARE
  t text;
BEGIN
  FOREACH t IN ARRAY ARRAY['runs', 'steps', 'events', 'run_units', 'calibrations',
                           'acceptances', 'fits', 'sample_chunks', 'sync_cursors',
                           'sample_cursors'] LOOP
    EXECUTE format('ALTER TABLE %I ENABLE ROW LEVEL SECURITY', t);
    EXECUTE format('CREATE POLICY station_own ON %I TO calstand_station '
                   'USING (station IN (SELECT uuid FROM stations WHERE db_role = current_user)) '
                   'WITH CHECK (station IN (SELECT uuid FROM stations WHERE db_role = current_user))',
                   t);
    EXECUTE format('CREATE POLICY reader_all ON %I FOR SELECT TO calstand_reader USING (true)', t);
    EXECUTE format('GRANT SELECT ON %I TO calstand_reader', t);
    EXECUTE format('GRANT SELECT, INSERT ON %I TO calstand_station', t);
  END LOOP;
END
$$;
GRANT SELECT ON stations TO calstand_reader;
-- calstand_schema (the versions applied) is made by `calstand fleet migrate` before this block.
GRANT SELECT ON calstand_schema TO calstand_station, calstand_reader;
GRANT SELECT, INSERT ON stations TO calstand_station;
-- Cursors move: the only rows a station may change (its own, by the policy above).
GRANT UPDATE ON sync_cursors, sample_cursors TO calstand_station;
GRANT USAGE ON SEQUENCE runs_id_seq, calibrations_id_seq, acceptances_id_seq TO calstand_station;

-- migration 2: telemetry, step means, station-wide events, unique station names
-- What a station records besides runs and records, so that the central database answers "which
-- stations ran hot last week" (chamber telemetry by run, runs by their UTC times). Each is
-- copied once its run has ended and is central, all of a run in one transaction together with
-- its `run_details` row (the mark that the run's details are here: a sync cut in between copies
-- them whole next time). Step ids are the station's (`step_local_id`, the steps' `local_id`).
CREATE TABLE run_details (
  station  uuid NOT NULL REFERENCES stations (uuid),
  local_id bigint NOT NULL,  -- the run's id on the station
  run_id   bigint PRIMARY KEY REFERENCES runs (id),
  UNIQUE (station, local_id)
);

-- Per step attempt and device, over its samples (the station's step_means): a central fit of
-- step means needs no samples.
CREATE TABLE step_means (
  station              uuid NOT NULL REFERENCES stations (uuid),
  run_id               bigint NOT NULL REFERENCES runs (id),
  step_local_id        bigint NOT NULL,
  attempt              integer NOT NULL,
  device               text NOT NULL,
  count                integer NOT NULL,
  first_receive_time_s double precision NOT NULL,
  last_receive_time_s  double precision NOT NULL,
  gx_dps double precision, gy_dps double precision, gz_dps double precision,
  ax_mps2 double precision, ay_mps2 double precision, az_mps2 double precision,
  temperature_c double precision,
  std_gx_dps double precision, std_gy_dps double precision, std_gz_dps double precision,
  std_ax_mps2 double precision, std_ay_mps2 double precision, std_az_mps2 double precision,
  std_temperature_c double precision,
  PRIMARY KEY (station, step_local_id, attempt, device)
);
CREATE INDEX step_means_by_run ON step_means (run_id);

-- Table and chamber state as the station decimated it.
CREATE TABLE table_telemetry (
  station        uuid NOT NULL REFERENCES stations (uuid),
  local_id       bigint NOT NULL,
  run_id         bigint NOT NULL REFERENCES runs (id),
  step_local_id  bigint,
  time_s         double precision NOT NULL,
  outer_deg      double precision NOT NULL,
  inner_deg      double precision NOT NULL,
  outer_rate_dps double precision NOT NULL,
  inner_rate_dps double precision NOT NULL,
  outer_mode     text,
  inner_mode     text,
  PRIMARY KEY (station, local_id)
);
CREATE INDEX table_telemetry_by_run_time ON table_telemetry (run_id, time_s);

CREATE TABLE chamber_telemetry (
  station    uuid NOT NULL REFERENCES stations (uuid),
  local_id   bigint NOT NULL,
  run_id     bigint NOT NULL REFERENCES runs (id),
  time_s     double precision NOT NULL,
  air_c      double precision NOT NULL,
  setpoint_c double precision NOT NULL,
  mode       text,
  PRIMARY KEY (station, local_id)
);
CREATE INDEX chamber_telemetry_by_run_time ON chamber_telemetry (run_id, time_s);

-- Station-wide events (an interlock closed between runs, ...) have no run, as on the station.
ALTER TABLE events ALTER COLUMN run_id DROP NOT NULL;

-- A station's name is unique in its fleet (`calstand fleet --station NAME` names one station).
-- Names registered twice before this version keep the first registration's; the later ones
-- get ' #' and the first 8 characters of their uuid, so that the index can be made.
UPDATE stations s SET name = s.name || ' #' || left(s.uuid::text, 8)
WHERE EXISTS (SELECT 1 FROM stations o WHERE o.name = s.name AND
              (o.registered_utc, o.uuid::text) < (s.registered_utc, s.uuid::text));
CREATE UNIQUE INDEX stations_by_name ON stations (name);

DO $$
DECLARE
  t text;
BEGIN
  FOREACH t IN ARRAY ARRAY['run_details', 'step_means', 'table_telemetry',
                           'chamber_telemetry'] LOOP
    EXECUTE format('ALTER TABLE %I ENABLE ROW LEVEL SECURITY', t);
    EXECUTE format('CREATE POLICY station_own ON %I TO calstand_station '
                   'USING (station IN (SELECT uuid FROM stations WHERE db_role = current_user)) '
                   'WITH CHECK (station IN (SELECT uuid FROM stations WHERE db_role = current_user))',
                   t);
    EXECUTE format('CREATE POLICY reader_all ON %I FOR SELECT TO calstand_reader USING (true)', t);
    EXECUTE format('GRANT SELECT ON %I TO calstand_reader', t);
    EXECUTE format('GRANT SELECT, INSERT ON %I TO calstand_station', t);
  END LOOP;
END
$$;

-- migration 3: sample chunks stored as they are, without compression
-- A chunk's samples are float32 noise (store/sample_codec.hpp), which does not compress: on a
-- 4 h station PostgreSQL's default compression (pglz) gave up on every chunk (0 % saved; lz4
-- would save 3 %), and trying took the server about 8 ms per 144 kB chunk, most of a sync's
-- time (docs/fleet.md, "Speed"). EXTERNAL keeps the chunks out of line in the TOAST table, as
-- before, without the attempt. Chunks stored before keep their form; reads are unchanged.
ALTER TABLE sample_chunks ALTER COLUMN data SET STORAGE EXTERNAL;
