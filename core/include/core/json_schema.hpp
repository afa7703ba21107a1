#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace calstand::core {

/// One rule a document breaks. `path` locates the value, e.g. `steps[3].rate_dps` (empty for
/// the document root; keys that are not identifiers are written `["odd key"]`); `message` says
/// what is wrong in words a lab engineer reads, e.g. `220 is greater than the maximum 200`.
struct SchemaViolation {
  std::string path;
  std::string message;
};

/// A JSON Schema (draft 2020-12 subset), checked and compiled once, then used to validate any
/// number of documents.
///
/// Supported keywords: type, enum, const, properties, required, additionalProperties,
/// patternProperties, propertyNames, items, prefixItems, minItems, maxItems, uniqueItems,
/// minimum, maximum, exclusiveMinimum, exclusiveMaximum, multipleOf, minLength, maxLength,
/// pattern, allOf, anyOf, oneOf, not, if/then/else, $ref to a local JSON pointer ("#",
/// "#/$defs/name", "#/definitions/name", ...), $defs/definitions. Annotations (title,
/// description, default, examples, deprecated, readOnly, writeOnly, $schema, $id, $comment)
/// and keys starting with "x-" are ignored. Regular expressions are ECMAScript (std::regex),
/// unanchored as the standard says.
///
/// Copies share the compiled form; a JsonSchema is immutable, so validate() is thread safe.
class JsonSchema {
 public:
  /// Checks and compiles `schema`. `name` (usually the schema file name) prefixes load errors.
  /// Throws InputError, naming the schema and the JSON pointer of the offending subschema, on
  /// an unknown keyword (so a typo such as "maximun" cannot silently disable a rule), a keyword
  /// value of the wrong shape, an invalid regular expression, or a $ref that is not local or
  /// whose target does not exist.
  static JsonSchema parse(const nlohmann::json& schema, std::string name);

  /// Every violation of `doc`, in a stable order (document order within an object, which for
  /// nlohmann::json is key order); empty when `doc` is valid. Never throws for any document.
  /// After a type mismatch at a path, no further rules are checked at that path, so one
  /// mistake gives one message.
  std::vector<SchemaViolation> validate(const nlohmann::json& doc) const;

  /// The name given to parse().
  const std::string& name() const;

 private:
  struct Impl;
  explicit JsonSchema(std::shared_ptr<const Impl> impl);
  std::shared_ptr<const Impl> impl_;
};

/// A document that breaks its schema. what() lists every violation, one per line, as
/// `FILE: PATH: MESSAGE` (`FILE: MESSAGE` for the document root); where() is the file name.
class SchemaError : public InputError {
 public:
  SchemaError(const std::string& file_name, std::vector<SchemaViolation> violations);
  const std::vector<SchemaViolation>& violations() const { return violations_; }

 private:
  std::vector<SchemaViolation> violations_;
};

/// Throws SchemaError listing every violation when `doc` (read from `file_name`) breaks
/// `schema`; returns normally when it is valid.
void validate_or_throw(const JsonSchema& schema, const nlohmann::json& doc,
                       const std::string& file_name);

/// Parses JSON text. Throws InputError whose where() is `FILE:LINE:COLUMN` on a syntax error
/// (1-based; the column counts characters, not bytes, and points at the last character the
/// parser read: the end of the offending token), and InputError naming the JSON path on a key
/// repeated within one object (plain JSON parsers keep the last one silently, which hides a
/// mistyped file).
nlohmann::json parse_json_text(std::string_view text, const std::string& file_name);

/// Reads and parses the file at `path` as parse_json_text() does. Throws InputError naming the
/// path when the file cannot be opened or read.
nlohmann::json read_json_file(const std::string& path);

}  // namespace calstand::core
