// Security of calstandd (issue 16): named tokens with roles (reads need one beyond loopback,
// actions an operator token, every action recorded with the token's name), TLS (https with a
// throw-away certificate, plaintext beyond loopback refused at startup), path traversal in
// every parameter that names a file, and slow or oversized clients that must not hold the
// engine or the other clients.
#include <gtest/gtest.h>
#include <poll.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "cli_runner.hpp"
#include "core/error.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon_test_support.hpp"
#include "in_process_daemon.hpp"

namespace daemon_security {
namespace {

using calstand::daemon::api::ApiOptions;
using calstand::daemon::api::Role;
using calstand::testing::InProcessDaemon;
using calstand::testing::wait_until;

constexpr const char* kViewerSecret = "viewer-secret-0123456789";
constexpr const char* kLabOpSecret = "lab-op-secret-0123456789";

// Two named tokens; listening on every address (beyond loopback), in plaintext unless a test
// gives a certificate.
ApiOptions beyond_loopback() {
  ApiOptions o;
  o.host = "0.0.0.0";
  o.tokens = {{"viewer", Role::kRead, kViewerSecret}, {"lab-op", Role::kOperator, kLabOpSecret}};
  o.allow_plaintext = true;
  return o;
}

struct Answer {
  int status = 0;  // 0: no answer
  nlohmann::json body;
  std::string raw;
  httplib::Headers headers;
};

Answer answer_of(const httplib::Result& res) {
  Answer a;
  if (!res) return a;
  a.status = res->status;
  a.raw = res->body;
  a.headers = res->headers;
  a.body = nlohmann::json::parse(res->body, nullptr, false);
  return a;
}

// A request to 127.0.0.1:port with `token` as bearer (none when empty).
Answer call(int port, const std::string& method, const std::string& path,
            const std::string& token = "", const std::string& body = "{}") {
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(30, 0);
  httplib::Headers headers{{"X-Calstand-Operator", "alice"}};
  if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
  if (method == "GET") return answer_of(c.Get(path.c_str(), headers));
  return answer_of(c.Post(path.c_str(), headers, body, "application/json"));
}

std::string run_status(int port, std::int64_t run) {
  const Answer a = call(port, "GET", "/runs/" + std::to_string(run), kViewerSecret);
  return a.status == 200 ? a.body.value("status", "") : "";
}

bool any_event_by(const nlohmann::json& events, const std::string& source_part,
                  const std::string& message_part) {
  for (const auto& e : events) {
    if (e.value("source", "").find(source_part) != std::string::npos &&
        e.value("message", "").find(message_part) != std::string::npos)
      return true;
  }
  return false;
}

TEST(DaemonSecurity, BeyondLoopbackReadsNeedATokenAndActionsAnOperatorToken) {
  InProcessDaemon d(calstand::testing::fresh_dir("sec-roles") + "/station.db", beyond_loopback());
  const int port = d.port();

  // Reads: refused without a token, or with one the daemon does not know; any role reads.
  for (const std::string path : {"/station", "/runs", "/runs/1", "/procedures", "/catalogue",
                                 "/runs/1/export", "/calibrations/1"}) {
    const Answer none = call(port, "GET", path);
    EXPECT_EQ(none.status, 401) << path;
    EXPECT_EQ(none.body.value("where", ""), "Authorization") << path << ": " << none.raw;
    EXPECT_TRUE(none.headers.count("WWW-Authenticate")) << path;
    EXPECT_EQ(call(port, "GET", path, "not-a-token-of-this-daemon").status, 401) << path;
  }
  EXPECT_EQ(call(port, "GET", "/station", kViewerSecret).status, 200);
  EXPECT_EQ(call(port, "GET", "/station", kLabOpSecret).status, 200);
  // The token as a query parameter, for what a browser opens by itself.
  EXPECT_EQ(call(port, "GET", std::string("/station?access_token=") + kViewerSecret).status, 200);
  // The console's own files hold no station data: a browser loads them before a token is typed.
  EXPECT_EQ(call(port, "GET", "/").status, 200);
  EXPECT_EQ(call(port, "GET", "/console/app.js").status, 200);

  // The live stream needs a token too.
  EXPECT_EQ(call(port, "GET", "/events").status, 401);
  {
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(10, 0);
    std::string got;
    c.Get((std::string("/events?access_token=") + kViewerSecret).c_str(),
          [&](const char* data, std::size_t n) {
            got.append(data, n);
            return got.find("event: station") == std::string::npos;
          });
    EXPECT_NE(got.find("event: station"), std::string::npos) << got;
  }

  // Actions: 401 without a token, 403 with a read token, and never a token from the query.
  const std::string submit =
      nlohmann::json{{"procedure", "six-position"}, {"parameters", {{"capture_s", 300}}}}.dump();
  EXPECT_EQ(call(port, "POST", "/runs", "", submit).status, 401);
  const Answer read_only = call(port, "POST", "/runs", kViewerSecret, submit);
  EXPECT_EQ(read_only.status, 403) << read_only.raw;
  EXPECT_NE(read_only.body.value("error", "").find("'viewer' may only read"), std::string::npos)
      << read_only.raw;
  EXPECT_EQ(call(port, "POST", "/plan", kViewerSecret, submit).status, 403);
  EXPECT_EQ(
      call(port, "POST", std::string("/runs?access_token=") + kLabOpSecret, "", submit).status,
      401);
  EXPECT_EQ(call(port, "GET", "/runs", kViewerSecret).body.size(), 0u);  // nothing was queued

  // The operator acts; the records carry the token's name.
  const Answer submitted = call(port, "POST", "/runs", kLabOpSecret, submit);
  ASSERT_EQ(submitted.status, 201) << submitted.raw;
  const std::int64_t run = submitted.body["id"];
  EXPECT_EQ(call(port, "POST", "/runs/" + std::to_string(run) + "/abort", kViewerSecret,
                 R"({"reason": "viewer tries"})")
                .status,
            403);
  ASSERT_TRUE(wait_until([&] { return run_status(port, run) == "running"; }));
  const Answer aborted = call(port, "POST", "/runs/" + std::to_string(run) + "/abort", kLabOpSecret,
                              R"({"reason": "enough"})");
  ASSERT_EQ(aborted.status, 202) << aborted.raw;
  ASSERT_TRUE(wait_until([&] { return run_status(port, run) == "aborted"; }));
  const Answer status = call(port, "GET", "/runs/" + std::to_string(run), kViewerSecret);
  EXPECT_EQ(status.body.value("exit_reason", ""),
            "aborted by alice@127.0.0.1 (token lab-op): enough")
      << status.raw;
  const Answer events =
      call(port, "GET", "/runs/" + std::to_string(run) + "/events", kViewerSecret);
  EXPECT_TRUE(any_event_by(events.body, "(token lab-op)", "submitted six-position")) << events.raw;
  EXPECT_FALSE(any_event_by(events.body, "(token viewer)", "")) << events.raw;
}

// Mangled credentials (the operator's secret with bytes flipped, cut, extended; other schemes;
// junk) are refused with 401, never taken for a token and never a failure inside.
TEST(DaemonSecurity, MangledTokensAreRefused) {
  InProcessDaemon d(calstand::testing::fresh_dir("sec-mangled") + "/station.db", beyond_loopback());
  std::mt19937 rng(16);
  auto pick = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const std::string secret = kLabOpSecret;
  const std::string plan = R"({"procedure": "two-position"})";
  for (int i = 0; i < 200; ++i) {
    std::string header;
    switch (pick(5)) {
      case 0: {  // a byte flipped (never to itself)
        std::string t = secret;
        const std::size_t at = pick(t.size());
        t[at] = static_cast<char>(t[at] ^ static_cast<char>(1 + pick(127)));
        header = "Bearer " + t;
        break;
      }
      case 1:  // cut short, or longer
        header = "Bearer " + (pick(2) == 0 ? secret.substr(0, pick(secret.size()))
                                           : secret + std::string(1 + pick(8), 'x'));
        break;
      case 2:  // another scheme, or the scheme spelt otherwise
        header = std::vector<std::string>{"Basic ", "bearer ", "Bearer  ", "Token ", ""}[pick(5)] +
                 secret;
        break;
      case 3:  // the read token where an action needs an operator one (403, counted apart)
        header = std::string("Bearer ") + kViewerSecret;
        break;
      default: {  // junk
        header = "Bearer ";
        for (std::size_t k = 0, n = pick(64); k < n; ++k)
          header += static_cast<char>(0x20 + pick(0x5f));
      }
    }
    httplib::Client c("127.0.0.1", d.port());
    c.set_read_timeout(30, 0);
    const Answer a =
        answer_of(c.Post("/plan", {{"Authorization", header}}, plan, "application/json"));
    const bool viewer = header == std::string("Bearer ") + kViewerSecret;
    EXPECT_EQ(a.status, viewer ? 403 : 401) << header << ": " << a.raw;
    const Answer r = answer_of(c.Get("/station", {{"Authorization", header}}));
    EXPECT_EQ(r.status, viewer ? 200 : 401) << header << ": " << r.raw;
  }
  EXPECT_EQ(call(d.port(), "POST", "/plan", kLabOpSecret, plan).status, 200);
}

TEST(DaemonSecurity, OnLoopbackReadsStayOpenAndActionsNeedTheOperatorToken) {
  ApiOptions o = beyond_loopback();
  o.host = "127.0.0.1";
  o.allow_plaintext = false;
  InProcessDaemon d(calstand::testing::fresh_dir("sec-loopback") + "/station.db", o);
  const std::string plan = R"({"procedure": "two-position"})";
  EXPECT_EQ(call(d.port(), "GET", "/station").status, 200);
  EXPECT_EQ(call(d.port(), "POST", "/plan", "", plan).status, 401);
  EXPECT_EQ(call(d.port(), "POST", "/plan", kViewerSecret, plan).status, 403);
  EXPECT_EQ(call(d.port(), "POST", "/plan", kLabOpSecret, plan).status, 200);

  // Without any token on loopback everything is open, as before tokens had names.
  ApiOptions open;
  InProcessDaemon o2(calstand::testing::fresh_dir("sec-open") + "/station.db", open);
  EXPECT_EQ(call(o2.port(), "POST", "/plan", "", plan).status, 200);
}

// A fit asked for through the API writes the run's history: an operator action, recorded.
TEST(DaemonSecurity, FitsAreOperatorActionsRecordedWithTheTokensName) {
  InProcessDaemon d(calstand::testing::fresh_dir("sec-fit") + "/station.db", beyond_loopback());
  const int port = d.port();
  const Answer submitted = call(port, "POST", "/runs", kLabOpSecret,
                                R"({"procedure": "six-position", "parameters": {"capture_s": 5}})");
  ASSERT_EQ(submitted.status, 201) << submitted.raw;
  const std::string run = std::to_string(submitted.body["id"].get<std::int64_t>());
  ASSERT_TRUE(wait_until([&] { return run_status(port, std::stoll(run)) == "completed"; }));
  const std::string body = R"({"model": ["accel_bias", "accel_scale"], "sensor": "accel"})";
  EXPECT_EQ(call(port, "POST", "/runs/" + run + "/fits", kViewerSecret, body).status, 403);
  const Answer fit = call(port, "POST", "/runs/" + run + "/fits", kLabOpSecret, body);
  ASSERT_EQ(fit.status, 200) << fit.raw;
  const Answer events = call(port, "GET", "/runs/" + run + "/events", kViewerSecret);
  EXPECT_TRUE(any_event_by(events.body, "alice@127.0.0.1 (token lab-op)", "fit requested"))
      << events.raw;
}

// A self-signed certificate for 127.0.0.1, made with the openssl command for this test only.
struct ThrowAwayCertificate {
  std::string cert;
  std::string key;
  explicit ThrowAwayCertificate(const std::string& dir)
      : cert(dir + "/cert.pem"), key(dir + "/key.pem") {
    const std::string command =
        "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 1 "
        "-subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1,DNS:localhost -keyout " +
        key + " -out " + cert + " 2>" + dir + "/openssl.txt";
    ok = std::system(command.c_str()) == 0;
  }
  bool ok = false;
};

TEST(DaemonSecurity, HttpsWithTheCertificateAndNothingInPlaintext) {
  const std::string dir = calstand::testing::fresh_dir("sec-tls");
  const ThrowAwayCertificate certificate(dir);
  ASSERT_TRUE(certificate.ok) << calstand::testing::read_text(dir + "/openssl.txt");
  ApiOptions o = beyond_loopback();
  o.allow_plaintext = false;
  o.tls_cert_file = certificate.cert;
  o.tls_key_file = certificate.key;
  InProcessDaemon d(dir + "/station.db", o);
  const std::string url = "https://127.0.0.1:" + std::to_string(d.port());

  httplib::Client tls(url);
  tls.set_ca_cert_path(certificate.cert.c_str());
  tls.enable_server_certificate_verification(true);
  tls.set_read_timeout(30, 0);
  tls.set_bearer_token_auth(kViewerSecret);
  const Answer station = answer_of(tls.Get("/station"));
  EXPECT_EQ(station.status, 200) << station.raw;
  tls.set_bearer_token_auth(kLabOpSecret);
  EXPECT_EQ(
      answer_of(tls.Post("/plan", R"({"procedure": "two-position"})", "application/json")).status,
      200);

  // A client that does not trust the certificate gets no answer; a plaintext one neither.
  httplib::Client untrusting(url);
  untrusting.enable_server_certificate_verification(true);
  untrusting.set_ca_cert_path((dir + "/no-such-ca.pem").c_str());
  EXPECT_FALSE(untrusting.Get("/station"));
  EXPECT_NE(call(d.port(), "GET", "/station", kViewerSecret).status, 200);

  // The command line reaches it with --ca-file and the token.
  setenv("CALSTAND_TOKEN", kViewerSecret, 1);
  const auto status =
      calstand::testing::run("status --daemon " + url + " --ca-file " + certificate.cert);
  EXPECT_EQ(status.exit_code, 0) << status.out;
  EXPECT_NE(status.out.find("station"), std::string::npos) << status.out;
  const auto plain =
      calstand::testing::run("status --daemon 127.0.0.1:" + std::to_string(d.port()));
  EXPECT_NE(plain.exit_code, 0) << plain.out;
  // A read token cannot submit; an operator token submits and watches, recorded by its name.
  const std::string tls_options = " --daemon " + url + " --ca-file " + certificate.cert;
  const auto refused =
      calstand::testing::run("submit six-position --set capture_s=5" + tls_options);
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("HTTP 403"), std::string::npos) << refused.out;
  setenv("CALSTAND_TOKEN", kLabOpSecret, 1);
  const auto submitted =
      calstand::testing::run("submit six-position --set capture_s=5 --operator bob" + tls_options);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out;
  const auto watched = calstand::testing::run("watch 1" + tls_options);
  EXPECT_EQ(watched.exit_code, 0) << watched.out;
  EXPECT_NE(watched.out.find("run 1 completed"), std::string::npos) << watched.out;
  tls.set_bearer_token_auth(kViewerSecret);
  const Answer events = answer_of(tls.Get("/runs/1/events"));
  EXPECT_TRUE(any_event_by(events.body, "bob@127.0.0.1 (token lab-op)", "submitted")) << events.raw;
  // A token the daemon does not know: refused at once, not retried.
  setenv("CALSTAND_TOKEN", "not-a-token-of-this-daemon", 1);
  const auto unknown = calstand::testing::run("watch 1 --reconnect 600" + tls_options);
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("HTTP 401"), std::string::npos) << unknown.out;
  unsetenv("CALSTAND_TOKEN");
}

TEST(DaemonSecurity, PlaintextOrNoTokenBeyondLoopbackIsRefusedAtStartup) {
  ApiOptions o = beyond_loopback();
  o.allow_plaintext = false;
  try {
    o.validate();
    ADD_FAILURE() << "plaintext beyond loopback accepted";
  } catch (const calstand::core::InputError& e) {
    EXPECT_EQ(e.where(), "--listen");
    EXPECT_NE(std::string(e.what()).find("TLS is required"), std::string::npos) << e.what();
  }
  o.tls_cert_file = "cert.pem";  // half a pair
  EXPECT_THROW(o.validate(), calstand::core::InputError);

  // A certificate file that is not one: refused naming the option.
  const std::string dir = calstand::testing::fresh_dir("sec-badcert");
  calstand::testing::write_text(dir + "/cert.pem", "not a certificate\n");
  calstand::testing::write_text(dir + "/key.pem", "not a key\n");
  ApiOptions bad = beyond_loopback();
  bad.allow_plaintext = false;
  bad.tls_cert_file = dir + "/cert.pem";
  bad.tls_key_file = dir + "/key.pem";
  try {
    InProcessDaemon d(dir + "/station.db", bad);
    ADD_FAILURE() << "a daemon started with a broken certificate";
  } catch (const calstand::core::InputError& e) {
    EXPECT_EQ(e.where(), "--tls-cert") << e.what();
  }

  // calstandd itself: exit 2 with the reason, before it opens anything.
  const std::string command = std::string("env CALSTAND_TOKEN=") + kLabOpSecret + " " +
                              CALSTANDD_BIN + " --db " + dir + "/station.db --listen 0.0.0.0:0 2>" +
                              dir + "/err.txt";
  const int exit_status = std::system(command.c_str());
  EXPECT_EQ(WEXITSTATUS(exit_status), 2);
  const std::string err = calstand::testing::read_text(dir + "/err.txt");
  EXPECT_NE(err.find("TLS is required"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/station.db"));
}

// Every parameter that names something the daemon might read (the console's files, a library
// procedure, a device) is a name, never a path: traversals to a file beside the data folder
// get a clear refusal and never its content.
TEST(DaemonSecurity, PathTraversalInEveryParameterThatNamesAFile) {
  const std::string dir = calstand::testing::fresh_dir("sec-traversal");
  const std::string data = dir + "/data";
  std::filesystem::create_directories(data);
  const std::string secret_text = "SECRET-OUTSIDE-THE-DATA-FOLDER";
  calstand::testing::write_text(dir + "/secret.txt", secret_text + "\n");
  InProcessDaemon d(data + "/station.db", ApiOptions{});
  const int port = d.port();
  const Answer submitted = call(port, "POST", "/runs", "",
                                R"({"procedure": "two-position", "parameters": {"capture_s": 2}})");
  ASSERT_EQ(submitted.status, 201) << submitted.raw;
  const std::string run = std::to_string(submitted.body["id"].get<std::int64_t>());
  ASSERT_TRUE(wait_until([&] { return run_status(port, std::stoll(run)) == "completed"; }));

  const std::vector<std::string> traversals = {"../secret.txt",     "../../../../../../etc/passwd",
                                               dir + "/secret.txt", "/etc/passwd",
                                               "..%2Fsecret.txt",   "%2e%2e%2fsecret.txt",
                                               "....//secret.txt",  "..\\secret.txt",
                                               "secret.txt%00.js",  "./../secret.txt"};
  auto encoded = [](const std::string& s) {  // as a query value, '%' sequences kept as sent
    std::string out;
    for (char c : s) out += c == '/' ? std::string("%2F") : std::string(1, c);
    return out;
  };
  auto refused_without_leak = [&](const Answer& a, const std::string& what) {
    EXPECT_TRUE(a.status >= 400 && a.status < 500) << what << " -> " << a.status << ": " << a.raw;
    EXPECT_EQ(a.raw.find(secret_text), std::string::npos) << what;
    EXPECT_EQ(a.raw.find("root:"), std::string::npos) << what;
  };
  for (const auto& t : traversals) {
    refused_without_leak(call(port, "GET", "/console/" + t), "GET /console/" + t);
    for (const std::string route : {"/runs", "/plan"}) {
      refused_without_leak(call(port, "POST", route, "", nlohmann::json{{"procedure", t}}.dump()),
                           "POST " + route + " procedure " + t);
    }
    for (const std::string route :
         {"/export?device=", "/series?signal=gz&device=", "/report?model=accel_bias&device="}) {
      const std::string path = "/runs/" + run + route + encoded(t);
      refused_without_leak(call(port, "GET", path), "GET " + path);
    }
    for (const std::string route : {"/fits", "/diagnose"}) {
      refused_without_leak(
          call(port, "POST", "/runs/" + run + route, "", nlohmann::json{{"device", t}}.dump()),
          "POST " + route + " device " + t);
    }
  }
  // Nothing was written outside the data folder either.
  std::vector<std::string> beside;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    beside.push_back(e.path().filename().string());
  std::sort(beside.begin(), beside.end());
  EXPECT_EQ(beside, (std::vector<std::string>{"data", "secret.txt"}));
}

// A raw TCP connection to the daemon, for clients no HTTP library would be.
class RawConnection {
 public:
  explicit RawConnection(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  }
  ~RawConnection() { ::close(fd_); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;
  bool send_text(const std::string& text) {
    return ::send(fd_, text.data(), text.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(text.size());
  }
  /// What the daemon sends until it closes the connection or `timeout_ms` passes without a
  /// byte; `closed` tells which.
  std::string read_until_closed(int timeout_ms, bool& closed) {
    std::string got;
    closed = false;
    for (;;) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, timeout_ms) <= 0) return got;
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) {
        closed = true;
        return got;
      }
      got.append(buf, static_cast<std::size_t>(n));
    }
  }
  void shut() { ::shutdown(fd_, SHUT_RDWR); }
  bool connected() const { return connected_; }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

// Slow clients trickling their headers a byte at a time and one sending an oversized body hold
// a connection thread each, but neither the other clients nor the engine: a normal client is
// answered and a run completes while they are all still connected. A client that stops
// sending mid-request is disconnected. (The request deadline, which cuts trickling clients, is
// set beyond this test's length here: it has its test below.)
TEST(DaemonSecurity, SlowAndOversizedClientsHoldNeitherTheEngineNorOtherClients) {
  ApiOptions options;
  options.token = calstand::testing::kTestToken;
  options.max_body_bytes = 64 * 1024;
  options.request_deadline_s = 3600;
  InProcessDaemon d(calstand::testing::fresh_dir("sec-slowloris") + "/station.db", options);
  const int port = d.port();
  constexpr int kSlowClients = 6;
  std::vector<std::unique_ptr<RawConnection>> slow;
  for (int i = 0; i < kSlowClients; ++i) {
    slow.push_back(std::make_unique<RawConnection>(port));
    ASSERT_TRUE(slow.back()->connected());
    ASSERT_TRUE(slow.back()->send_text("GET /station HTTP/1.1\r\nHost: station\r\n"));
  }
  std::atomic<bool> stop{false};
  std::atomic<int> trickled_bytes{0};
  std::thread trickler([&] {
    const std::string header = "X-Slow: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\r\n";
    for (std::size_t i = 0; !stop; ++i) {
      for (auto& c : slow) {
        if (c->send_text(std::string(1, header[i % header.size()]))) ++trickled_bytes;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  // The oversized body: far beyond the daemon's limit (64 KiB here), sent in full.
  RawConnection huge(port);
  ASSERT_TRUE(huge.connected());
  constexpr std::size_t kHugeBytes = 8u << 20;
  std::thread huge_sender([&] {
    huge.send_text("POST /runs HTTP/1.1\r\nHost: station\r\nAuthorization: Bearer " +
                   std::string(calstand::testing::kTestToken) +
                   "\r\nContent-Type: application/json\r\nContent-Length: " +
                   std::to_string(kHugeBytes) + "\r\n\r\n");
    const std::string chunk(64 * 1024, '[');
    for (std::size_t sent = 0; sent < kHugeBytes && !stop; sent += chunk.size()) {
      if (!huge.send_text(chunk)) break;
    }
  });
  // A client that sends half a request and then nothing.
  RawConnection silent(port);
  ASSERT_TRUE(silent.send_text("GET /station HTTP/1.1\r\nHost: sta"));

  calstand::testing::ApiClient api(port);
  EXPECT_EQ(api.get("/station").status, 200);
  const std::int64_t run = api.submit("six-position", {{"capture_s", 5}});
  ASSERT_GT(run, 0);
  EXPECT_TRUE(wait_until([&] {
    const auto r = api.get("/runs/" + std::to_string(run));
    return r.status == 200 && r.body.value("status", "") == "completed";
  }));
  bool huge_closed = false;
  const std::string huge_answer = huge.read_until_closed(60000, huge_closed);
  EXPECT_EQ(huge_answer.rfind("HTTP/1.1 413", 0), 0u) << huge_answer.substr(0, 200);
  bool silent_closed = false;
  silent.read_until_closed(60000, silent_closed);
  EXPECT_TRUE(silent_closed) << "a client that stopped sending mid-request kept its connection";
  // The slow clients were connected, and trickling, all along.
  const int before = trickled_bytes;
  EXPECT_TRUE(wait_until([&] { return trickled_bytes > before + kSlowClients; }));
  EXPECT_EQ(api.get("/station").status, 200);

  stop = true;
  huge.shut();
  trickler.join();
  huge_sender.join();
}

// `calstand token add` prints a secret once and keeps only its hash; calstandd --tokens accepts
// that secret, refuses a wrong one, and warns of the plain-text token it was also given.
TEST(DaemonSecurity, ATokenAddedByTheCommandLineIsHashedAndAcceptedByTheDaemon) {
  const std::string dir = calstand::testing::fresh_dir("sec-hashed-token");
  const std::string file = dir + "/tokens.json";
  const calstand::testing::Result added =
      calstand::testing::run("token add lab-op --role operator --file " + file, dir + "/err.txt");
  ASSERT_EQ(added.exit_code, 0) << added.out << calstand::testing::read_text(dir + "/err.txt");
  std::string secret = added.out;
  while (!secret.empty() && (secret.back() == '\n' || secret.back() == '\r')) secret.pop_back();
  ASSERT_EQ(secret.size(), 81u) << secret;
  EXPECT_EQ(calstand::testing::read_text(file).find(secret.substr(17)), std::string::npos)
      << "the file holds the secret";
  const calstand::testing::Result listed = calstand::testing::run("token list --file " + file);
  EXPECT_NE(listed.out.find("lab-op"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("hashed"), std::string::npos) << listed.out;
  EXPECT_EQ(listed.out.find(secret.substr(17)), std::string::npos) << listed.out;

  const std::string log = dir + "/calstandd.log";
  calstand::testing::DaemonProcess daemon(dir + "/station.db", log, "127.0.0.1:0",
                                          {"--tokens", file});
  ASSERT_GT(daemon.port(), 0) << calstand::testing::read_text(log);
  // An action with the secret reaches the route (404: no such run), without it is refused.
  EXPECT_EQ(call(daemon.port(), "POST", "/runs/999/pause", secret).status, 404);
  std::string wrong = secret;
  wrong.back() = wrong.back() == '0' ? '1' : '0';
  EXPECT_EQ(call(daemon.port(), "POST", "/runs/999/pause", wrong).status, 401);
  EXPECT_EQ(call(daemon.port(), "POST", "/runs/999/pause", secret).status, 404);
  // The test harness's CALSTAND_TOKEN is a plain-text token: still accepted, with a warning.
  EXPECT_EQ(call(daemon.port(), "POST", "/runs/999/pause", calstand::testing::kTestToken).status,
            404);
  EXPECT_NE(calstand::testing::read_text(log).find("kept in plain text"), std::string::npos)
      << calstand::testing::read_text(log);
}

// The guard of connection_guard.hpp: a request trickled within the read timeout but past the
// whole-request deadline is cut at the deadline; one address holds at most its cap of
// connections (the next is answered 503 and closed) and gets its room back as they close; a
// live stream outlasts the deadline (it limits requests, not answers).
TEST(DaemonSecurity, ATrickledRequestIsCutAtItsDeadlineAndAnAddressHoldsAtMostItsCap) {
  ApiOptions options;
  options.token = calstand::testing::kTestToken;
  options.request_deadline_s = 2;
  options.max_connections_per_address = 4;
  InProcessDaemon d(calstand::testing::fresh_dir("sec-deadline") + "/station.db", options);
  const int port = d.port();

  // A live stream, then three tricklers: the address's four connections.
  RawConnection stream(port);
  ASSERT_TRUE(stream.send_text("GET /events HTTP/1.1\r\nHost: station\r\n\r\n"));
  bool stream_closed = false;
  const std::string stream_head = stream.read_until_closed(1000, stream_closed);
  ASSERT_EQ(stream_head.rfind("HTTP/1.1 200", 0), 0u) << stream_head.substr(0, 200);
  const auto started = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<RawConnection>> slow;
  for (int i = 0; i < 3; ++i) {
    slow.push_back(std::make_unique<RawConnection>(port));
    ASSERT_TRUE(slow.back()->send_text("GET /station HTTP/1.1\r\nHost: station\r\n"));
  }
  std::atomic<bool> stop{false};
  std::vector<std::atomic<double>> cut_after_s(slow.size());
  for (auto& c : cut_after_s) c = -1.0;
  std::thread trickler([&] {
    // A byte every 200 ms: far within the read timeout (5 s), so only the deadline cuts them.
    for (std::size_t i = 0; !stop; ++i) {
      for (std::size_t k = 0; k < slow.size(); ++k) {
        if (cut_after_s[k] >= 0.0) continue;
        if (!slow[k]->send_text(i % 2 == 0 ? "X" : ":")) {
          cut_after_s[k] =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
  // While the four are open, a fifth connection of the address is refused by name.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  {
    RawConnection fifth(port);
    ASSERT_TRUE(fifth.send_text("GET /station HTTP/1.1\r\nHost: station\r\n\r\n"));
    bool closed = false;
    const std::string answer = fifth.read_until_closed(5000, closed);
    EXPECT_EQ(answer.rfind("HTTP/1.1 503", 0), 0u) << answer.substr(0, 300);
    EXPECT_NE(answer.find("holds 4 connections already"), std::string::npos) << answer;
    EXPECT_TRUE(closed);
  }
  // The tricklers are cut at the deadline: each sees its connection closed (a send fails, or
  // the daemon's answer arrives) between 2 s and 2 s + a few pieces after its first byte.
  for (std::size_t k = 0; k < slow.size(); ++k) {
    bool closed = false;
    slow[k]->read_until_closed(8000, closed);
    EXPECT_TRUE(closed) << "trickler " << k << " outlived the 2 s deadline";
    const double at =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    EXPECT_GE(at, 1.9) << "trickler " << k << " cut before its deadline";
    EXPECT_LE(at, 4.5) << "trickler " << k;
  }
  stop = true;
  trickler.join();
  // A request refused before its body was read (no token) leaves the kept-alive connection
  // usable: the unread body is not taken for the start of the next request (as the console's
  // refused abort followed by a read once was).
  {
    RawConnection keep(port);
    ASSERT_TRUE(keep.send_text(
        "POST /runs/1/abort HTTP/1.1\r\nHost: station\r\nContent-Type: application/json\r\n"
        "Content-Length: 2\r\n\r\n{}"));
    bool closed = false;
    const std::string refused = keep.read_until_closed(1000, closed);
    EXPECT_EQ(refused.rfind("HTTP/1.1 401", 0), 0u) << refused.substr(0, 200);
    ASSERT_FALSE(closed);
    ASSERT_TRUE(keep.send_text("GET /station HTTP/1.1\r\nHost: station\r\n\r\n"));
    const std::string next = keep.read_until_closed(1000, closed);
    EXPECT_EQ(next.rfind("HTTP/1.1 200", 0), 0u) << next.substr(0, 200);
  }
  // The stream, older than the deadline now, still stands; and with the tricklers gone the
  // address has room again.
  stream.read_until_closed(300, stream_closed);
  EXPECT_FALSE(stream_closed) << "a live stream was cut by the request deadline";
  calstand::testing::ApiClient api(port);
  EXPECT_TRUE(wait_until([&] { return api.get("/station").status == 200; }));
}

}  // namespace
}  // namespace daemon_security
