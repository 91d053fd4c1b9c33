#pragma once
/// \file
/// Publishing outputs so that a reader never sees a half-written result: objects are
/// content-addressed (named by their SHA-256) and written through a temporary file that is
/// fsync'ed and renamed; manifests are written last, the same way.

#include <filesystem>
#include <string>
#include <string_view>

#include "csgtile/worker/errors.h"

namespace csgtile::worker {

/// Lower-case hex SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);

/// Writes `bytes` to `path` atomically (temp file in the same directory, fsync, rename,
/// fsync of the directory). Creates parent directories. Error: Io, naming the path; also
/// when `path` exists and is not a regular file (a device, a pipe, a directory).
Failure write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

/// A relative object key is safe when it has no "..", no absolute root, no empty or "."
/// segments and only [A-Za-z0-9._-] characters in its segments.
bool is_safe_key(std::string_view key);

}  // namespace csgtile::worker
