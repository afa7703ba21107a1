#include "binary_copy.hpp"

#include <fmt/format.h>
#include <libpq-fe.h>

#include <bit>
#include <charconv>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace calstand::fleet::detail {
namespace {

// The header of the binary COPY format: the 11-byte signature, no flags (no OIDs), no header
// extension.
constexpr char kSignature[] = "PGCOPY\n\377\r\n";  // + its terminating NUL: 11 bytes
constexpr std::size_t kSignatureBytes = sizeof(kSignature);
static_assert(kSignatureBytes == 11);

/// libpq's connection under a libpqxx transaction: `largeobject::raw_connection` is protected,
/// for classes derived from largeobject.
struct ConnectionOf : pqxx::largeobject {
  static pqxx::internal::pq::PGconn* of(const pqxx::dbtransaction& tx) {
    return raw_connection(tx);
  }
};

std::string trimmed_error(PGconn* conn) {
  std::string why = PQerrorMessage(conn);
  while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
  return why;
}

[[noreturn]] void refuse(const char* column, const std::string& why) {
  throw std::invalid_argument(fmt::format("column {}: {}", column, why));
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

CopyType copy_type_of(const std::string& column, const std::string& type) {
  if (type == "smallint") return CopyType::kInt2;
  if (type == "integer") return CopyType::kInt4;
  if (type == "bigint") return CopyType::kInt8;
  if (type == "double precision") return CopyType::kFloat8;
  if (type == "text") return CopyType::kText;
  if (type == "bytea") return CopyType::kBytea;
  if (type == "uuid") return CopyType::kUuid;
  throw std::invalid_argument(
      fmt::format("column {}: type {} has no binary COPY writer here", column, type));
}

void BinaryCopyRows::put16(std::uint16_t v) {
  if constexpr (std::endian::native == std::endian::little) v = __builtin_bswap16(v);
  data_.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void BinaryCopyRows::put32(std::uint32_t v) {
  if constexpr (std::endian::native == std::endian::little) v = __builtin_bswap32(v);
  data_.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void BinaryCopyRows::put64(std::uint64_t v) {
  if constexpr (std::endian::native == std::endian::little) v = __builtin_bswap64(v);
  data_.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void BinaryCopyRows::begin_row(std::size_t fields) { put16(static_cast<std::uint16_t>(fields)); }

void BinaryCopyRows::null() { put32(0xffffffffU); }

void BinaryCopyRows::integer(CopyType type, const char* column, std::int64_t value) {
  switch (type) {
    case CopyType::kInt2:
      if (value < std::numeric_limits<std::int16_t>::min() ||
          value > std::numeric_limits<std::int16_t>::max()) {
        refuse(column, fmt::format("{} is beyond a smallint", value));
      }
      put32(2);
      put16(static_cast<std::uint16_t>(static_cast<std::int16_t>(value)));
      return;
    case CopyType::kInt4:
      if (value < std::numeric_limits<std::int32_t>::min() ||
          value > std::numeric_limits<std::int32_t>::max()) {
        refuse(column, fmt::format("{} is beyond an integer", value));
      }
      put32(4);
      put32(static_cast<std::uint32_t>(static_cast<std::int32_t>(value)));
      return;
    case CopyType::kInt8:
      put32(8);
      put64(static_cast<std::uint64_t>(value));
      return;
    case CopyType::kFloat8:
      // As PostgreSQL's text input reads an integer into a double: the nearest double.
      real(type, column, static_cast<double>(value));
      return;
    case CopyType::kText:
    case CopyType::kBytea:
    case CopyType::kUuid: {
      const std::string text = std::to_string(value);
      this->text(type, column, text);
      return;
    }
  }
}

void BinaryCopyRows::real(CopyType type, const char* column, double value) {
  if (type != CopyType::kFloat8) {
    if (type == CopyType::kText) {
      text(type, column, fmt::format("{}", value));
      return;
    }
    refuse(column, fmt::format("the real {} is not a value of this column", value));
  }
  put32(8);
  put64(std::bit_cast<std::uint64_t>(value));
}

void BinaryCopyRows::text(CopyType type, const char* column, std::string_view value) {
  switch (type) {
    case CopyType::kInt2:
    case CopyType::kInt4:
    case CopyType::kInt8: {
      std::int64_t v = 0;
      const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
      if (value.empty() || ec != std::errc() || ptr != value.data() + value.size()) {
        refuse(column, fmt::format("'{}' is not an integer", value));
      }
      integer(type, column, v);
      return;
    }
    case CopyType::kFloat8: {
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
      if (value.empty() || ec != std::errc() || ptr != value.data() + value.size()) {
        refuse(column, fmt::format("'{}' is not a number", value));
      }
      real(type, column, v);
      return;
    }
    case CopyType::kText:
    case CopyType::kBytea:
      bytes(type, column, value.data(), value.size());
      return;
    case CopyType::kUuid: {
      // 32 hex digits, hyphens anywhere between pairs (the canonical 8-4-4-4-12 form).
      unsigned char out[16];
      std::size_t n = 0;
      for (std::size_t i = 0; i < value.size(); ++i) {
        if (value[i] == '-') continue;
        const int hi = hex_digit(value[i]);
        const int lo = i + 1 < value.size() ? hex_digit(value[i + 1]) : -1;
        if (hi < 0 || lo < 0 || n == 16) refuse(column, fmt::format("'{}' is not a UUID", value));
        out[n++] = static_cast<unsigned char>(hi << 4 | lo);
        ++i;
      }
      if (n != 16) refuse(column, fmt::format("'{}' is not a UUID", value));
      put32(16);
      data_.append(reinterpret_cast<const char*>(out), 16);
      return;
    }
  }
}

void BinaryCopyRows::bytes(CopyType type, const char* column, const void* data, std::size_t size) {
  if (type != CopyType::kBytea && type != CopyType::kText) {
    refuse(column, "a blob is not a value of this column");
  }
  if (size > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    refuse(column, fmt::format("{} bytes are more than one COPY field holds", size));
  }
  put32(static_cast<std::uint32_t>(size));
  data_.append(static_cast<const char*>(data), size);
}

BinaryCopy::BinaryCopy(pqxx::dbtransaction& tx, const std::string& table,
                       const std::vector<std::string>& columns)
    : conn_(ConnectionOf::of(tx)) {
  command_ = "COPY " + table + " (";
  for (std::size_t i = 0; i < columns.size(); ++i) command_ += (i ? ", " : "") + columns[i];
  command_ += ") FROM STDIN (FORMAT binary)";
  PGresult* r = PQexec(conn_, command_.c_str());
  const ExecStatusType status = PQresultStatus(r);
  if (status != PGRES_COPY_IN) {
    const char* state = r != nullptr ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
    const std::string sqlstate = state != nullptr ? state : "";
    std::string why = r != nullptr ? PQresultErrorMessage(r) : trimmed_error(conn_);
    PQclear(r);
    // Whatever else the server sent for this command, so that the connection is idle again.
    while (PGresult* more = PQgetResult(conn_)) PQclear(more);
    if (PQstatus(conn_) != CONNECTION_OK) throw pqxx::broken_connection(why);
    throw pqxx::sql_error(why, command_, sqlstate.empty() ? nullptr : sqlstate.c_str());
  }
  PQclear(r);
  open_ = true;
  std::string header(kSignature, kSignatureBytes);
  header.append(8, '\0');  // flags, header extension length
  write(header);
}

BinaryCopy::~BinaryCopy() {
  if (!open_) return;
  // Abandoned (an exception between the rows): end the COPY as failed, which aborts the
  // transaction, and drain its results so that libpqxx finds the connection idle.
  PQputCopyEnd(conn_, "calstand: COPY abandoned");
  while (PGresult* r = PQgetResult(conn_)) PQclear(r);
}

void BinaryCopy::write(std::string_view rows) {
  if (rows.empty()) return;
  if (PQputCopyData(conn_, rows.data(), static_cast<int>(rows.size())) != 1) {
    open_ = false;
    throw pqxx::broken_connection(trimmed_error(conn_));
  }
}

std::int64_t BinaryCopy::finish() {
  static constexpr char kTrailer[] = {'\xff', '\xff'};
  write(std::string_view(kTrailer, sizeof kTrailer));
  open_ = false;
  if (PQputCopyEnd(conn_, nullptr) != 1) throw pqxx::broken_connection(trimmed_error(conn_));
  std::int64_t rows = 0;
  std::string why, sqlstate;
  bool failed = false;
  while (PGresult* r = PQgetResult(conn_)) {
    if (PQresultStatus(r) == PGRES_COMMAND_OK) {
      const char* tuples = PQcmdTuples(r);
      if (tuples != nullptr && *tuples != '\0') rows = std::stoll(tuples);
    } else if (!failed) {
      failed = true;
      why = PQresultErrorMessage(r);
      const char* state = PQresultErrorField(r, PG_DIAG_SQLSTATE);
      if (state != nullptr) sqlstate = state;
    }
    PQclear(r);
  }
  if (failed) {
    if (PQstatus(conn_) != CONNECTION_OK) throw pqxx::broken_connection(why);
    throw pqxx::sql_error(why, command_, sqlstate.empty() ? nullptr : sqlstate.c_str());
  }
  if (PQstatus(conn_) != CONNECTION_OK) throw pqxx::broken_connection(trimmed_error(conn_));
  return rows;
}

}  // namespace calstand::fleet::detail
