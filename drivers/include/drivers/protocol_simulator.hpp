#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/station_config.hpp"
#include "drivers/turntable.hpp"

namespace calstand::drivers {

class SimWorldRunner;

/// Where and how `calstand sim-station` serves its world.
struct ProtocolSimOptions {
  double time_scale = 1.0;         ///< world seconds per wall-clock second
  std::string host = "127.0.0.1";  ///< listening address of the TCP servers
  int table_port = 0;              ///< ACUTROL-style command server; 0: any free port
  int modbus_port = 0;             ///< Modbus TCP server (chamber_protocol's map); 0: any free
  /// The command set or register map the simulated chamber is served in over TCP
  /// (chamber_protocol_names() lists them).
  std::string chamber_protocol = "watlow-f4t";
  /// The command set the simulated table is served in (table_protocol_names() lists them).
  std::string table_protocol = "acutrol";
  bool f4_rtu = true;         ///< also serve the chamber as a Watlow F4 over RTU on a pty
  std::string can_interface;  ///< the first IMU's frames also on this CAN interface
  std::string can_map_file;   ///< the CAN signal map for them (docs/protocols.md)
  /// Each IMU's wire format on its line (imu_wire_format.hpp) by IMU name, "*" for every IMU
  /// not named; "calstand" where none applies.
  std::map<std::string, std::string> imu_formats;

  /// Throws core::InputError naming the option (--chamber-protocol, --table-protocol) and the
  /// names known when a protocol is not one.
  void validate() const;
};

/// The protocols sim-station can serve the chamber in, comma separated (for help and errors).
std::string chamber_protocol_names();
/// The protocols sim-station can serve the table in, comma separated.
std::string table_protocol_names();

/// One simulated world (the sim/ physics of a station file) behind the real protocols: the
/// table command server on TCP, the chamber over Modbus TCP (the chamber_protocol's map) and RTU on
/// a pseudo-terminal (F4 map), every IMU on a pseudo-terminal in its wire format (calstand frames,
/// or a real unit's protocol answering its configuration dialogue) and on CAN where an interface is
/// given. The real drivers, pointed at client_station(), cannot tell it from a lab, except that
/// time runs time_scale times faster.
class ProtocolSimulator {
 public:
  /// `sim_config`: a station whose backends are all "sim". Nothing runs until start().
  /// Throws core::InputError when `options` do not validate().
  ProtocolSimulator(const core::StationConfig& sim_config, ProtocolSimOptions options);
  ~ProtocolSimulator();

  /// Starts the world and every server; throws std::runtime_error naming the endpoint that
  /// could not be opened.
  void start();
  void stop();

  /// The endpoints as JSON (what `sim-station` prints on start).
  nlohmann::json endpoints() const;
  /// The station file for the real drivers: the same station with backends acutrol, modbus
  /// and serial pointed at the endpoints, and time_scale set.
  core::StationConfig client_station() const;

  // Fault rehearsal (sim-station's stdin commands; tests).
  /// The axis interlock opens (`why` becomes the fault text); the controller refuses motion
  /// until the cause is cleared and a client closes the interlock.
  void open_interlock(TableAxis axis, const std::string& why);
  void clear_interlock_cause(TableAxis axis);
  /// The Modbus servers stop answering (controller unplugged) or come back.
  void set_modbus_running(bool running);
  /// false: the table's link drops (every client connection closed, new ones closed at once)
  /// while the simulated table keeps doing what it was told, as a real controller does; true:
  /// connections are accepted again.
  void set_table_link(bool up);
  /// IMU `index` stops talking (frames are lost) or resumes.
  void set_imu_silent(std::size_t index, bool silent);
  /// Writes raw bytes on IMU `index`'s line (garbage, corrupted frames).
  void inject_imu_bytes(std::size_t index, std::vector<std::uint8_t> bytes);
  /// IMU `index`'s frames held back, or let go at once (a burst).
  void set_imu_held(std::size_t index, bool held);
  /// IMU `index`'s own clock jumps by `seconds`.
  void jump_imu_clock(std::size_t index, double seconds);
  std::size_t imu_index(const std::string& name) const;  ///< throws core::InputError

  /// Frames sent and dropped per IMU, world lag: for `status`.
  nlohmann::json statistics() const;
  SimWorldRunner& runner();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace calstand::drivers
