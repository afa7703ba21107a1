// A command-set controller's link (line_session.hpp): render, send, read the reply line, check
// it against the set's refusals, parse it; reopen the link after a failure so that a late reply
// is never taken for the next command's.
#include "drivers/line_session.hpp"

#include <fmt/format.h>

#include <deque>
#include <thread>

#include "core/error.hpp"
#include "core/schemas.hpp"
#include "drivers/serial_reopen.hpp"

namespace calstand::drivers::line {
namespace {

using SteadyClock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// A reply line longer than this is not a reply of any command set: the stream is out of step.
constexpr std::size_t kMaxReplyBytes = 4096;

std::unique_ptr<ByteTransport> make_transport(const LineLink& link) {
  if (link.transport == LineLink::Transport::kSerial) {
    return std::make_unique<SerialPort>(link.serial);
  }
  return std::make_unique<TcpClient>(link.tcp);
}

}  // namespace

LineConnection LineConnection::from_json(const nlohmann::json& c, const CommandSet& set,
                                         const std::string& where) {
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "line_connection"), c,
                               "", where);
  nlohmann::json filled = c;
  if (c.at("transport") == "tcp" && !c.contains("port")) {
    if (set.line.default_tcp_port == 0) {
      throw core::InputError(where + ".port", fmt::format("the command set \"{}\" has no default "
                                                          "TCP port: give one",
                                                          set.name));
    }
    filled["port"] = set.line.default_tcp_port;
  }
  LineConnection out;
  out.link = LineLink::from_json(filled, set.line.default_baud);
  out.timeout = milliseconds(c.value("timeout_ms", set.line.timeout_ms));
  out.address = c.value("address", set.line.address);
  return out;
}

double Outcome::number(const std::string& field) const {
  const auto v = maybe_number(field);
  if (!v) throw std::out_of_range("no number \"" + field + "\" in the reply");
  return *v;
}

std::optional<double> Outcome::maybe_number(const std::string& field) const {
  const auto it = fields.find(field);
  return it == fields.end() ? std::nullopt : it->second.number;
}

std::optional<bool> Outcome::truth(const std::string& field) const {
  const auto it = fields.find(field);
  if (it == fields.end()) return std::nullopt;
  if (it->second.truth) return it->second.truth;
  if (it->second.number) return *it->second.number != 0.0;
  // A map field's value: "1"/"0", "true"/"false".
  if (it->second.text == "1" || it->second.text == "true") return true;
  if (it->second.text == "0" || it->second.text == "false") return false;
  return std::nullopt;
}

std::optional<std::string> Outcome::text(const std::string& field) const {
  const auto it = fields.find(field);
  return it == fields.end() ? std::nullopt : it->second.text;
}

struct LineSession::Impl {
  std::unique_ptr<ByteTransport> transport;
  SerialPort* serial = nullptr;  ///< transport when it is a serial port (reopened on failure)
  TcpClient* tcp = nullptr;      ///< transport when it is TCP (closed to resynchronise)
  ReconnectBackoff serial_backoff{milliseconds(100), milliseconds(5000)};
  std::string partial;            ///< bytes of a line not yet ended
  std::deque<std::string> lines;  ///< complete lines not yet taken

  /// Splits `bytes` into lines at CR or LF; empty lines (the LF of a CR LF) are dropped.
  /// False when a line grows beyond kMaxReplyBytes.
  bool push(std::span<const std::uint8_t> bytes) {
    for (const std::uint8_t b : bytes) {
      if (b == '\r' || b == '\n') {
        if (!partial.empty()) lines.push_back(std::move(partial));
        partial.clear();
      } else {
        partial.push_back(static_cast<char>(b));
        if (partial.size() > kMaxReplyBytes) return false;
      }
    }
    return true;
  }
  void clear() {
    partial.clear();
    lines.clear();
  }
};

LineSession::LineSession(CommandSet set, const LineConnection& connection, std::string who,
                         core::Clock& clock, FaultCounters& counters, EventQueue& events)
    : set_(std::move(set)),
      who_(std::move(who)),
      link_name_(connection.link.describe()),
      timeout_(connection.timeout),
      address_(connection.address),
      clock_(clock),
      counters_(counters),
      events_(events),
      impl_(std::make_unique<Impl>()) {
  impl_->transport = make_transport(connection.link);
  impl_->serial = dynamic_cast<SerialPort*>(impl_->transport.get());
  impl_->tcp = dynamic_cast<TcpClient*>(impl_->transport.get());
}

LineSession::LineSession(CommandSet set, std::unique_ptr<ByteTransport> transport,
                         std::string link_name, milliseconds timeout, std::string who,
                         core::Clock& clock, FaultCounters& counters, EventQueue& events)
    : set_(std::move(set)),
      who_(std::move(who)),
      link_name_(std::move(link_name)),
      timeout_(timeout),
      address_(set_.line.address),
      clock_(clock),
      counters_(counters),
      events_(events),
      impl_(std::make_unique<Impl>()) {
  impl_->transport = std::move(transport);
  impl_->serial = dynamic_cast<SerialPort*>(impl_->transport.get());
  impl_->tcp = dynamic_cast<TcpClient*>(impl_->transport.get());
}

LineSession::~LineSession() = default;

Outcome LineSession::fail(Outcome::Kind kind, std::string message) {
  impl_->clear();  // whatever is buffered is out of step with the commands now
  if (kind == Outcome::Kind::kTimeout) counters_.add("timeouts");
  if (kind == Outcome::Kind::kLinkError) counters_.add("link_errors");
  if (kind == Outcome::Kind::kBadReply) {
    counters_.add("bad_replies");
    if (!bad_reply_reported_) {
      bad_reply_reported_ = true;
      events_.push(clock_.now_s(), true, fmt::format("bad reply from the {}: {}", who_, message));
    }
  } else if (!link_down_) {
    link_down_ = true;
    events_.push(clock_.now_s(), true, fmt::format("{} link lost: {}", who_, message));
  }
  // A reply that comes late would be taken for the next command's: reopen the link so that the
  // stream starts clean (TCP: a new connection; serial: the input is flushed on open).
  if (impl_->tcp != nullptr) impl_->tcp->close();
  if (impl_->serial != nullptr && impl_->serial->is_open()) {
    impl_->serial->close();
    impl_->serial_backoff.lost(SteadyClock::now());
  }
  Outcome o;
  o.kind = kind;
  o.message = std::move(message);
  return o;
}

void LineSession::note_link_ok() {
  bad_reply_reported_ = false;
  if (!link_down_) return;
  link_down_ = false;
  counters_.add("reconnects");
  events_.push(clock_.now_s(), false, fmt::format("{} link back", who_));
}

Outcome LineSession::open() {
  if (impl_->serial != nullptr) {
    if (auto r = reopen_with_backoff(*impl_->serial, impl_->serial_backoff); !r) {
      return fail(Outcome::Kind::kLinkError, r.message);
    }
  } else if (impl_->tcp != nullptr && !impl_->tcp->is_connected()) {
    if (auto why = impl_->tcp->connect(timeout_); !why.empty()) {
      return fail(Outcome::Kind::kLinkError, why);
    }
  }
  return {};
}

Outcome LineSession::run(std::string_view operation, const Arguments& args) {
  const Operation* op = set_.find(operation);
  if (op == nullptr) {
    Outcome o;
    o.kind = Outcome::Kind::kRefused;
    o.message = fmt::format("the command set \"{}\" has no {}", set_.name, operation);
    return o;
  }
  Outcome all;
  for (const Step& step : op->steps) {
    Outcome one = run_step(step, args, std::string(operation));
    if (!one.ok()) return one;
    all.fields.merge(one.fields);
  }
  return all;
}

Outcome LineSession::run_step(const Step& step, const Arguments& args,
                              const std::string& operation) {
  Arguments with_address = args;
  with_address.texts["address"] = address_;
  std::string text;
  try {
    text = render(set_.line.prefix, with_address, set_.name + ": line.prefix") +
           render(step.command, with_address, set_.name + ": operations." + operation);
  } catch (const core::InputError& e) {
    Outcome o;
    o.kind = Outcome::Kind::kRefused;
    o.message = e.what();
    return o;
  }
  if (auto o = open(); !o.ok()) return o;

  // Bytes nobody asked for (a late reply, line noise) would be taken for this command's reply.
  std::uint8_t buffer[512];
  std::size_t stray = impl_->partial.size();
  for (const auto& l : impl_->lines) stray += l.size() + 1;
  impl_->clear();
  const bool connected = impl_->tcp == nullptr || impl_->tcp->is_connected();
  for (int i = 0; connected && i < 16; ++i) {
    const IoResult r = impl_->transport->read(buffer, milliseconds(0));
    if (!r.ok()) return fail(Outcome::Kind::kLinkError, r.error);  // hung up while idle
    if (r.bytes == 0) break;
    stray += r.bytes;
  }
  if (stray > 0) counters_.add("stray_bytes", stray);

  const auto deadline = SteadyClock::now() + timeout_;
  const auto left = [&] {
    return std::max(milliseconds(0),
                    std::chrono::duration_cast<milliseconds>(deadline - SteadyClock::now()));
  };
  const std::string wire = text + set_.line.terminator;
  const IoResult w =
      impl_->transport->write(std::span<const std::uint8_t>(
                                  reinterpret_cast<const std::uint8_t*>(wire.data()), wire.size()),
                              left());
  if (!w.ok())
    return fail(Outcome::Kind::kLinkError, fmt::format("sending '{}': {}", text, w.error));
  if (!step.reply) {
    if (set_.line.delay_ms > 0) std::this_thread::sleep_for(milliseconds(set_.line.delay_ms));
    // A controller that answers nothing to a command it takes may still answer one it refuses
    // (Actidyn): what came meanwhile is read now, so that its words reach this command.
    for (int i = 0; i < 16; ++i) {
      const IoResult r = impl_->transport->read(buffer, milliseconds(0));
      if (!r.ok() || r.bytes == 0) break;
      impl_->push(std::span<const std::uint8_t>(buffer, r.bytes));
    }
    while (!impl_->lines.empty()) {
      const std::string line = std::move(impl_->lines.front());
      impl_->lines.pop_front();
      if (auto words = match_error(set_, line)) {
        counters_.add("refused_commands");
        Outcome o;
        o.kind = Outcome::Kind::kRefused;
        o.message = fmt::format("the {} refused '{}': {}", who_, text, *words);
        return o;
      }
      counters_.add("stray_bytes", line.size() + 1);
    }
    note_link_ok();
    return {};
  }
  for (;;) {
    if (!impl_->lines.empty()) {
      std::string line = std::move(impl_->lines.front());
      impl_->lines.pop_front();
      note_link_ok();
      if (auto words = match_error(set_, line)) {
        counters_.add("refused_commands");
        Outcome o;
        o.kind = Outcome::Kind::kRefused;
        o.message = fmt::format("the {} refused '{}': {}", who_, text, *words);
        return o;
      }
      ParsedReply parsed = parse_reply(step, line);
      if (!parsed.error.empty()) {
        return fail(Outcome::Kind::kBadReply, fmt::format("'{}': {}", text, parsed.error));
      }
      Outcome o;
      o.fields = std::move(parsed.fields);
      return o;
    }
    const auto wait = left();
    if (wait.count() <= 0) {
      return fail(Outcome::Kind::kTimeout,
                  fmt::format("'{}': no reply from the {} ({}) within {} ms", text, who_,
                              link_name_, timeout_.count()));
    }
    const IoResult r = impl_->transport->read(buffer, wait);
    if (!r.ok()) return fail(Outcome::Kind::kLinkError, fmt::format("'{}': {}", text, r.error));
    if (!impl_->push(std::span<const std::uint8_t>(buffer, r.bytes))) {
      return fail(Outcome::Kind::kBadReply,
                  fmt::format("'{}': a reply longer than {} bytes", text, kMaxReplyBytes));
    }
  }
}

}  // namespace calstand::drivers::line
