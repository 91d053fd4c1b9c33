// Native files: atomic replacement on write (temporary + fsync + rename + directory fsync),
// whole-file read. POSIX calls: the C++ library has no fsync, and the service runs on Linux.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <string>
#include <string_view>
#include <system_error>

#include "csgtile/kernel/native_format.h"
#include "io/native_layout.h"

namespace csgtile::kernel {

namespace {

/// The message comes from std::generic_category (thread-safe, unlike strerror).
Error io_error(const std::string& what, const std::filesystem::path& path, int error_number) {
  return Error{ErrorCode::IoError,
               what + " " + path.string() + ": " + std::generic_category().message(error_number)};
}

/// Closes a file descriptor when it goes out of scope (unless released).
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }
  /// Closes now, reporting the error (close can report a failed delayed write).
  int close() {
    const int result = ::close(fd_);
    fd_ = -1;
    return result;
  }

 private:
  int fd_;
};

Status write_all(int fd, std::string_view bytes, const std::filesystem::path& path) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return io_error("cannot write", path, errno);
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return {};
}

/// A name in the same directory (rename is atomic only within one file system) that no
/// other writer, thread or process, uses at the same time.
std::filesystem::path temporary_path(const std::filesystem::path& path) {
  static std::atomic<unsigned long> counter{0};
  std::filesystem::path temporary = path;
  temporary.replace_filename("." + path.filename().string() + ".tmp." + std::to_string(::getpid()) +
                             "." + std::to_string(++counter));
  return temporary;
}

Status write_and_sync(const std::filesystem::path& temporary, std::string_view bytes) {
  FileDescriptor fd(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644));
  if (fd.get() < 0) return io_error("cannot create", temporary, errno);
  if (Status s = write_all(fd.get(), bytes, temporary); !s.ok()) return s;
  if (::fsync(fd.get()) != 0) return io_error("cannot sync", temporary, errno);
  if (fd.close() != 0) return io_error("cannot close", temporary, errno);
  return {};
}

}  // namespace

Status detail::write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  if (path.filename().empty()) {
    return Error{ErrorCode::IoError, "cannot write " + path.string() + ": not a file name"};
  }
  const std::filesystem::path temporary = temporary_path(path);
  if (Status s = write_and_sync(temporary, bytes); !s.ok()) {
    ::unlink(temporary.c_str());
    return s;
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error_number = errno;
    ::unlink(temporary.c_str());
    return io_error("cannot rename a temporary file to", path, error_number);
  }
  // Make the rename itself durable. File systems that cannot sync a directory say EINVAL;
  // the file is in place either way.
  std::filesystem::path directory = path.parent_path();
  if (directory.empty()) directory = ".";
  FileDescriptor dir(::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir.get() >= 0 && ::fsync(dir.get()) != 0 && errno != EINVAL) {
    return io_error("cannot sync directory", directory, errno);
  }
  return {};
}

Status write_native_file(const std::filesystem::path& path, const Shape& shape) {
  return detail::write_file_atomically(path, write_native(shape));
}

Result<std::string> detail::read_whole_file(const std::filesystem::path& path) {
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return io_error("cannot open", path, errno);
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      return io_error("cannot read", path, errno);
    }
    if (n == 0) break;
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  return bytes;
}

Result<Shape> read_native_file(const std::filesystem::path& path) {
  auto bytes = detail::read_whole_file(path);
  if (!bytes.ok()) return bytes.error();
  auto shape = read_native(bytes.value());
  if (!shape.ok()) {
    return Error{shape.error().code, path.string() + ": " + shape.error().message};
  }
  return shape;
}

}  // namespace csgtile::kernel
