#pragma once
// The simulator's side of a command set: sim-station serves its simulated chamber or table to
// clients in any command set (built-in or a user's file), so that a whole campaign can be
// rehearsed through the words of the controller a lab owns.

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/acutrol_server.hpp"
#include "drivers/command_set.hpp"
#include "drivers/modbus_chamber_server.hpp"

namespace calstand::drivers::line {

/// Answers the lines of a command set from a simulated device. Each incoming line is matched
/// against the set's command templates (made into patterns: the literal text, each replacement
/// field a capture), acted on through the backend when it is an operation's last step (a mode
/// then a demand act together), and answered by the step's `reply_format` with the device's
/// values, or the set's `error_format` with the backend's refusal. A step without a
/// `reply_format` cannot be served (answered with the error format, or not at all). Thread safe.
class CommandSetHandler {
 public:
  CommandSetHandler(CommandSet set, TableServerBackend& table);
  CommandSetHandler(CommandSet set, ChamberServerBackend& chamber);
  ~CommandSetHandler();
  /// The reply to one line (terminator excluded), or none (a step the device does not answer,
  /// an empty line).
  std::optional<std::string> handle(std::string_view line);
  const CommandSet& command_set() const { return set_; }

 private:
  struct Pattern;
  void compile();
  std::optional<std::string> act(const std::string& operation, std::size_t step_index,
                                 const Arguments& args);
  std::string refuse(const std::string& why) const;
  Fields table_fields(const std::string& operation, const Arguments& args, std::string& refusal);
  Fields chamber_fields(const std::string& operation, const Arguments& args, std::string& refusal);

  CommandSet set_;
  TableServerBackend* table_ = nullptr;
  ChamberServerBackend* chamber_ = nullptr;
  std::vector<Pattern> patterns_;
  std::mutex mutex_;
  std::map<std::string, Arguments> pending_;      ///< arguments of an operation's earlier steps
  std::map<std::string, std::size_t> next_step_;  ///< the step each operation expects next
};

/// A CommandSetHandler behind the line server (TCP, and a pseudo-terminal on request): lines
/// end at CR or LF, replies end with the set's terminator.
std::unique_ptr<AcutrolServer> make_command_set_server(std::shared_ptr<CommandSetHandler> handler,
                                                       AcutrolServerOptions options);

}  // namespace calstand::drivers::line
