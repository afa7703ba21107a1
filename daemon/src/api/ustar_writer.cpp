#include "daemon/api/ustar_writer.hpp"

#include <cstring>
#include <stdexcept>

namespace calstand::daemon::api {
namespace {

constexpr std::size_t kBlock = kUstarBlock;

// Writes `value` as width-1 zero-padded octal digits and a NUL (a value too large for the
// field keeps its low digits).
void put_octal(char* field, std::size_t width, std::uint64_t value) {
  field[width - 1] = '\0';
  for (std::size_t i = width - 1; i-- > 0;) {
    field[i] = static_cast<char>('0' + (value & 7));
    value >>= 3;
  }
}

}  // namespace

std::string ustar_header(std::string_view name, std::uint64_t size, std::int64_t mtime_s) {
  if (name.empty() || name.size() > 100 || name.front() == '/' ||
      name.find("..") != std::string_view::npos) {
    throw std::invalid_argument("ustar: file name '" + std::string(name) + "' not admitted");
  }
  char header[kBlock] = {};
  std::memcpy(header, name.data(), name.size());  // name[100]
  put_octal(header + 100, 8, 0644);               // mode
  put_octal(header + 108, 8, 0);                  // uid
  put_octal(header + 116, 8, 0);                  // gid
  if (size < (std::uint64_t{1} << 33)) {
    put_octal(header + 124, 12, size);  // size: 11 octal digits hold < 8 GiB
  } else {
    // Larger: the base-256 size field GNU tar and bsdtar read (high bit set, big-endian).
    header[124] = static_cast<char>(0x80);
    for (int i = 11; i >= 1; --i, size >>= 8) header[124 + i] = static_cast<char>(size & 0xFF);
  }
  put_octal(header + 136, 12, static_cast<std::uint64_t>(mtime_s < 0 ? 0 : mtime_s));
  std::memset(header + 148, ' ', 8);      // checksum counts as spaces
  header[156] = '0';                      // typeflag: regular file
  std::memcpy(header + 257, "ustar", 6);  // magic "ustar\0"
  std::memcpy(header + 263, "00", 2);     // version
  unsigned checksum = 0;
  for (unsigned char c : header) checksum += c;
  put_octal(header + 148, 7, checksum);  // six digits and a NUL, then the space kept
  header[155] = ' ';
  return std::string(header, kBlock);
}

std::size_t ustar_padding(std::uint64_t size) { return (kBlock - size % kBlock) % kBlock; }

void UstarWriter::add_file(std::string_view name, std::string_view content, std::int64_t mtime_s) {
  out_.append(ustar_header(name, content.size(), mtime_s));
  out_.append(content);
  out_.append(ustar_padding(content.size()), '\0');
}

std::string UstarWriter::finish() && {
  out_.append(2 * kBlock, '\0');
  return std::move(out_);
}

}  // namespace calstand::daemon::api
