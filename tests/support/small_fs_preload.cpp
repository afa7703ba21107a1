// A small filesystem for tests, by LD_PRELOAD: writes into one folder fail with ENOSPC once the
// files in it would hold more than a capacity, as on a full disk; statvfs() of the folder
// reports that capacity; removing a file gives its space back. So a test can fill "the disk"
// under a real calstand process (its SQLite writes, its reserve file, its free-space checks)
// without root, a loop device or a small partition.
//
//   CALSTAND_SMALL_FS_DIR=/abs/folder            the folder that is "the disk" (not recursive)
//   CALSTAND_SMALL_FS_CAPACITY_FILE=/abs/file    holds the capacity in bytes; read at every
//                                                write, so a test frees space by raising it
//
// Growth is counted in 4 KiB blocks: a write inside a file's present size (SQLite rewriting a
// page, the WAL reused after a checkpoint) needs no new space.
#include <dirent.h>
#include <dlfcn.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr long long kBlock = 4096;

long long blocks_of(long long bytes) { return (bytes + kBlock - 1) / kBlock; }

const char* folder() {
  static const char* dir = std::getenv("CALSTAND_SMALL_FS_DIR");
  return dir;
}

long long capacity_bytes() {
  const char* file = std::getenv("CALSTAND_SMALL_FS_CAPACITY_FILE");
  if (file == nullptr) return -1;
  FILE* f = std::fopen(file, "r");
  if (f == nullptr) return -1;
  long long bytes = -1;
  if (std::fscanf(f, "%lld", &bytes) != 1) bytes = -1;
  std::fclose(f);
  return bytes;
}

// Bytes the folder's regular files hold, in whole blocks.
long long used_bytes() {
  DIR* d = opendir(folder());
  if (d == nullptr) return 0;
  long long blocks = 0;
  while (const dirent* e = readdir(d)) {
    struct stat st {};
    const std::string path = std::string(folder()) + "/" + e->d_name;
    if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) blocks += blocks_of(st.st_size);
  }
  closedir(d);
  return blocks * kBlock;
}

bool in_folder(const std::string& path) {
  const char* dir = folder();
  if (dir == nullptr) return false;
  const std::size_t n = std::strlen(dir);
  return path.size() > n && path.compare(0, n, dir) == 0 && path[n] == '/' &&
         path.find('/', n + 1) == std::string::npos;
}

std::string path_of(int fd) {
  char link[64];
  std::snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  char target[4096];
  const ssize_t n = ::readlink(link, target, sizeof target - 1);
  if (n <= 0) return {};
  return std::string(target, static_cast<std::size_t>(n));
}

// False (errno ENOSPC) when growing the file of `fd` to `new_end` bytes does not fit.
bool fits(int fd, long long new_end) {
  const std::string path = path_of(fd);
  if (!in_folder(path)) return true;
  const long long capacity = capacity_bytes();
  if (capacity < 0) return true;
  struct stat st {};
  if (::fstat(fd, &st) != 0) return true;
  const long long growth = (blocks_of(new_end) - blocks_of(st.st_size)) * kBlock;
  if (growth <= 0 || used_bytes() + growth <= capacity) return true;
  errno = ENOSPC;
  return false;
}

long long position_of(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0 && (flags & O_APPEND) != 0) {
    struct stat st {};
    return ::fstat(fd, &st) == 0 ? st.st_size : 0;
  }
  const off_t at = ::lseek(fd, 0, SEEK_CUR);
  return at < 0 ? 0 : at;
}

template <typename F>
F next(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

void report_statvfs(struct statvfs* buf) {
  const long long capacity = capacity_bytes();
  if (capacity < 0) return;
  const long long used = used_bytes();
  buf->f_bsize = buf->f_frsize = kBlock;
  buf->f_blocks = static_cast<fsblkcnt_t>(capacity / kBlock);
  const long long free_blocks = capacity > used ? (capacity - used) / kBlock : 0;
  buf->f_bfree = buf->f_bavail = static_cast<fsblkcnt_t>(free_blocks);
}

bool path_in_folder_or_is(const char* path) {
  const char* dir = folder();
  if (dir == nullptr || path == nullptr) return false;
  char resolved[4096];
  if (::realpath(path, resolved) == nullptr) return false;
  return std::strcmp(resolved, dir) == 0 || in_folder(resolved);
}

}  // namespace

extern "C" {

ssize_t write(int fd, const void* buf, size_t count) {
  static auto real = next<ssize_t (*)(int, const void*, size_t)>("write");
  if (!fits(fd, position_of(fd) + static_cast<long long>(count))) return -1;
  return real(fd, buf, count);
}

ssize_t pwrite(int fd, const void* buf, size_t count, off_t offset) {
  static auto real = next<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite");
  if (!fits(fd, offset + static_cast<long long>(count))) return -1;
  return real(fd, buf, count, offset);
}

ssize_t pwrite64(int fd, const void* buf, size_t count, off64_t offset) {
  static auto real = next<ssize_t (*)(int, const void*, size_t, off64_t)>("pwrite64");
  if (!fits(fd, offset + static_cast<long long>(count))) return -1;
  return real(fd, buf, count, offset);
}

ssize_t writev(int fd, const struct iovec* iov, int n) {
  static auto real = next<ssize_t (*)(int, const struct iovec*, int)>("writev");
  long long count = 0;
  for (int i = 0; i < n; ++i) count += static_cast<long long>(iov[i].iov_len);
  if (!fits(fd, position_of(fd) + count)) return -1;
  return real(fd, iov, n);
}

int ftruncate(int fd, off_t length) {
  static auto real = next<int (*)(int, off_t)>("ftruncate");
  if (!fits(fd, length)) return -1;
  return real(fd, length);
}

int ftruncate64(int fd, off64_t length) {
  static auto real = next<int (*)(int, off64_t)>("ftruncate64");
  if (!fits(fd, length)) return -1;
  return real(fd, length);
}

int fallocate(int fd, int mode, off_t offset, off_t length) {
  static auto real = next<int (*)(int, int, off_t, off_t)>("fallocate");
  if (!fits(fd, offset + length)) return -1;
  return real(fd, mode, offset, length);
}

int fallocate64(int fd, int mode, off64_t offset, off64_t length) {
  static auto real = next<int (*)(int, int, off64_t, off64_t)>("fallocate64");
  if (!fits(fd, offset + length)) return -1;
  return real(fd, mode, offset, length);
}

// posix_fallocate returns the error instead of setting errno.
int posix_fallocate(int fd, off_t offset, off_t length) {
  static auto real = next<int (*)(int, off_t, off_t)>("posix_fallocate");
  if (!fits(fd, offset + length)) return ENOSPC;
  return real(fd, offset, length);
}

int posix_fallocate64(int fd, off64_t offset, off64_t length) {
  static auto real = next<int (*)(int, off64_t, off64_t)>("posix_fallocate64");
  if (!fits(fd, offset + length)) return ENOSPC;
  return real(fd, offset, length);
}

int statvfs(const char* path, struct statvfs* buf) {
  static auto real = next<int (*)(const char*, struct statvfs*)>("statvfs");
  const int r = real(path, buf);
  if (r == 0 && path_in_folder_or_is(path)) report_statvfs(buf);
  return r;
}

int statvfs64(const char* path, struct statvfs64* buf) {
  static auto real = next<int (*)(const char*, struct statvfs64*)>("statvfs64");
  const int r = real(path, buf);
  if (r == 0 && path_in_folder_or_is(path)) report_statvfs(reinterpret_cast<struct statvfs*>(buf));
  return r;
}

}  // extern "C"
