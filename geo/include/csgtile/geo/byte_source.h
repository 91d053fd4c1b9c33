#pragma once
/// \file
/// Bytes that can be read at any offset: what the LAS/LAZ/COPC reader reads from. geo opens
/// files and memory itself; the worker gives it HTTP(S) and S3 objects read by range requests
/// (a COPC query then fetches only the octree nodes it needs).

#include <cstdint>
#include <span>
#include <string>

#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// Random-access bytes. Implementations need not be thread-safe: one reader uses one source.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  ByteSource(const ByteSource&) = delete;
  ByteSource& operator=(const ByteSource&) = delete;
  /// Size in bytes, fixed when the source was opened.
  virtual std::uint64_t size() const = 0;
  /// Reads exactly out.size() bytes at `offset`. Errors: IoError (or the transport's own
  /// code, e.g. Network), CorruptData (past the end).
  virtual kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) = 0;
  /// The name used in every message (a path or a URL without credentials).
  const std::string& name() const { return name_; }

 protected:
  explicit ByteSource(std::string name) : name_(std::move(name)) {}

 private:
  std::string name_;
};

}  // namespace csgtile::geo
