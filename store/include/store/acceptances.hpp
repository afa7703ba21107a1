#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::store {

/// A row of table acceptances: one judgement of a calibration record against a specification.
struct AcceptanceRow {
  std::int64_t id = 0;
  std::int64_t calibration = 0;
  std::string spec_name;
  std::string spec_sha256;  ///< of the specification file's bytes, as read
  std::string verdict;      ///< "pass", "fail" or "indeterminate"
  nlohmann::json result;    ///< the whole outcome, as `calstand accept --json` prints a unit
  std::string created_utc;
};

/// Stores a judgement of calibration `calibration`; returns its id. Throws core::InputError for
/// an unknown calibration or verdict, StoreError on SQL failure.
std::int64_t insert_acceptance(Database& db, std::int64_t calibration, const std::string& spec_name,
                               const std::string& spec_sha256, const std::string& verdict,
                               const nlohmann::json& result);

/// The latest judgement of calibration `calibration`, if it was ever judged.
std::optional<AcceptanceRow> latest_acceptance(Database& db, std::int64_t calibration);

}  // namespace calstand::store
