#include "drivers/dbc_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "core/error.hpp"

namespace calstand::drivers {
namespace {

/// A DBC token: an identifier (keywords included), a number, a "string" or one punctuation
/// character. `first_on_line`: nothing but blanks before it on its line.
struct DbcToken {
  enum class Kind { kIdent, kNumber, kString, kPunct, kEnd };
  Kind kind = Kind::kEnd;
  std::string text;
  std::size_t line = 0;
  bool first_on_line = false;
};

class DbcLexer {
 public:
  DbcLexer(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  std::vector<DbcToken> run() {
    std::vector<DbcToken> out;
    bool line_start = true;
    if (text_.starts_with("\xEF\xBB\xBF")) at_ = 3;  // a UTF-8 byte order mark
    while (at_ < text_.size()) {
      const char c = text_[at_];
      if (c == '\n') {
        ++line_;
        ++at_;
        line_start = true;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        ++at_;
        continue;
      }
      if (c == '/' && at_ + 1 < text_.size() && text_[at_ + 1] == '/') {  // comment line
        while (at_ < text_.size() && text_[at_] != '\n') ++at_;
        continue;
      }
      DbcToken t;
      t.line = line_;
      t.first_on_line = line_start;
      line_start = false;
      const auto uc = static_cast<unsigned char>(c);
      if (std::isalpha(uc) || c == '_') {
        t.kind = DbcToken::Kind::kIdent;
        while (at_ < text_.size() &&
               (std::isalnum(static_cast<unsigned char>(text_[at_])) || text_[at_] == '_'))
          t.text += text_[at_++];
      } else if (std::isdigit(uc) || ((c == '-' || c == '+' || c == '.') && number_follows())) {
        t.kind = DbcToken::Kind::kNumber;
        t.text += text_[at_++];
        while (at_ < text_.size()) {
          const char d = text_[at_];
          const bool exponent_sign =
              (d == '-' || d == '+') && (t.text.back() == 'e' || t.text.back() == 'E');
          if (!(std::isalnum(static_cast<unsigned char>(d)) || d == '.' || exponent_sign)) break;
          t.text += text_[at_++];
        }
      } else if (c == '"') {
        t.kind = DbcToken::Kind::kString;
        ++at_;
        for (;;) {
          if (at_ >= text_.size())
            throw core::InputError(fmt::format("{}:{}", file_, t.line), "unterminated string");
          const char d = text_[at_++];
          if (d == '"') break;
          if (d == '\\' && at_ < text_.size() && text_[at_] == '"') {
            t.text += '"';
            ++at_;
            continue;
          }
          if (d == '\n') ++line_;
          t.text += d;
        }
      } else {
        t.kind = DbcToken::Kind::kPunct;
        t.text = std::string(1, c);
        ++at_;
      }
      out.push_back(std::move(t));
    }
    DbcToken end;
    end.line = line_;
    end.first_on_line = true;
    out.push_back(end);
    return out;
  }

 private:
  bool number_follows() const {
    std::size_t i = at_ + 1;
    if (text_[at_] != '.' && i < text_.size() && text_[i] == '.') ++i;
    return i < text_.size() && std::isdigit(static_cast<unsigned char>(text_[i]));
  }

  std::string_view text_;
  const std::string& file_;
  std::size_t at_ = 0;
  std::size_t line_ = 1;
};

/// BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: CANdb++'s holder of signals that belong to no
/// message (id 0xC0000000: not a CAN id). Parsed, kept out of the messages.
constexpr std::uint64_t kDbcIndependentRawId = 0xC0000000u;
constexpr canid_t kDbcIndependentId = 0xFFFFFFFFu;  // no can_id has every bit set

/// The sections a DBC may hold that carry nothing the station needs: skipped up to their `;`.
const std::set<std::string, std::less<>> kDbcSkipped = {
    "BA_DEF_DEF_", "BA_DEF_DEF_REL_", "BA_DEF_REL_", "BA_REL_",       "BA_DEF_SGTYPE_",
    "BA_SGTYPE_",  "VAL_TABLE_",      "EV_",         "ENVVAR_DATA_",  "SGTYPE_",
    "SGTYPE_VAL_", "SIG_GROUP_",      "CAT_DEF_",    "CAT_",          "FILTER",
    "BU_SG_REL_",  "BU_EV_REL_",      "BU_BO_REL_",  "SIG_TYPE_REF_", "SIGTYPE_VALTYPE_",
    "BO_TX_BU_",   "NS_DESC_",        "EV_DATA_",    "SIG_TYPE_REF_"};

class DbcParser {
 public:
  DbcParser(std::vector<DbcToken> tokens, const std::string& file)
      : t_(std::move(tokens)), file_(file) {}

  DbcFile run() {
    DbcFile out;
    out.file = file_;
    while (peek().kind != DbcToken::Kind::kEnd) {
      const DbcToken& k = peek();
      if (k.kind != DbcToken::Kind::kIdent) fail(k, fmt::format("unexpected '{}'", k.text));
      const std::string key = k.text;
      if (key == "VERSION") {
        next();
        out.version = expect_string("the version string");
      } else if (key == "NS_") {
        skip_new_symbols();
      } else if (key == "BS_") {
        next();
        expect_punct(':');
        skip_rest_of_line(k.line);
      } else if (key == "BU_") {
        const std::size_t line = next().line;
        expect_punct(':');
        while (peek().kind == DbcToken::Kind::kIdent && peek().line == line)
          out.nodes.push_back(next().text);
      } else if (key == "BO_") {
        DbcMessage m = parse_message();
        if (m.id == kDbcIndependentId) {
          independent_ = std::move(m);  // a signal store, not a frame: kept for CM_ and VAL_
        } else {
          out.messages.push_back(std::move(m));
        }
      } else if (key == "SG_") {
        fail(k, "SG_ outside a message (no BO_ before it)");
      } else if (key == "CM_") {
        parse_comment(out);
      } else if (key == "BA_DEF_") {
        parse_attribute_definition();
      } else if (key == "BA_") {
        parse_attribute(out);
      } else if (key == "VAL_") {
        parse_values(out);
      } else if (key == "SIG_VALTYPE_") {
        parse_value_type(out);
      } else if (key == "SG_MUL_VAL_") {
        fail(k,
             "extended multiplexing (SG_MUL_VAL_) is not supported: only one `M` switch per "
             "message with `mN` signals");
      } else if (kDbcSkipped.count(key)) {
        skip_statement();
      } else {
        fail(k, fmt::format("unknown keyword {}", key));
      }
    }
    check(out);
    return out;
  }

 private:
  [[noreturn]] void fail(const DbcToken& at, const std::string& why) const {
    throw core::InputError(fmt::format("{}:{}", file_, at.line), why);
  }
  const DbcToken& peek() const { return t_[at_]; }
  const DbcToken& next() {
    const DbcToken& t = t_[at_];
    if (at_ + 1 < t_.size()) ++at_;
    return t;
  }
  bool is_punct(char c) const {
    return peek().kind == DbcToken::Kind::kPunct && peek().text[0] == c;
  }
  void expect_punct(char c) {
    if (!is_punct(c)) fail(peek(), fmt::format("expected '{}', found '{}'", c, describe(peek())));
    next();
  }
  static std::string describe(const DbcToken& t) {
    return t.kind == DbcToken::Kind::kEnd ? "end of file" : t.text;
  }
  std::string expect_ident(std::string_view what) {
    if (peek().kind != DbcToken::Kind::kIdent)
      fail(peek(), fmt::format("expected {}, found '{}'", what, describe(peek())));
    return next().text;
  }
  std::string expect_string(std::string_view what) {
    if (peek().kind != DbcToken::Kind::kString)
      fail(peek(), fmt::format("expected {} in quotes, found '{}'", what, describe(peek())));
    return next().text;
  }
  double expect_number(std::string_view what) {
    const DbcToken& t = peek();
    if (t.kind != DbcToken::Kind::kNumber)
      fail(t, fmt::format("expected {} (a number), found '{}'", what, describe(t)));
    next();
    std::string text = t.text;
    if (!text.empty() && text[0] == '+') text.erase(0, 1);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v))
      fail(t, fmt::format("{}: \"{}\" is not a number", what, t.text));
    return v;
  }
  std::uint64_t expect_unsigned(std::string_view what) {
    const DbcToken& t = peek();
    if (t.kind != DbcToken::Kind::kNumber)
      fail(t, fmt::format("expected {} (a whole number), found '{}'", what, describe(t)));
    next();
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || end != t.text.data() + t.text.size())
      fail(t, fmt::format("{}: \"{}\" is not a whole number", what, t.text));
    return v;
  }
  std::int64_t expect_integer(std::string_view what) {
    const DbcToken& t = peek();
    std::string text = t.text;
    if (t.kind == DbcToken::Kind::kNumber && !text.empty() && text[0] == '+') text.erase(0, 1);
    std::int64_t v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (t.kind != DbcToken::Kind::kNumber || ec != std::errc() || end != text.data() + text.size())
      fail(t, fmt::format("expected {} (an integer), found '{}'", what, describe(t)));
    next();
    return v;
  }
  void skip_statement() {
    const DbcToken& start = next();
    while (!is_punct(';')) {
      if (peek().kind == DbcToken::Kind::kEnd) fail(start, start.text + " without its ';'");
      next();
    }
    next();
  }
  void skip_rest_of_line(std::size_t line) {
    while (peek().kind != DbcToken::Kind::kEnd && peek().line == line) next();
  }
  /// NS_ : followed by the names of optional sections, one per indented line. The list ends at
  /// a token at the start of a line that is followed by ':' (BS_:) or is not indented.
  void skip_new_symbols() {
    next();
    expect_punct(':');
    while (peek().kind == DbcToken::Kind::kIdent) {
      const bool followed_by_colon = at_ + 1 < t_.size() &&
                                     t_[at_ + 1].kind == DbcToken::Kind::kPunct &&
                                     t_[at_ + 1].text == ":";
      if (followed_by_colon || peek().text == "BO_") break;
      next();
    }
  }

  DbcMessage parse_message() {
    const DbcToken& bo = next();
    DbcMessage m;
    m.line = bo.line;
    const DbcToken& id_token = peek();
    const std::uint64_t raw_id = expect_unsigned("the message id");
    if (raw_id > 0xFFFFFFFFu)
      fail(id_token, fmt::format("message id {} is beyond 32 bits", raw_id));
    const bool extended = (raw_id & 0x80000000u) != 0;
    const std::uint64_t id = raw_id & 0x7FFFFFFFu;
    const bool independent = raw_id == kDbcIndependentRawId;
    if (!independent && (extended ? id > CAN_EFF_MASK : id > CAN_SFF_MASK)) {
      fail(id_token,
           fmt::format("message id {} is beyond the {} ids{}", raw_id,
                       extended ? "29-bit extended" : "11-bit standard",
                       extended ? "" : " (an extended id has bit 31 set: id + 2147483648)"));
    }
    m.id =
        independent ? kDbcIndependentId : static_cast<canid_t>(id) | (extended ? CAN_EFF_FLAG : 0u);
    m.name = expect_ident("the message name");
    expect_punct(':');
    const DbcToken& dlc_token = peek();
    const std::uint64_t dlc = expect_unsigned("the message length (DLC)");
    if (dlc > 8) {
      fail(dlc_token,
           fmt::format("message {}: length {} bytes is CAN FD (more than 8 bytes), which is "
                       "not supported: classic CAN frames only",
                       m.name, dlc));
    }
    m.dlc = static_cast<std::uint32_t>(dlc);
    m.sender = expect_ident("the sending node");
    while (peek().kind == DbcToken::Kind::kIdent && peek().text == "SG_")
      m.signals.push_back(parse_signal(m));
    return m;
  }

  DbcSignal parse_signal(const DbcMessage& m) {
    const DbcToken& sg = next();
    DbcSignal s;
    s.line = sg.line;
    s.name = expect_ident("the signal name");
    if (peek().kind == DbcToken::Kind::kIdent) {
      const DbcToken& mux = next();
      const std::string& x = mux.text;
      if (x == "M") {
        s.mux = DbcSignal::Mux::kSwitch;
      } else if (x.size() >= 2 && x[0] == 'm' && std::all_of(x.begin() + 1, x.end(), [](char c) {
                   return std::isdigit(static_cast<unsigned char>(c));
                 })) {
        s.mux = DbcSignal::Mux::kMultiplexed;
        std::uint64_t v = 0;
        const auto [end, ec] = std::from_chars(x.data() + 1, x.data() + x.size(), v);
        if (ec != std::errc() || v > 0xFFFFFFFFu) fail(mux, "multiplexer value out of range");
        s.mux_value = static_cast<std::uint32_t>(v);
      } else if (x.size() >= 3 && x[0] == 'm' && x.back() == 'M') {
        fail(mux, fmt::format("signal {}: extended multiplexing ({}: a multiplexed multiplexer) "
                              "is not supported",
                              s.name, x));
      } else {
        fail(mux,
             fmt::format("signal {}: \"{}\" is not a multiplexer indicator (M or mN)", s.name, x));
      }
    }
    expect_punct(':');
    const DbcToken& start_token = peek();
    const std::uint64_t start = expect_unsigned("the start bit");
    expect_punct('|');
    const std::uint64_t length = expect_unsigned("the signal length");
    expect_punct('@');
    const DbcToken& order = peek();
    // "1+" may lex as a number "1" then '+'; "0-" likewise.
    const std::uint64_t order_value = expect_unsigned("the byte order (@1 Intel or @0 Motorola)");
    if (order_value > 1) fail(order, "byte order must be @1 (Intel) or @0 (Motorola)");
    s.little_endian = order_value == 1;
    if (is_punct('+')) {
      s.is_signed = false;
    } else if (is_punct('-')) {
      s.is_signed = true;
    } else {
      fail(peek(), fmt::format("expected the sign '+' or '-', found '{}'", describe(peek())));
    }
    next();
    expect_punct('(');
    s.factor = expect_number("the factor");
    expect_punct(',');
    s.offset = expect_number("the offset");
    expect_punct(')');
    expect_punct('[');
    s.minimum = expect_number("the minimum");
    expect_punct('|');
    s.maximum = expect_number("the maximum");
    expect_punct(']');
    s.unit = expect_string("the unit");
    while (peek().kind == DbcToken::Kind::kIdent && !peek().first_on_line) {
      s.receivers.push_back(next().text);
      if (is_punct(',')) next();
    }
    if (length < 1 || length > 64) {
      fail(start_token, fmt::format("signal {}: length {} bits (1..64)", s.name, length));
    }
    if (start > 63) {
      fail(start_token,
           fmt::format("signal {}: start bit {} is beyond the 64 bits of a classic CAN frame",
                       s.name, start));
    }
    s.start_bit = static_cast<std::uint32_t>(start);
    s.length_bits = static_cast<std::uint32_t>(length);
    if (m.id == kDbcIndependentId) return s;  // not placed in any frame
    if (s.factor == 0.0) fail(start_token, fmt::format("signal {}: factor 0", s.name));
    // Within the 64 bits and the message's length.
    const std::uint32_t last_stream =
        s.little_endian ? s.start_bit + s.length_bits
                        : 8 * (s.start_bit / 8) + 7 - s.start_bit % 8 + s.length_bits;
    if (last_stream > 64) {
      fail(start_token,
           fmt::format("signal {}: {} bits from start bit {} ({}) run beyond the 64 bits of a "
                       "classic CAN frame",
                       s.name, s.length_bits, s.start_bit, s.little_endian ? "Intel" : "Motorola"));
    }
    if (s.field().bytes_needed() > m.dlc) {
      fail(start_token, fmt::format("signal {}: needs {} bytes but message {} has {}", s.name,
                                    s.field().bytes_needed(), m.name, m.dlc));
    }
    return s;
  }

  DbcMessage* find_message(DbcFile& f, std::uint64_t raw_id, const DbcToken& at) {
    if (raw_id == kDbcIndependentRawId && independent_.id == kDbcIndependentId)
      return &independent_;
    for (auto& m : f.messages) {
      const std::uint64_t mid =
          (m.id & CAN_EFF_FLAG) ? ((m.id & CAN_EFF_MASK) | 0x80000000u) : m.id;
      if (mid == raw_id) return &m;
    }
    fail(at, fmt::format("no message with id {}", raw_id));
  }
  DbcSignal* find_signal(DbcMessage& m, const std::string& name, const DbcToken& at) {
    for (auto& s : m.signals)
      if (s.name == name) return &s;
    fail(at, fmt::format("message {} has no signal {}", m.name, name));
  }

  void parse_comment(DbcFile& f) {
    const DbcToken& cm = next();
    if (peek().kind == DbcToken::Kind::kString) {  // a network comment
      next();
    } else {
      const DbcToken& kind = peek();
      const std::string what = expect_ident("BU_, BO_, SG_ or EV_");
      if (what == "BO_") {
        const DbcToken& at = peek();
        DbcMessage* m = find_message(f, expect_unsigned("the message id"), at);
        m->comment = expect_string("the comment");
      } else if (what == "SG_") {
        const DbcToken& at = peek();
        DbcMessage* m = find_message(f, expect_unsigned("the message id"), at);
        const DbcToken& sig = peek();
        DbcSignal* s = find_signal(*m, expect_ident("the signal name"), sig);
        s->comment = expect_string("the comment");
      } else if (what == "BU_" || what == "EV_") {
        expect_ident("the name");
        expect_string("the comment");
      } else {
        fail(kind, fmt::format("CM_ {}: expected BU_, BO_, SG_ or EV_", what));
      }
    }
    if (!is_punct(';')) fail(cm, "CM_ without its ';'");
    next();
  }

  /// BA_DEF_ [BU_|BO_|SG_|EV_] "name" type ...; kept: ENUM values (for VFrameFormat).
  void parse_attribute_definition() {
    const DbcToken& start = next();
    if (peek().kind == DbcToken::Kind::kIdent) next();  // object kind
    const std::string name = expect_string("the attribute name");
    std::vector<std::string> enums;
    if (peek().kind == DbcToken::Kind::kIdent && peek().text == "ENUM") {
      next();
      while (peek().kind == DbcToken::Kind::kString) {
        enums.push_back(next().text);
        if (is_punct(',')) next();
      }
    }
    while (!is_punct(';')) {
      if (peek().kind == DbcToken::Kind::kEnd) fail(start, "BA_DEF_ without its ';'");
      next();
    }
    next();
    enums_[name] = std::move(enums);
  }

  /// BA_ "name" [BU_ n|BO_ id|SG_ id s|EV_ n] value; checked: VFrameFormat of a message is not
  /// CAN FD. Every other attribute is skipped.
  void parse_attribute(DbcFile& f) {
    const DbcToken& start = next();
    const std::string name = expect_string("the attribute name");
    if (name == "VFrameFormat" && peek().kind == DbcToken::Kind::kIdent && peek().text == "BO_") {
      next();
      const DbcToken& at = peek();
      DbcMessage* m = find_message(f, expect_unsigned("the message id"), at);
      const DbcToken& value_token = peek();
      const std::int64_t value = expect_integer("the frame format");
      const auto it = enums_.find(name);
      std::string text;
      if (it != enums_.end() && value >= 0 && static_cast<std::size_t>(value) < it->second.size())
        text = it->second[static_cast<std::size_t>(value)];
      if (text.find("FD") != std::string::npos || (text.empty() && value >= 14)) {
        fail(value_token, fmt::format("message {}: frame format {} is CAN FD, which is not "
                                      "supported: classic CAN frames only",
                                      m->name, text.empty() ? std::to_string(value) : text));
      }
    }
    while (!is_punct(';')) {
      if (peek().kind == DbcToken::Kind::kEnd) fail(start, "BA_ without its ';'");
      next();
    }
    next();
  }

  /// VAL_ id signal (value "text")* ;  (VAL_ of an environment variable is skipped)
  void parse_values(DbcFile& f) {
    const DbcToken& start = peek();
    if (t_[at_ + 1].kind != DbcToken::Kind::kNumber) {
      skip_statement();
      return;
    }
    next();
    const DbcToken& at = peek();
    DbcMessage* m = find_message(f, expect_unsigned("the message id"), at);
    const DbcToken& sig = peek();
    DbcSignal* s = find_signal(*m, expect_ident("the signal name"), sig);
    while (!is_punct(';')) {
      if (peek().kind == DbcToken::Kind::kEnd) fail(start, "VAL_ without its ';'");
      const std::int64_t value = expect_integer("a value");
      s->values[value] = expect_string("the value's description");
    }
    next();
  }

  /// SIG_VALTYPE_ id signal : 0|1|2 ;
  void parse_value_type(DbcFile& f) {
    next();
    const DbcToken& at = peek();
    DbcMessage* m = find_message(f, expect_unsigned("the message id"), at);
    const DbcToken& sig = peek();
    DbcSignal* s = find_signal(*m, expect_ident("the signal name"), sig);
    expect_punct(':');
    const DbcToken& type_token = peek();
    const std::uint64_t type = expect_unsigned("the value type (0 integer, 1 float, 2 double)");
    if (type > 2) fail(type_token, "value type must be 0 (integer), 1 (float) or 2 (double)");
    s->value_type = static_cast<DbcSignal::ValueType>(type);
    const std::uint32_t need = type == 1 ? 32 : 64;
    if (type != 0 && s->length_bits != need) {
      fail(type_token, fmt::format("signal {}: a {} is {} bits, not {}", s->name,
                                   type == 1 ? "float" : "double", need, s->length_bits));
    }
    expect_punct(';');
  }

  /// Rules across statements: unique message names and ids, unique signal names, one switch
  /// per message, multiplexed signals only with a switch.
  void check(const DbcFile& f) const {
    std::set<std::string> names;
    std::set<canid_t> ids;
    for (const auto& m : f.messages) {
      DbcToken at;
      at.line = m.line;
      if (!names.insert(m.name).second) fail(at, fmt::format("message {} defined twice", m.name));
      if (!ids.insert(m.id).second) fail(at, fmt::format("message id of {} used twice", m.name));
      std::set<std::string> signal_names;
      std::size_t switches = 0;
      bool multiplexed = false;
      for (const auto& s : m.signals) {
        at.line = s.line;
        if (!signal_names.insert(s.name).second)
          fail(at, fmt::format("message {}: signal {} defined twice", m.name, s.name));
        switches += s.mux == DbcSignal::Mux::kSwitch ? 1 : 0;
        multiplexed = multiplexed || s.mux == DbcSignal::Mux::kMultiplexed;
        if (s.mux == DbcSignal::Mux::kSwitch && s.value_type != DbcSignal::ValueType::kInteger)
          fail(at, fmt::format("message {}: the multiplexer {} is a float", m.name, s.name));
      }
      at.line = m.line;
      if (switches > 1) {
        fail(at, fmt::format("message {}: {} multiplexer switches (M); extended multiplexing is "
                             "not supported",
                             m.name, switches));
      }
      if (multiplexed && switches == 0)
        fail(at, fmt::format("message {}: mN signals without a multiplexer switch (M)", m.name));
    }
  }

  std::vector<DbcToken> t_;
  const std::string& file_;
  std::size_t at_ = 0;
  std::map<std::string, std::vector<std::string>> enums_;
  DbcMessage independent_;
};

}  // namespace

CanField DbcSignal::field() const {
  CanField f;
  f.length_bits = length_bits;
  if (little_endian) {
    f.byte_order = ByteOrder::kLittle;
    f.start_bit = start_bit;
  } else {
    // Sawtooth: DBC bit s is bit s % 8 of byte s / 8; the big-endian bit string counts from
    // bit 7 of byte 0.
    f.byte_order = ByteOrder::kBig;
    f.start_bit = 8 * (start_bit / 8) + 7 - start_bit % 8;
  }
  switch (value_type) {
    case ValueType::kInteger:
      f.type = is_signed ? FieldType::kSigned : FieldType::kUnsigned;
      break;
    case ValueType::kFloat32:
    case ValueType::kFloat64:
      f.type = FieldType::kFloat;
      break;
  }
  f.scale = factor;
  f.offset = offset;
  return f;
}

const DbcSignal* DbcMessage::signal(std::string_view signal_name) const {
  for (const auto& s : signals)
    if (s.name == signal_name) return &s;
  return nullptr;
}

const DbcSignal* DbcMessage::multiplexer() const {
  for (const auto& s : signals)
    if (s.mux == DbcSignal::Mux::kSwitch) return &s;
  return nullptr;
}

const DbcMessage* DbcFile::message(std::string_view name) const {
  for (const auto& m : messages)
    if (m.name == name) return &m;
  return nullptr;
}

DbcFile DbcFile::parse(std::string_view text, const std::string& file) {
  return DbcParser(DbcLexer(text, file).run(), file).run();
}

DbcFile DbcFile::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw core::InputError(path,
                           std::string("cannot read the DBC file (") + std::strerror(errno) + ")");
  }
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

}  // namespace calstand::drivers
