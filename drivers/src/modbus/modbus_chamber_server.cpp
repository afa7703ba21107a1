#include "drivers/modbus_chamber_server.hpp"

#include <fmt/format.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace calstand::drivers {
namespace {

constexpr int kPollMs = 100;  // how quickly stop() is noticed [ms]

std::uint16_t word_at(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

/// Address range [first, first + count) of one register table.
struct Range {
  int first = INT_MAX;
  int last = -1;
  void add(int address, int count) {
    first = std::min(first, address);
    last = std::max(last, address + count - 1);
  }
  int count() const { return last < first ? 0 : last - first + 1; }
  int start() const { return last < first ? 0 : first; }
};

bool covers(const RegisterField& f, int address) {
  return f.kind == RegisterKind::kHolding && address >= f.address &&
         address < f.address + f.register_count();
}

}  // namespace

struct ModbusChamberServer::Impl {
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  int listen_fd = -1;
  std::vector<int> clients;
  std::optional<double> ramp_c_per_min;  // last written to the ramp register

  std::uint16_t* holding(int address) {
    return &mapping->tab_registers[address - int(mapping->start_registers)];
  }
  std::uint16_t* input(int address) {
    return &mapping->tab_input_registers[address - int(mapping->start_input_registers)];
  }
  std::uint16_t* slot(const RegisterField& f) {
    return f.kind == RegisterKind::kHolding ? holding(f.address) : input(f.address);
  }
  void store(const RegisterField& f, double value) {
    auto words = encode_value(f, value);
    // A value the encoding cannot hold is shown as the integer full scale, which is what an
    // integer controller does with an over-range reading.
    if (!words) {
      words = RegisterWords{};
      words->count = f.register_count();
      words->words[0] = value < 0 ? 0x8000 : 0x7FFF;
    }
    std::copy_n(words->words.begin(), words->count, slot(f));
  }
  void close_clients() {
    for (int fd : clients) ::close(fd);
    clients.clear();
  }
};

std::unique_ptr<ModbusChamberServer> ModbusChamberServer::tcp(ChamberRegisterMap map,
                                                              ChamberServerBackend& backend,
                                                              int port, int unit_id,
                                                              std::string bind_host) {
  return std::unique_ptr<ModbusChamberServer>(
      new ModbusChamberServer(std::move(map), backend, port, unit_id, false, std::move(bind_host)));
}

std::unique_ptr<ModbusChamberServer> ModbusChamberServer::rtu(ChamberRegisterMap map,
                                                              ChamberServerBackend& backend,
                                                              int unit_id) {
  return std::unique_ptr<ModbusChamberServer>(
      new ModbusChamberServer(std::move(map), backend, 0, unit_id, true, ""));
}

ModbusChamberServer::ModbusChamberServer(ChamberRegisterMap map, ChamberServerBackend& backend,
                                         int port, int unit_id, bool rtu, std::string bind_host)
    : map_(std::move(map)),
      backend_(backend),
      port_(port),
      unit_id_(unit_id),
      bind_host_(std::move(bind_host)),
      impl_(std::make_unique<Impl>()) {
  if (rtu) pty_ = std::make_unique<PseudoTerminal>();
  Range hr, ir;
  auto add = [&](const RegisterField& f) {
    (f.kind == RegisterKind::kHolding ? hr : ir).add(f.address, f.register_count());
  };
  add(map_.process_value);
  add(map_.setpoint);
  if (map_.ramp_rate) add(*map_.ramp_rate);
  if (map_.mode) hr.add(map_.mode->address, 1);
  for (const auto& alarm : map_.alarms) hr.add(alarm.address, 1);
  impl_->mapping =
      modbus_mapping_new_start_address(0, 0, 0, 0, unsigned(hr.start()), unsigned(hr.count()),
                                       unsigned(ir.start()), unsigned(ir.count()));
  if (impl_->mapping == nullptr) throw std::runtime_error("modbus server: out of memory");
}

ModbusChamberServer::~ModbusChamberServer() {
  stop();
  modbus_mapping_free(impl_->mapping);
}

std::string ModbusChamberServer::slave_path() const { return pty_ ? pty_->slave_path() : ""; }

void ModbusChamberServer::start() {
  if (running()) return;
  auto& im = *impl_;
  if (pty_) {
    im.ctx = modbus_new_rtu(pty_->slave_path().c_str(), 9600, 'N', 8, 1);
    if (im.ctx == nullptr) throw std::runtime_error("modbus server: cannot create an RTU context");
    modbus_set_slave(im.ctx, unit_id_);
    modbus_set_socket(im.ctx, pty_->master_fd());
    // Requests sent while we were stopped are long timed out at the client: answering them now
    // would only confuse it.
    std::uint8_t junk[256];
    while (::read(pty_->master_fd(), junk, sizeof junk) > 0) {
    }
  } else {
    im.ctx = modbus_new_tcp(bind_host_.c_str(), port_);
    if (im.ctx == nullptr) {
      throw std::runtime_error("modbus server " + bind_host_ + ": cannot create a TCP context");
    }
    im.listen_fd = modbus_tcp_listen(im.ctx, 8);
    if (im.listen_fd < 0) {
      const int err = errno;
      modbus_free(im.ctx);
      im.ctx = nullptr;
      throw std::runtime_error(
          fmt::format("modbus server {}:{}: listen: {}", bind_host_, port_, std::strerror(err)));
    }
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    if (::getsockname(im.listen_fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
      port_ = ntohs(addr.sin_port);
    }
  }
  // libmodbus sleeps for the response timeout after answering a garbled or unknown request
  // (to let a serial line fall silent) and waits up to the byte timeout for the rest of a
  // torn frame. Its 500 ms defaults would stall every other TCP client that long; a serial
  // frame's bytes are milliseconds apart even at 9600 bit/s.
  modbus_set_response_timeout(im.ctx, 0, 50000);
  modbus_set_byte_timeout(im.ctx, 0, 100000);
  stopping_ = false;
  thread_ = std::thread([this] { pty_ ? serve_rtu() : serve_tcp(); });
}

void ModbusChamberServer::stop() noexcept {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  auto& im = *impl_;
  im.close_clients();
  if (im.listen_fd >= 0) ::close(im.listen_fd);
  im.listen_fd = -1;
  if (im.ctx != nullptr) {
    // The descriptors are ours (clients, pty master): keep modbus_free() from touching them.
    modbus_set_socket(im.ctx, -1);
    modbus_free(im.ctx);
    im.ctx = nullptr;
  }
}

void ModbusChamberServer::serve_tcp() {
  auto& im = *impl_;
  std::vector<std::uint8_t> query(MODBUS_TCP_MAX_ADU_LENGTH);
  std::vector<pollfd> fds;
  while (!stopping_) {
    fds.clear();
    fds.push_back({im.listen_fd, POLLIN, 0});
    for (int fd : im.clients) fds.push_back({fd, POLLIN, 0});
    if (::poll(fds.data(), fds.size(), kPollMs) <= 0) continue;
    if (fds[0].revents & POLLIN) {
      const int fd = ::accept(im.listen_fd, nullptr, nullptr);
      if (fd >= 0) im.clients.push_back(fd);
    }
    for (std::size_t i = 1; i < fds.size(); ++i) {
      if (fds[i].revents == 0) continue;
      modbus_set_socket(im.ctx, fds[i].fd);
      const int n = modbus_receive(im.ctx, query.data());
      if (n > 0) {
        answer(query.data(), n);
      } else if (n < 0) {
        // Closed by the client, or a frame libmodbus cannot parse: drop that connection only.
        ::close(fds[i].fd);
        std::erase(im.clients, fds[i].fd);
      }
    }
  }
}

void ModbusChamberServer::serve_rtu() {
  auto& im = *impl_;
  std::vector<std::uint8_t> query(MODBUS_RTU_MAX_ADU_LENGTH);
  while (!stopping_) {
    pollfd fd{pty_->master_fd(), POLLIN, 0};
    if (::poll(&fd, 1, kPollMs) <= 0) continue;
    const int n = modbus_receive(im.ctx, query.data());
    if (n > 0) {
      answer(query.data(), n);
    } else if (n < 0) {
      // Bad CRC or a torn frame: discard the rest, as a controller resynchronises on silence.
      modbus_flush(im.ctx);
    }
  }
}

void ModbusChamberServer::answer(const std::uint8_t* query, int length) {
  auto& im = *impl_;
  ++requests_;
  const int h = modbus_get_header_length(im.ctx);
  if (length < h + 1) return;
  const auto state = backend_.state();
  im.store(map_.process_value, state.air_temperature_c);
  im.store(map_.setpoint, state.setpoint_c);
  if (map_.mode) {
    *im.holding(map_.mode->address) =
        state.mode == core::ChamberMode::kActive ? map_.mode->control : map_.mode->standby;
  }
  if (map_.ramp_rate && im.ramp_c_per_min) im.store(*map_.ramp_rate, *im.ramp_c_per_min);

  const std::uint8_t function = query[h];
  if (function == MODBUS_FC_WRITE_AND_READ_REGISTERS) {
    // Not needed by any chamber client; refusing it keeps every write on the checked path.
    modbus_reply_exception(im.ctx, query, MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
    return;
  }
  if (function != MODBUS_FC_WRITE_SINGLE_REGISTER &&
      function != MODBUS_FC_WRITE_MULTIPLE_REGISTERS) {
    modbus_reply(im.ctx, query, length, im.mapping);
    return;
  }

  // Writes: decode the registers as they will be, act on the backend, and only then let
  // libmodbus store them and acknowledge (a refused value leaves the registers unchanged).
  if (length < h + 5) return;
  const int address = word_at(query + h + 1);
  std::vector<std::uint16_t> values;
  if (function == MODBUS_FC_WRITE_SINGLE_REGISTER) {
    values.push_back(word_at(query + h + 3));
  } else {
    const int count = word_at(query + h + 3);
    if (count < 1 || count > MODBUS_MAX_WRITE_REGISTERS || length < h + 6 + 2 * count) {
      modbus_reply(im.ctx, query, length, im.mapping);  // libmodbus answers the exception
      return;
    }
    for (int i = 0; i < count; ++i) values.push_back(word_at(query + h + 6 + 2 * i));
  }
  const int last = address + int(values.size()) - 1;
  const bool is_mode = map_.mode && address <= map_.mode->address && map_.mode->address <= last;
  for (int a = address; a <= last; ++a) {
    const bool writable = covers(map_.setpoint, a) ||
                          (map_.ramp_rate && covers(*map_.ramp_rate, a)) ||
                          (map_.mode && a == map_.mode->address);
    if (!writable) {
      modbus_reply_exception(im.ctx, query, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
      return;
    }
  }
  auto future = [&](const RegisterField& f) {
    RegisterWords w;
    w.count = f.register_count();
    for (int i = 0; i < w.count; ++i) {
      const int a = f.address + i;
      w.words[std::size_t(i)] =
          (a >= address && a <= last) ? values[std::size_t(a - address)] : *im.holding(a);
    }
    return decode_value(f, w.span());
  };
  auto touches = [&](const RegisterField& f) {
    return f.address <= last && address <= f.address + f.register_count() - 1;
  };
  Result r;
  if (map_.ramp_rate && touches(*map_.ramp_rate)) {
    r = backend_.set_ramp(future(*map_.ramp_rate));
    if (r) im.ramp_c_per_min = future(*map_.ramp_rate);
  }
  if (r && touches(map_.setpoint)) {
    r = backend_.set_setpoint(future(map_.setpoint));
    // A controller without a mode register controls whenever it has a setpoint.
    if (r && !map_.mode) r = backend_.set_mode(ChamberServerBackend::Mode::kControl);
  }
  if (r && is_mode) {
    const std::uint16_t v = values[std::size_t(map_.mode->address - address)];
    if (v == map_.mode->control) {
      r = backend_.set_mode(ChamberServerBackend::Mode::kControl);
    } else if (v == map_.mode->standby) {
      r = backend_.set_mode(ChamberServerBackend::Mode::kStandby);
    } else {
      r = Result::failure(fmt::format("mode {} is neither control nor standby", v));
    }
  }
  if (!r) {
    modbus_reply_exception(im.ctx, query, MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    return;
  }
  modbus_reply(im.ctx, query, length, im.mapping);
}

}  // namespace calstand::drivers
