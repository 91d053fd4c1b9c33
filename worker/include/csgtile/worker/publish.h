#pragma once
/// \file
/// Publishing outputs so that a reader never sees a half-written result: objects are
/// content-addressed (named by their SHA-256) and written through a temporary file that is
/// fsync'ed and renamed; manifests are written last, the same way.

#include <string_view>

#include "csgtile/worker/files.h"  // sha256_hex, write_file_atomic: the publishing primitives

namespace csgtile::worker {

/// A relative object key is safe when it has no "..", no absolute root, no empty or "."
/// segments and only [A-Za-z0-9._-] characters in its segments.
bool is_safe_key(std::string_view key);

}  // namespace csgtile::worker
