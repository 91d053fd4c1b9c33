#pragma once
/// \file
/// Content digests and atomic file replacement: the two things fetch, publishing and the
/// exporters share about files. A file is made visible only when it is complete: it is
/// written under a temporary name beside its target, flushed to disk, renamed onto the target
/// (atomic within one file system) and the rename made durable by flushing the directory.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "csgtile/worker/errors.h"

namespace csgtile::worker {

/// Incremental SHA-256: feed bytes with update(), read the lower-case hex with hex().
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  /// Starts again from no bytes.
  void reset();
  void update(std::string_view bytes);
  /// The digest of the bytes fed since construction or reset(), as 64 lower-case hex digits.
  /// Ends the digest: call reset() before feeding more.
  std::string hex();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Lower-case hex SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);

/// Lower-case hex of raw bytes.
std::string hex_encode(std::string_view bytes);

/// HMAC-SHA256 of `data` under `key`, as raw bytes (32); nullopt when OpenSSL fails.
std::optional<std::string> hmac_sha256(std::string_view key, std::string_view data);

/// Streams `path` through SHA-256 (lower-case hex) and counts its bytes; Io when unreadable.
Failure file_sha256(const std::filesystem::path& path, std::string& hex, std::uint64_t& bytes);

/// The whole of `path` into `bytes` (read in large blocks, not a character at a time); Io
/// naming the path when it cannot be opened or read.
Failure read_file_bytes(const std::filesystem::path& path, std::string& bytes);

/// A fresh temporary name beside `target` (same directory, so a rename onto `target` is
/// atomic): ".<name>.<tag>.<pid>.<random>". Concurrent writers of one target never share it.
std::filesystem::path temp_path_beside(const std::filesystem::path& target, std::string_view tag);

/// Makes the complete file `temp` visible as `target`: flushes it to disk, renames it onto
/// `target` and flushes the directory. Refuses a `target` that exists and is not a regular
/// file (a device, a pipe, a directory would be replaced). On failure `temp` is removed and
/// the error (Io) names the path and the cause.
Failure commit_temp_file(const std::filesystem::path& temp, const std::filesystem::path& target);

/// Writes `bytes` to `path` atomically: a temporary beside it, then commit_temp_file().
/// Creates parent directories. Error: Io, naming the path.
Failure write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

/// Writes several files atomically as one batch: each to a temporary beside it, flushed;
/// then each renamed onto its path, and each directory flushed once for the batch (not once
/// per file). A file appears whole or not at all; on failure the temporaries not yet renamed
/// are removed and the error (Io) names the path. Creates parent directories.
Failure write_files_atomic(const std::vector<std::pair<std::filesystem::path, std::string>>& files);

}  // namespace csgtile::worker
