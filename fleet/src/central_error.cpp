#include "fleet/central_error.hpp"

#include <exception>
#include <pqxx/pqxx>

#include "core/error.hpp"

namespace calstand::fleet {

void rethrow_as_central(const std::string& operation) {
  try {
    throw;
  } catch (const core::InputError&) {
    throw;
  } catch (const CentralError&) {
    throw;
  } catch (const pqxx::broken_connection& e) {
    std::string why = e.what();
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw CentralError(operation, "no connection: " + why);
  } catch (const pqxx::sql_error& e) {
    // SQLSTATE first: 42501 (insufficient privilege, a row-level security refusal), 57P01 (the
    // server shut down), ... say more than the text in logs that are grepped.
    std::string why = e.what();
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw CentralError(operation, "SQLSTATE " + e.sqlstate() + ": " + why);
  } catch (const std::exception& e) {
    std::string why = e.what();
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw CentralError(operation, why);
  }
}

}  // namespace calstand::fleet
