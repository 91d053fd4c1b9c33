#include "csgtile/worker/files.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <fstream>
#include <random>
#include <set>
#include <span>
#include <string_view>
#include <system_error>

#include "ops/metrics.h"

namespace csgtile::worker {

// ---- digests ------------------------------------------------------------------------------

struct Sha256::State {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx{EVP_MD_CTX_new(), EVP_MD_CTX_free};
};

Sha256::Sha256() : state_(std::make_unique<State>()) { reset(); }
Sha256::~Sha256() = default;

void Sha256::reset() { EVP_DigestInit_ex(state_->ctx.get(), EVP_sha256(), nullptr); }

void Sha256::update(std::string_view bytes) {
  EVP_DigestUpdate(state_->ctx.get(), bytes.data(), bytes.size());
}

namespace {
std::string hex_of(const unsigned char* digest, std::size_t length) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * length);
  for (std::size_t i = 0; i < length; ++i) {
    out.push_back(kHex[digest[i] >> 4]);
    out.push_back(kHex[digest[i] & 15]);
  }
  return out;
}
}  // namespace

std::string Sha256::hex() {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(state_->ctx.get(), digest.data(), &length);
  return hex_of(digest.data(), length);
}

std::string hex_encode(std::string_view bytes) {
  return hex_of(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
}

std::optional<std::string> hmac_sha256(std::string_view key, std::string_view data) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> mac{};
  unsigned int length = 0;
  if (HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()),
           reinterpret_cast<const unsigned char*>(data.data()), data.size(), mac.data(),
           &length) == nullptr) {
    return std::nullopt;
  }
  return std::string(reinterpret_cast<const char*>(mac.data()), length);
}

std::string sha256_hex(std::string_view bytes) {
  Sha256 sha;
  sha.update(bytes);
  return sha.hex();
}

namespace {

// Streams `path` to `take` in blocks of 64 KiB. Error: Io naming the path.
template <typename Take>
Failure read_in_blocks(const std::filesystem::path& path, Take take) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {ErrorCode::Io, "cannot read " + path.string()};
  std::array<char, 1 << 16> buffer{};
  while (in) {
    in.read(buffer.data(), buffer.size());
    take(std::string_view(buffer.data(), static_cast<std::size_t>(in.gcount())));
  }
  if (in.bad()) return {ErrorCode::Io, "cannot read " + path.string()};
  return {};
}

}  // namespace

Failure file_sha256(const std::filesystem::path& path, std::string& hex, std::uint64_t& bytes) {
  Sha256 sha;
  bytes = 0;
  Failure read = read_in_blocks(path, [&](std::string_view block) {
    sha.update(block);
    bytes += block.size();
  });
  if (!read.ok()) return read;
  hex = sha.hex();
  return {};
}

Failure read_file_bytes(const std::filesystem::path& path, std::string& bytes) {
  bytes.clear();
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) bytes.reserve(static_cast<std::size_t>(size));
  return read_in_blocks(path, [&](std::string_view block) { bytes.append(block); });
}

// ---- atomic replacement -------------------------------------------------------------------

namespace {

Failure io_error(const std::string& what, const std::filesystem::path& path, int err) {
  return {ErrorCode::Io, what + " " + path.string() + ": " + std::generic_category().message(err)};
}

// The rename would replace whatever is at `target`: never a device, a pipe or a directory
// (`--out /dev/null` must not turn the device node into a file).
Failure refuse_special(const std::filesystem::path& target) {
  std::error_code ec;
  const auto status = std::filesystem::status(target, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    return {ErrorCode::Io, target.string() + ": not a regular file (it would be replaced)"};
  }
  return {};
}

std::filesystem::path directory_of(const std::filesystem::path& path) {
  return path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
}

// Flushes a directory: the renames into it are durable once it is.
void sync_directory(const std::filesystem::path& dir) {
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace

std::filesystem::path temp_path_beside(const std::filesystem::path& target, std::string_view tag) {
  // Unique within the process by the counter, across processes by the pid and a random start
  // (drawn once: a random_device read per file cost more than the write of a small one).
  static std::atomic<std::uint64_t> next{std::random_device{}()};
  return directory_of(target) / ("." + target.filename().string() + "." + std::string(tag) + "." +
                                 std::to_string(::getpid()) + "." + std::to_string(next++));
}

Failure commit_temp_file(const std::filesystem::path& temp, const std::filesystem::path& target) {
  auto fail = [&](Failure f) {
    ::unlink(temp.c_str());
    return f;
  };
  if (Failure f = refuse_special(target); !f.ok()) return fail(f);
  const int fd = ::open(temp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return fail(io_error("cannot open", temp, errno));
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    return fail(io_error("cannot flush", temp, err));
  }
  ::close(fd);
  if (::rename(temp.c_str(), target.c_str()) != 0) {
    return fail(io_error("cannot rename into", target, errno));
  }
  sync_directory(directory_of(target));
  return {};
}

namespace {

// Writes `bytes` to a new temporary beside `path` (parent directories created), starts its
// write-back and leaves it open, not yet flushed: `fd` and `tmp` name it; on failure it is closed
// and removed.
Failure write_temp(const std::filesystem::path& path, std::string_view bytes,
                   std::filesystem::path& tmp, int& fd) {
  if (Failure f = refuse_special(path); !f.ok()) return f;
  std::error_code ec;
  const std::filesystem::path dir = directory_of(path);
  std::filesystem::create_directories(dir, ec);
  if (ec) return {ErrorCode::Io, "cannot create directory " + dir.string() + ": " + ec.message()};
  tmp = temp_path_beside(path, "tmp");
  fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return io_error("cannot create", tmp, errno);
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      fd = -1;
      return io_error("cannot write", tmp, err);
    }
    written += static_cast<std::size_t>(n);
  }
  // Its data on the way to the disk now, so that the batch's flushes find most of it written.
  (void)::sync_file_range(fd, 0, 0, SYNC_FILE_RANGE_WRITE);
  return {};
}

// Flushes and closes a temporary write_temp left open.
Failure flush_temp(int fd, const std::filesystem::path& tmp) {
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    return io_error("cannot flush", tmp, err);
  }
  if (::close(fd) != 0) return io_error("cannot close", tmp, errno);
  return {};
}

// One file of an atomic write.
struct Pending {
  const std::filesystem::path* path;
  std::string_view bytes;
};

// Every file to a flushed temporary, then every rename, then each directory flushed once.
// The temporaries are written a batch at a time and then flushed: one journal commit covers
// many files (a cell publishes three per building), and few descriptors are open at once.
Failure write_atomic(std::span<const Pending> files) {
  constexpr std::size_t kBatch = 64;
  std::vector<std::filesystem::path> temps;
  temps.reserve(files.size());
  const auto remove_temps = [&temps](std::size_t from) {
    for (std::size_t i = from; i < temps.size(); ++i) ::unlink(temps[i].c_str());
  };
  std::vector<int> open;
  const auto fail = [&](Failure f) {
    for (int fd : open) ::close(fd);
    remove_temps(0);
    return f;
  };
  for (std::size_t first = 0; first < files.size(); first += kBatch) {
    const std::size_t last = std::min(files.size(), first + kBatch);
    open.clear();
    for (std::size_t i = first; i < last; ++i) {
      std::filesystem::path tmp;
      int fd = -1;
      if (Failure f = write_temp(*files[i].path, files[i].bytes, tmp, fd); !f.ok()) {
        return fail(f);
      }
      temps.push_back(std::move(tmp));
      open.push_back(fd);
    }
    for (std::size_t k = 0; k < open.size(); ++k) {
      const int fd = open[k];
      open[k] = -1;
      if (Failure f = flush_temp(fd, temps[first + k]); !f.ok()) {
        std::erase(open, -1);
        return fail(f);
      }
    }
    open.clear();
  }
  std::set<std::filesystem::path> dirs;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (::rename(temps[i].c_str(), files[i].path->c_str()) != 0) {
      const int err = errno;
      remove_temps(i);
      return io_error("cannot rename into", *files[i].path, err);
    }
    dirs.insert(directory_of(*files[i].path));
  }
  for (const std::filesystem::path& dir : dirs) sync_directory(dir);
  for (const Pending& file : files) ops::metrics().add_bytes_published(file.bytes.size());
  return {};
}

}  // namespace

Failure write_file_atomic(const std::filesystem::path& path, std::string_view bytes) {
  const Pending file{&path, bytes};
  return write_atomic({&file, 1});
}

Failure write_files_atomic(
    const std::vector<std::pair<std::filesystem::path, std::string>>& files) {
  std::vector<Pending> pending;
  pending.reserve(files.size());
  for (const auto& [path, bytes] : files) pending.push_back({&path, bytes});
  return write_atomic(pending);
}

}  // namespace csgtile::worker
