#!/usr/bin/env python3
"""The web console in a real browser (headless Chromium through Selenium) against calstandd on
an ephemeral loopback port with the simulated demo station.

Checks, in one daemon's life (it takes seconds: the simulated station runs faster than real time):
  1. the station page shows live telemetry from the event stream (EventSource('/events'));
  2. a run submitted from the runs page (plan preview first) completes;
  3. on the loop page of a thermal calibration run, fit, diagnose, and the recommended term
     added with one click lowers the displayed chi2/dof to the value the API returns for the
     same model;
  4. a mutating click without the token (the daemon has one) is refused with a message shown;
  6. a daemon beyond loopback (0.0.0.0, plaintext allowed, named tokens): without a token the
     live stream is refused; with a read token entered the station page goes live, and an
     action is refused (403) with a message shown.
  5. on the loop page of a run recorded without a table (a simulated hand-held session imported
     with `calstand import`), fit and diagnose show the table-free fit: its method, the frame
     convention's parameters, and the candidates such a run can fit.
  8. the fleet page (#/fleet) against calstandd --fleet on a throw-away PostgreSQL server that
     the console's station and the fixture's line synced to: stations, units, parameters and
     records as the API has them (a screenshot console_fleet.png), and empty for a later `since`.
  7. on a fixture of three units of the demo IMU (the third with its gyro x bias ten times a
     line's limit) run, calibrated and judged: the lot page shows the yield and the verdicts, the
     parameter table with the API's numbers and the odd unit flagged, and a control chart per
     parameter drawn with every unit and the outliers ringed; a `since` after the records empties
     it; the lookup of a serial lists its records with the one in force and a certificate link
     that opens the unit's certificate. Screenshots of the lot page are saved as console_lot.png and
     console_lot_charts.png.
Screenshots and the page's HTML are saved into --out when a check fails.

Exit codes: 0 passed, 1 failed, 77 skipped (no chromium, chromedriver or selenium; a failure
instead when CALSTAND_REQUIRE_BROWSER=1).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
import urllib.error
import urllib.request

SKIP = 77
TOKEN = "console-test-token-0123456789"
VIEWER_TOKEN = "console-test-viewer-0123456789"


def browser_missing():
    """What is missing to drive a browser, or None."""
    missing = [name for name in ("chromium", "chromedriver") if not shutil.which(name)]
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("python3-selenium")
    return ", ".join(missing) or None


class Daemon:
    """calstandd on 127.0.0.1:0; the port is read from its first stdout line."""

    def __init__(self, binary, workdir, station, name="console", listen="127.0.0.1:0", extra=()):
        self.db = os.path.join(workdir, f"{name}.db")
        token_file = os.path.join(workdir, f"{name}-token")
        with open(token_file, "w") as f:
            f.write(TOKEN + "\n")
        os.chmod(token_file, 0o600)
        self.log_path = os.path.join(workdir, f"{name}-calstandd.log")
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen(
            [binary, "--db", self.db, "--listen", listen, "--token-file", token_file,
             "--station", station, *extra],
            stdout=subprocess.PIPE, stderr=self.log, text=True)
        line = self.proc.stdout.readline()
        if "listening on http://" not in line:
            raise RuntimeError(f"calstandd did not start: {line!r} (log {self.log_path})")
        # A daemon on every address is reached on loopback.
        self.url = line.strip().split("listening on ", 1)[1].replace("//0.0.0.0:", "//127.0.0.1:")

    def request(self, method, path, body=None, token=TOKEN):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.url + path, data=data, method=method)
        req.add_header("Content-Type", "application/json")
        if token:
            req.add_header("Authorization", f"Bearer {token}")
        try:
            with urllib.request.urlopen(req, timeout=120) as r:
                return r.status, json.loads(r.read() or b"null")
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read() or b"null")

    def wait_run(self, run, statuses=("completed",), timeout_s=60):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            _, doc = self.request("GET", f"/runs/{run}")
            if doc["status"] in statuses or doc["status"] in ("failed", "aborted"):
                return doc["status"]
            time.sleep(0.2)
        raise AssertionError(f"run {run} did not end within {timeout_s} s")

    def stop(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self.log.close()


def fixture_station(demo_station, workdir):
    """The demo station with a fixture of three demo IMUs (the errors the same, the noise each
    its own): CON-1001 and CON-1002 named by the station file, the third named with the run and
    built with its gyro x bias at 0.05 deg/s, ten times the line's limit."""
    with open(demo_station) as f:
        station = json.load(f)
    base = station["imus"][0]
    station["imus"] = []
    for i in range(3):
        imu = json.loads(json.dumps(base))
        imu["name"] = f"imu{i}"
        if i < 2:
            imu["serial"] = f"CON-100{i + 1}"
        else:
            imu["truth"]["parameters"]["gyro_bias.x"] = 0.05
        station["imus"].append(imu)
    path = os.path.join(workdir, "fixture.json")
    with open(path, "w") as f:
        json.dump(station, f)
    return path


def prepare_lot(daemon, calstand, workdir):
    """One six-position run of the fixture, each unit calibrated twice (the second model
    newest), the newest records judged: CON-1003 fails (its first record, never judged, stays in
    force)."""
    status, answer = daemon.request("POST", "/runs", {"procedure": "six-position", "parameters": {"capture_s": 5},
                                                     "units": {"imu2": "CON-1003"}})
    assert status == 201, answer
    run = answer["id"]
    assert daemon.wait_run(run) == "completed"
    for model in ("accel_bias,gyro_bias,earth_rate",
                  "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate"):
        subprocess.run([calstand, "calibrate", "--db", daemon.db, "--run", str(run), "--model", model,
                        "--out-dir", workdir], check=True, capture_output=True)
    status, verdict = daemon.request("POST", f"/runs/{run}/acceptance", {
        "format": "calstand-acceptance/1", "name": "console line", "limits": [
            {"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"}]})
    assert status == 200, verdict
    verdicts = [u["verdict"] for u in verdict["units"]]
    assert verdicts == ["pass", "pass", "fail"], verdicts


class Postgres:
    """A throw-away PostgreSQL server, as tests/support/postgres_server.hpp makes one: initdb into
    a temporary folder, a unix socket there and no TCP port, scram-sha-256 passwords in a
    password file; as `nobody` under root (the server refuses root)."""

    PORT = 5432  # only names the socket file

    def __init__(self, workdir):
        import glob
        # Debian's server programs with their psql first (an initdb on PATH may be a wrapper).
        found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"))
        initdb = found[-1] if found else shutil.which("initdb")
        if not initdb:
            raise RuntimeError("no PostgreSQL server (initdb): apt-get install postgresql")
        self.bin = os.path.dirname(initdb)
        self.dir = os.path.join(workdir, "pg")
        os.makedirs(self.dir)
        self.as_user = ["runuser", "-u", "nobody", "--"] if os.geteuid() == 0 else []
        owner_pw = os.path.join(self.dir, "owner.pw")
        self.owner_password = f"owner-{os.getpid()}"
        with open(owner_pw, "w") as f:
            f.write(self.owner_password + "\n")
        if os.geteuid() == 0:
            os.chmod(workdir, 0o755)
            subprocess.run(["chown", "nobody", self.dir, owner_pw], check=True)
        self.passfile = os.path.join(self.dir, "test.pgpass")
        self.add_password("calstand_owner", self.owner_password)
        subprocess.run(self.as_user + [os.path.join(self.bin, "initdb"), "-D", os.path.join(self.dir, "data"),
                                       "-U", "calstand_owner", "--auth=scram-sha-256", f"--pwfile={owner_pw}"],
                       check=True, capture_output=True)
        subprocess.run(self.as_user + [os.path.join(self.bin, "pg_ctl"), "-D", os.path.join(self.dir, "data"),
                                       "-l", os.path.join(self.dir, "server.log"), "-w", "-t", "60", "-o",
                                       f"-c listen_addresses='' -c unix_socket_directories={self.dir} -p {self.PORT}",
                                       "start"], check=True, capture_output=True)

    def add_password(self, role, password):
        with open(self.passfile, "a") as f:
            f.write(f"*:*:*:{role}:{password}\n")
        os.chmod(self.passfile, 0o600)

    def url(self, role, db):
        return f"postgresql://{role}@{self.dir.replace('/', '%2F')}:{self.PORT}/{db}"

    def sql(self, db, statement):
        env = dict(os.environ, PGPASSFILE=self.passfile)
        subprocess.run([os.path.join(self.bin, "psql"), "-h", self.dir, "-p", str(self.PORT), "-U",
                        "calstand_owner", "-d", db, "-v", "ON_ERROR_STOP=1", "-q", "-c", statement],
                       check=True, capture_output=True, env=env)

    def stop(self):
        subprocess.run(self.as_user + [os.path.join(self.bin, "pg_ctl"), "-D", os.path.join(self.dir, "data"),
                                       "-m", "fast", "-w", "stop"], capture_output=True)


def make_driver():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1100", "--no-first-run", "--disable-extensions"):
        options.add_argument(arg)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)


class ConsoleTest:
    def __init__(self, driver, daemon, out_dir):
        self.driver = driver
        self.daemon = daemon
        self.out_dir = out_dir
        self.failures = []

    # Helpers -------------------------------------------------------------------------------
    def find(self, css):
        from selenium.webdriver.common.by import By
        return self.driver.find_element(By.CSS_SELECTOR, css)

    def wait(self, what, condition, timeout_s=20):
        """Waits until condition() is truthy; returns its value, or fails naming `what`."""
        deadline = time.time() + timeout_s
        last_error = None
        while time.time() < deadline:
            try:
                value = condition()
                if value:
                    return value
            except Exception as e:  # an element not there yet, or being replaced
                last_error = e
            time.sleep(0.1)
        raise AssertionError(f"timed out ({timeout_s} s) waiting for {what}"
                             + (f" (last error: {last_error})" if last_error else ""))

    def text(self, css):
        return self.find(css).text

    def open(self, hash_route):
        self.driver.get(f"{self.daemon.url}/{hash_route}")

    def set_token(self, value, leave=False):
        field = self.find("#token")
        field.clear()
        if value:
            field.send_keys(value)
        # The field is read on 'input'; clear() alone fires none. Leaving it ('change') reads the
        # page and the stream again with the token.
        self.driver.execute_script(
            "const f = document.getElementById('token'); f.value = arguments[0];"
            "f.dispatchEvent(new Event('input'));"
            "if (arguments[1]) f.dispatchEvent(new Event('change'));", value, leave)

    def check(self, name, fn):
        started = time.time()
        try:
            fn()
            print(f"ok   {name} ({time.time() - started:.1f} s)")
        except Exception:
            self.failures.append(name)
            print(f"FAIL {name} ({time.time() - started:.1f} s)\n{traceback.format_exc()}")
            stem = os.path.join(self.out_dir, "console_test_" + name.replace(" ", "_"))
            try:
                self.driver.save_screenshot(stem + ".png")
                with open(stem + ".html", "w") as f:
                    f.write(self.driver.page_source)
                print(f"     screenshot {stem}.png, page {stem}.html")
            except Exception as e:
                print(f"     no screenshot: {e}")

    # Checks --------------------------------------------------------------------------------
    def static_files_served(self):
        """The console's files from the binary, with their types and revalidation."""
        def fetch(path, headers=None):
            req = urllib.request.Request(self.daemon.url + path, headers=headers or {})
            try:
                with urllib.request.urlopen(req, timeout=10) as r:
                    return r.status, r.headers, r.read()
            except urllib.error.HTTPError as e:
                return e.code, e.headers, e.read()
        status, headers, body = fetch("/")
        assert status == 200 and headers["Content-Type"] == "text/html; charset=utf-8", (status, headers)
        assert b"/console/app.js" in body and b"http" not in body.replace(b"http-equiv", b""), \
            "the page must load nothing from elsewhere"
        assert "default-src 'self'" in headers["Content-Security-Policy"]
        for path, kind in (("/console/app.js", "text/javascript"), ("/console/console.css", "text/css"),
                           ("/console/uPlot.iife.min.js", "text/javascript"), ("/console/uPlot.min.css", "text/css")):
            status, headers, body = fetch(path)
            assert status == 200 and headers["Content-Type"].startswith(kind), (path, status, headers["Content-Type"])
            assert headers["Cache-Control"] == "no-cache" and headers["ETag"], (path, dict(headers))
            again, _, rest = fetch(path, {"If-None-Match": headers["ETag"]})
            assert again == 304 and not rest, (path, again)
        # Byte for byte the npm file (the embedder's raw strings must not cut or alter it).
        status, _, body = fetch("/console/uPlot.iife.min.js")
        npm_file = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "console",
                                "node_modules", "uplot", "dist", "uPlot.iife.min.js")
        with open(npm_file, "rb") as f:
            assert body == f.read(), f"served uPlot ({len(body)} bytes) differs from {npm_file}"
        status, _, _ = fetch("/console/package.json")
        assert status == 404, f"/console/package.json answered {status}"

    def station_shows_live_telemetry(self):
        self.open("#/station")
        # Telemetry comes from the stream every second between runs: two messages show it is live.
        self.wait("two telemetry messages on the station page",
                  lambda: int(self.text("#telemetry-count")) >= 2, timeout_s=15)
        self.wait("the stream badge saying live", lambda: self.text("#stream-state") == "live")
        air = self.wait("the chamber air temperature", lambda: "°C" in self.text("#chamber-air") and self.text("#chamber-air"))
        _, station = self.daemon.request("GET", "/station")
        expected = station["telemetry"]["chamber"]["air_c"]
        shown = float(air.split()[0])
        assert abs(shown - expected) < 1.0, f"chamber air shown {shown}, the daemon says {expected}"
        assert "table" in self.text("#devices"), "the devices table lists no table"
        # uPlot drew the temperature plot (a canvas inside .uplot).
        self.wait("a drawn plot", lambda: self.find(".uplot canvas"))

    def submitted_run_completes(self):
        from selenium.webdriver.support.ui import Select
        self.open("#/runs")
        self.set_token(TOKEN)
        self.wait("the procedure list", lambda: self.find("#procedure option"))
        Select(self.find("#procedure")).select_by_value("six-position")
        capture = self.wait("the capture_s field", lambda: self.find("#param-capture_s"))
        # A value below the parameter's minimum is shown at its field by the preview.
        capture.clear()
        capture.send_keys("-5")
        self.find("#preview").click()
        self.wait("the violation at capture_s",
                  lambda: "invalid" in capture.get_attribute("class") and self.text("#error-capture_s"))
        assert not self.find("#submit").is_enabled(), "submit enabled with a violation"
        capture.clear()
        capture.send_keys("5")
        self.find("#preview").click()
        self.wait("a plan within limits", lambda: self.find("#plan-ok"))
        assert self.text("#plan-duration"), "no duration shown"
        self.wait("submit enabled", lambda: self.find("#submit").is_enabled())
        self.find("#submit").click()
        self.wait("the run page", lambda: "#/runs/" in self.driver.current_url)
        run = int(self.driver.current_url.rsplit("/", 1)[1])
        self.wait("the run completed, shown live",
                  lambda: self.text("#run-status") == "completed", timeout_s=60)
        _, doc = self.daemon.request("GET", f"/runs/{run}")
        assert doc["status"] == "completed" and doc["parameters"]["capture_s"] == 5, doc

    def recommended_term_lowers_chi2(self):
        from selenium.webdriver.common.by import By
        status, _ = self.daemon.request("GET", "/catalogue")
        assert status == 200, f"GET /catalogue answers {status}: this calstandd has no analysis routes"
        # The demo campaign's thermal calibration (scripts/demo-campaign.sh): the demo IMU's
        # temperature drift is what the classical model lacks.
        status, answer = self.daemon.request("POST", "/runs", {"procedure": "thermal-calibration", "parameters": {
            "temperatures": [-10, 25, 60], "soak_s": 600, "capture_s": 20, "outer_angles": [0, 90, 180, 270],
            "inner_angles": [0, 90], "rates": [30, 100, 300]}})
        assert status == 201, answer
        run = answer["id"]
        assert self.daemon.wait_run(run) == "completed"
        self.open(f"#/loop/{run}")
        self.set_token(TOKEN)
        self.wait("the catalogue", lambda: self.find("#term-gyro_bias").is_selected())
        self.find("#fit").click()
        before = float(self.wait("the first fit's chi2/dof", lambda: self.text("#chi2-dof").strip() not in ("", "–")
                                 and self.text("#chi2-dof"), timeout_s=60))
        self.wait("the groups of steps", lambda: self.find("#groups"))
        self.find("#diagnose").click()
        self.wait("the candidates", lambda: self.find("#candidates"), timeout_s=60)
        model = [box.get_attribute("id")[len("term-"):] for box in
                 self.driver.find_elements(By.CSS_SELECTOR, "#terms input[type=checkbox]") if box.is_selected()]
        _, diagnosis = self.daemon.request("POST", f"/runs/{run}/diagnose",
                                           {"model": model, "custom": [], "sensor": "both", "white_noise": False})
        recommended = diagnosis["recommended"]
        assert recommended, f"diagnose recommends nothing: {diagnosis.get('advice')}"
        self.find(f"#add-{recommended.replace(':', '-')}").click()
        self.wait("the recommended term in the model", lambda: self.find(f"#term-{recommended.split(':')[0]}").is_selected())
        after_text = self.wait("the new chi2/dof", lambda: self.text("#chi2-dof") != f"{before:g}" and
                               self.text("#busy").startswith("fitting took") and self.text("#chi2-dof"), timeout_s=60)
        after = float(after_text)
        _, fit = self.daemon.request("POST", f"/runs/{run}/fits", {
            "model": model + [recommended], "custom": [], "sensor": "both", "white_noise": False})
        assert after < before, f"chi2/dof did not fall: {before} -> {after}"
        assert abs(after - fit["chi2_dof"]) <= 1e-3 * fit["chi2_dof"], \
            f"shown chi2/dof {after}, the API's {fit['chi2_dof']}"
        # The history shows the fits as a falling curve (one row per fit).
        self.wait("the history rows", lambda: len(self.driver.find_elements(By.CSS_SELECTOR, "#history tbody tr")) >= 2)

    def table_free_run_in_the_loop(self):
        workdir = os.path.dirname(self.daemon.db)
        session = os.path.join(workdir, "hand-session")
        subprocess.run([self.calstand, "sim-session", "--kind", "hand", "--poses", "12", "--rate", "200",
                        "--seed", "3", "--out", session], check=True, capture_output=True)
        imported = subprocess.run([self.calstand, "import", session, "--db", self.daemon.db, "--json"],
                                  check=True, capture_output=True, text=True)
        run = json.loads(imported.stdout)["run"]
        self.open(f"#/loop/{run}")
        self.set_token(TOKEN)
        self.wait("the catalogue", lambda: self.find("#term-gyro_bias").is_selected())
        self.find("#fit").click()
        self.wait("the table-free fit", lambda: "no table" in self.text("#quality"), timeout_s=60)
        quality = self.text("#quality")
        assert "gravity_norm" in quality and "earth_rate is no fitted term" in quality, quality
        self.wait("the frame convention's parameters", lambda: "fixed by convention" in self.text("#parameters"))
        self.find("#diagnose").click()
        self.wait("the candidates", lambda: self.find("#candidates"), timeout_s=60)
        candidates = self.text("#candidates")
        assert "gyro_g_sensitivity" in candidates and "accel_quadratic" in candidates, candidates

    def lot_page_charts_every_parameter(self):
        from selenium.webdriver.common.by import By
        self.open("#/lot")
        lot = self.daemon.request("GET", "/lot")[1]
        names = [p["name"] for p in lot["parameters"]]
        assert len(lot["units"]) == 3 and names, f"the fixture's lot: {lot}"
        rows = self.wait("the parameter table", lambda: self.driver.find_elements(
            By.CSS_SELECTOR, "#lot-parameters tbody tr"))
        assert [r.get_attribute("data-parameter") for r in rows] == names, \
            f"table rows {[r.get_attribute('data-parameter') for r in rows]}, the lot's {names}"
        self.wait("the yield", lambda: self.text("#yield") == "66.7 %")
        verdicts = self.text("#verdicts")
        assert "2 pass" in verdicts and "1 fail" in verdicts, verdicts
        for row, p in zip(rows, lot["parameters"]):
            cells = [c.text for c in row.find_elements(By.CSS_SELECTOR, "td")]
            assert cells[2] == "3", (p["name"], cells)
            for shown, key in ((cells[3], "mean"), (cells[4], "std"), (cells[5], "median")):
                assert abs(float(shown) - p[key]) <= 1e-4 * abs(p[key]) + 1e-300, \
                    f"{p['name']} {key}: shown {shown}, the API's {p[key]}"
            for o in p["outliers"]:
                assert o["serial"] in cells[8], f"{p['name']}: {o['serial']} not flagged in '{cells[8]}'"
            if not p["outliers"]:
                assert cells[8] == "–", (p["name"], cells[8])
        odd = next(p for p in lot["parameters"] if p["name"] == "gyro_bias.x")
        assert [o["serial"] for o in odd["outliers"]] == ["CON-1003"], odd["outliers"]
        odd_row = rows[names.index("gyro_bias.x")].text
        assert "CON-1003" in odd_row and "fail" in odd_row, odd_row
        # One drawn chart per parameter, each with every unit and the parameter's outliers.
        charts = self.wait("a control chart per parameter", lambda: (lambda c: len(c) == len(names) and c)(
            self.driver.find_elements(By.CSS_SELECTOR, "#control-charts .control-chart")))
        for chart, p in zip(charts, lot["parameters"]):
            assert chart.get_attribute("data-parameter") == p["name"]
            assert chart.find_elements(By.CSS_SELECTOR, ".uplot canvas"), f"{p['name']}: no plot drawn"
            assert chart.get_attribute("data-units") == "3", (p["name"], chart.get_attribute("data-units"))
            assert chart.get_attribute("data-outliers") == str(len(p["outliers"])), \
                (p["name"], chart.get_attribute("data-outliers"), p["outliers"])
        self.driver.execute_script("window.scrollTo(0, 0)")
        self.driver.save_screenshot(os.path.join(self.out_dir, "console_lot.png"))
        self.driver.execute_script(
            "document.querySelector('.control-chart[data-parameter=\"gyro_bias.x\"]').parentElement.scrollIntoView()")
        self.driver.save_screenshot(os.path.join(self.out_dir, "console_lot_charts.png"))
        # A lot that starts after every record is empty.
        self.driver.execute_script(
            "const f = document.getElementById('since'); f.value = '2999-12-31';"
            "f.dispatchEvent(new Event('change'));")
        self.wait("the lot since 2999-12-31 in the address", lambda: self.driver.current_url.endswith("#/lot/2999-12-31"))
        self.wait("an empty lot", lambda: self.text("#lot-size") == "0")
        assert not self.driver.find_elements(By.CSS_SELECTOR, "#control-charts .control-chart"), "charts of an empty lot"

    def unit_lookup_links_certificates(self):
        from selenium.webdriver.common.by import By
        self.open("#/lot")
        field = self.wait("the serial field", lambda: self.find("#serial"))
        field.send_keys("CON-1003")
        self.find("#lookup").click()
        self.wait("the unit's page", lambda: self.text("#unit-serial") == "CON-1003")
        answer = self.daemon.request("GET", "/units/CON-1003/calibrations")[1]
        rows = self.wait("the unit's records", lambda: self.driver.find_elements(By.CSS_SELECTOR, "#records tbody tr"))
        assert [int(r.get_attribute("data-record")) for r in rows] == [c["id"] for c in answer["calibrations"]], \
            (answer, [r.text for r in rows])
        # Its newest record failed: the older one, never judged, is in force.
        assert "fail" in rows[0].text and "in force" not in rows[0].text, rows[0].text
        assert "in force" in rows[1].text, rows[1].text
        assert f"record #{answer['calibrations'][1]['id']}" in self.text("#in-force"), self.text("#in-force")
        link = rows[0].find_element(By.CSS_SELECTOR, "a.certificate").get_attribute("href")
        assert link.endswith(f"/calibrations/{answer['calibrations'][0]['id']}/certificate"), link
        with urllib.request.urlopen(link, timeout=120) as r:
            page = r.read().decode()
            assert r.status == 200 and r.headers["Content-Type"].startswith("text/html"), (r.status, r.headers)
        assert "CON-1003" in page, "the certificate does not name the unit"

    def action_without_token_refused(self):
        status, answer = self.daemon.request("POST", "/runs", {"procedure": "six-position",
                                                                "parameters": {"capture_s": 30000}})
        assert status == 201, answer
        run = answer["id"]
        self.open(f"#/runs/{run}")
        self.set_token("")
        self.wait("the abort button enabled", lambda: self.find("#abort").is_enabled())
        self.find("#abort").click()
        message = self.wait("the refusal message", lambda: self.find("#message").is_displayed() and self.text("#message"))
        assert "401" in message and "token" in message.lower(), message
        _, doc = self.daemon.request("GET", f"/runs/{run}")
        assert doc["status"] not in ("aborted",), f"the run was aborted without the token: {doc['status']}"
        self.daemon.request("POST", f"/runs/{run}/abort", {"reason": "test over"})

    def fleet_page_shows_the_central_database(self):
        """#/fleet against calstandd --fleet on a central database two stations synced to: the
        stations, units, each parameter's spread per station and the newest records, as the
        API (the code of `calstand fleet`) has them; a `since` after everything empties it."""
        from selenium.webdriver.common.by import By
        self.open("#/fleet")
        stations = self.daemon.request("GET", "/fleet")[1]["stations"]
        assert sorted(s["name"] for s in stations) == ["line-a", "line-b"], stations
        rows = self.wait("the stations table", lambda: (lambda r: len(r) == len(stations) and r)(
            self.driver.find_elements(By.CSS_SELECTOR, "#fleet-stations tbody tr")))
        for row, s in zip(rows, stations):
            cells = [c.text for c in row.find_elements(By.CSS_SELECTOR, "td")]
            assert row.get_attribute("data-station") == s["name"], (row.get_attribute("data-station"), s)
            assert cells[1] == str(s["runs"]) and cells[3] == str(s["calibrations"]), (cells, s)
            assert cells[6] == s["uuid"], (cells, s)
        units = self.daemon.request("GET", "/fleet/units")[1]["units"]
        unit_rows = self.wait("the units table", lambda: (lambda r: len(r) == len(units) and r)(
            self.driver.find_elements(By.CSS_SELECTOR, "#fleet-units tbody tr")))
        assert [r.get_attribute("data-serial") for r in unit_rows] == [u["serial"] for u in units], \
            ([r.get_attribute("data-serial") for r in unit_rows], units)
        odd = next(r for r in unit_rows if r.get_attribute("data-serial") == "CON-1003")
        assert "fail" in odd.text and "line-a" in odd.text, odd.text
        parameters = self.daemon.request("GET", "/fleet/parameters")[1]["parameters"]
        assert parameters, "no parameter in the fleet"
        parameter_rows = self.driver.find_elements(By.CSS_SELECTOR, "#fleet-parameters tbody tr")
        assert len(parameter_rows) == sum(len(p["stations"]) for p in parameters), len(parameter_rows)
        first = parameters[0]["stations"][0]
        cells = [c.text for c in parameter_rows[0].find_elements(By.CSS_SELECTOR, "td")]
        assert cells[2] == first["station"] and cells[3] == str(first["n"]), (cells, first)
        assert abs(float(cells[4]) - first["mean"]) <= 1e-4 * abs(first["mean"]) + 1e-300, (cells, first)
        records = self.daemon.request("GET", "/fleet/calibrations")[1]["calibrations"]
        record_rows = self.driver.find_elements(By.CSS_SELECTOR, "#fleet-records tbody tr")
        assert len(record_rows) == min(50, len(records)) and records, (len(record_rows), len(records))
        self.driver.save_screenshot(os.path.join(self.out_dir, "console_fleet.png"))
        self.driver.execute_script(
            "const f = document.getElementById('fleet-since'); f.value = '2999-12-31';"
            "f.dispatchEvent(new Event('change'));")
        self.wait("the fleet since 2999-12-31 in the address",
                  lambda: self.driver.current_url.endswith("#/fleet/2999-12-31"))
        self.wait("no units made since", lambda: "No unit with a serial" in self.text("#page"))
        assert not self.driver.find_elements(By.CSS_SELECTOR, "#fleet-units tbody tr"), "units made after 2999"

    def read_token_beyond_loopback(self):
        self.open("#/station")
        self.set_token("", leave=True)
        self.wait("the stream refused without a token", lambda: self.text("#stream-state") == "closed")
        self.set_token(VIEWER_TOKEN, leave=True)
        self.wait("the stream live with the read token", lambda: self.text("#stream-state") == "live")
        self.wait("two telemetry messages on the station page",
                  lambda: int(self.text("#telemetry-count")) >= 2, timeout_s=15)
        status, answer = self.daemon.request("POST", "/runs", {"procedure": "six-position",
                                                                "parameters": {"capture_s": 30000}})
        assert status == 201, answer
        run = answer["id"]
        self.open(f"#/runs/{run}")
        self.wait("the abort button enabled", lambda: self.find("#abort").is_enabled())
        self.find("#abort").click()
        message = self.wait("the refusal message", lambda: self.find("#message").is_displayed() and self.text("#message"))
        assert "403" in message and "only read" in message, message
        _, doc = self.daemon.request("GET", f"/runs/{run}")
        assert doc["status"] != "aborted", "a read token aborted the run"
        self.daemon.request("POST", f"/runs/{run}/abort", {"reason": "test over"})


def run_fleet_page(driver, args, workdir, outer):
    """The console's own station (line-b) and the fixture's line (line-a), synced to a fresh
    central database by their own station roles; a daemon with --fleet (a reader role) shows it."""
    pg = Postgres(workdir)
    fleet = None
    try:
        pg.sql("postgres", "CREATE DATABASE fleet")
        subprocess.run([args.calstand, "fleet", "migrate", "--to", pg.url("calstand_owner", "fleet"),
                        "--password-file", pg.passfile], check=True, capture_output=True)
        for role, group in (("station_a", "calstand_station"), ("station_b", "calstand_station"),
                            ("dashboard", "calstand_reader")):
            pg.sql("fleet", f"CREATE ROLE {role} LOGIN PASSWORD 'pw-{role}' IN ROLE {group}")
            pg.add_password(role, f"pw-{role}")
        for db, role, name in ((os.path.join(workdir, "line.db"), "station_a", "line-a"),
                               (os.path.join(workdir, "console.db"), "station_b", "line-b")):
            synced = subprocess.run([args.calstand, "sync", "--db", db, "--to", pg.url(role, "fleet"),
                                     "--password-file", pg.passfile, "--name", name],
                                    capture_output=True, text=True)
            assert synced.returncode == 0, synced.stdout + synced.stderr
        fleet = Daemon(args.calstandd, workdir, args.station, name="fleet",
                       extra=("--fleet", pg.url("dashboard", "fleet"), "--fleet-password-file", pg.passfile))
        page = ConsoleTest(driver, fleet, args.out)
        page.fleet_page_shows_the_central_database()
    finally:
        if fleet:
            fleet.stop()
        pg.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calstandd", required=True)
    parser.add_argument("--calstand", required=True, help="the command line (sim-session, import)")
    parser.add_argument("--station", required=True, help="station file (the demo station)")
    parser.add_argument("--out", required=True, help="directory for screenshots on failure")
    args = parser.parse_args()

    missing = browser_missing()
    if missing:
        if os.environ.get("CALSTAND_REQUIRE_BROWSER") == "1":
            print(f"console_test: {missing} missing, and CALSTAND_REQUIRE_BROWSER=1: failing")
            return 1
        print(f"console_test: SKIPPED: {missing} not installed (scripts/setup-deps.sh installs them)")
        return SKIP

    os.makedirs(args.out, exist_ok=True)
    started = time.time()
    with tempfile.TemporaryDirectory(prefix="calstand-console-") as workdir:
        daemon = Daemon(args.calstandd, workdir, args.station)
        driver = None
        try:
            driver = make_driver()
            test = ConsoleTest(driver, daemon, args.out)
            test.calstand = args.calstand
            test.check("static files served", test.static_files_served)
            test.check("station shows live telemetry", test.station_shows_live_telemetry)
            test.check("submitted run completes", test.submitted_run_completes)
            test.check("recommended term lowers chi2", test.recommended_term_lowers_chi2)
            test.check("action without token refused", test.action_without_token_refused)
            test.check("table-free run in the loop", test.table_free_run_in_the_loop)
            line = Daemon(args.calstandd, workdir, fixture_station(args.station, workdir), name="line")
            try:
                line_test = ConsoleTest(driver, line, args.out)
                line_test.check("fixture run calibrated and judged", lambda: prepare_lot(line, args.calstand, workdir))
                if not line_test.failures:
                    line_test.check("lot page charts every parameter", line_test.lot_page_charts_every_parameter)
                    line_test.check("unit lookup links certificates", line_test.unit_lookup_links_certificates)
                test.failures += line_test.failures
            finally:
                line.stop()
            fleet_test = ConsoleTest(driver, daemon, args.out)
            fleet_test.check("fleet page shows the central database",
                             lambda: run_fleet_page(driver, args, workdir, fleet_test))
            test.failures += fleet_test.failures
            with open(os.path.join(workdir, "tokens.json"), "w") as f:
                json.dump({"format": "calstand-tokens/1",
                           "tokens": [{"name": "screen", "role": "read", "token": VIEWER_TOKEN}]}, f)
            os.chmod(os.path.join(workdir, "tokens.json"), 0o600)
            lan = Daemon(args.calstandd, workdir, args.station, name="lan", listen="0.0.0.0:0",
                         extra=("--allow-plaintext", "--tokens", os.path.join(workdir, "tokens.json")))
            try:
                lan_test = ConsoleTest(driver, lan, args.out)
                lan_test.check("read token beyond loopback", lan_test.read_token_beyond_loopback)
                test.failures += lan_test.failures
            finally:
                lan.stop()
            for entry in driver.get_log("browser"):
                if entry.get("level") == "SEVERE":
                    print(f"browser console: {entry.get('message')}")
        finally:
            if driver:
                driver.quit()
            daemon.stop()
            if 'test' not in locals() or test.failures:
                shutil.copy(daemon.log_path, os.path.join(args.out, "console_test_calstandd.log"))
    print(f"console_test: {time.time() - started:.1f} s")
    return 1 if test.failures else 0


if __name__ == "__main__":
    sys.exit(main())
