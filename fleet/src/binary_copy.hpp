#pragma once
// COPY ... FROM STDIN in PostgreSQL's binary format, inside a libpqxx transaction.
//
// Why binary and why through libpq: libpqxx 6.4 (Debian's) streams COPY in the text format
// only, formatting and escaping every field on the client (a 150 kB sample chunk travels as
// 300 kB of bytea hex, copied five times on the way) and parsing it again on the server. The
// binary format sends each value as the server stores it (integers and doubles as their 8
// bytes, blobs as they are). libpqxx keeps its PGconn to itself but hands it to its large
// object classes (`pqxx::largeobject::raw_connection`, protected): a class of ours derived from
// largeobject reads it there, and the COPY runs on the transaction's own connection, so it
// stays in the batch's transaction with its cursor.
//
// The format: the PostgreSQL manual, COPY, "Binary Format" (signature `PGCOPY\n\377\r\n\0`,
// a 32-bit flags field, a 32-bit header extension length; per row a 16-bit field count, then
// per field a 32-bit length (-1 for NULL) and the value in its type's binary send form, in
// network byte order; a 16-bit -1 as the trailer).

#include <cstdint>
#include <pqxx/pqxx>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::fleet::detail {

/// The PostgreSQL column types the sync copies, as binary COPY writes them.
enum class CopyType { kInt2, kInt4, kInt8, kFloat8, kText, kBytea, kUuid };

/// The CopyType of a column whose `format_type()` is `type` ("bigint", "double precision",
/// ...). Throws std::invalid_argument naming `column` and the type for any other type.
CopyType copy_type_of(const std::string& column, const std::string& type);

/// Rows in the binary COPY format, built in memory; send them with BinaryCopy::write.
/// Values are checked against their column's type: an integer beyond an int4 column's range,
/// a text that is not an integer, a number or a UUID where one is needed throw
/// std::invalid_argument naming the column.
class BinaryCopyRows {
 public:
  /// Starts a row of `fields` fields.
  void begin_row(std::size_t fields);
  void null();
  void integer(CopyType type, const char* column, std::int64_t value);
  void real(CopyType type, const char* column, double value);
  /// A value given as text (a SQLite TEXT, a fixed field): converted as PostgreSQL's text input
  /// would (integers, doubles and UUIDs parsed; text and bytea taken as they are).
  void text(CopyType type, const char* column, std::string_view value);
  /// Raw bytes (a SQLite BLOB) for a bytea or text column.
  void bytes(CopyType type, const char* column, const void* data, std::size_t size);

  /// Appends rows or fields encoded before (e.g. the fields every row starts with).
  void append(const BinaryCopyRows& other) { data_ += other.data_; }
  const std::string& data() const { return data_; }
  void clear() { data_.clear(); }

 private:
  void put16(std::uint16_t v);
  void put32(std::uint32_t v);
  void put64(std::uint64_t v);
  std::string data_;
};

/// `COPY table (columns) FROM STDIN (FORMAT binary)` on the connection of `tx`: write() the
/// rows, then finish(). Not finishing (an exception on the way) ends the COPY as failed, which
/// aborts the transaction: nothing of it is kept. Throws pqxx::broken_connection when the
/// connection is lost and pqxx::sql_error (with the SQLSTATE) when the server refuses.
class BinaryCopy {
 public:
  BinaryCopy(pqxx::dbtransaction& tx, const std::string& table,
             const std::vector<std::string>& columns);
  ~BinaryCopy();
  BinaryCopy(const BinaryCopy&) = delete;
  BinaryCopy& operator=(const BinaryCopy&) = delete;

  /// Sends `rows` (whole rows or not: the server reassembles the stream).
  void write(std::string_view rows);
  /// Sends the trailer, ends the COPY and returns the rows the server read.
  std::int64_t finish();

 private:
  pqxx::internal::pq::PGconn* conn_;
  std::string command_;
  bool open_ = false;
};

}  // namespace calstand::fleet::detail
