#pragma once
// Random-access byte sources under the point readers (a file through pread, or memory), and
// a buffered sequential reader for the text formats. Private to geo.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/geo/byte_source.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo::detail {

/// The public interface (csgtile/geo/byte_source.h) under its private name.
using ByteSource = geo::ByteSource;

/// Opens `path` for reading. Errors: IoError naming the file and the system's reason.
kernel::Result<std::unique_ptr<ByteSource>> open_file_source(const std::filesystem::path& path);
/// Wraps memory that outlives the source.
std::unique_ptr<ByteSource> memory_source(std::string name, std::span<const std::uint8_t> bytes);

/// Sequential buffered reading from a position of a ByteSource: lines for text formats and
/// exact byte runs for binary bodies. Memory: one buffer of `buffer_size` bytes.
class SequentialReader {
 public:
  SequentialReader(ByteSource& source, std::uint64_t start, std::size_t buffer_size = 1 << 20);

  /// The next line without its "\n" or "\r\n" (valid until the next call); false at the end.
  /// Errors: CorruptData when a line is longer than the buffer (no newline in 1 MiB).
  kernel::Result<bool> next_line(std::string_view& line);
  /// Reads exactly out.size() bytes. Errors: CorruptData at the end of the data, IoError.
  kernel::Status read_exact(std::span<std::uint8_t> out);
  /// Skips `count` bytes. Errors: CorruptData when fewer remain.
  kernel::Status skip(std::uint64_t count);
  /// Bytes read: read_exact / next_line (with its newline) moves it.
  std::uint64_t position() const { return position_; }
  /// 1-based number of the last line returned.
  std::uint64_t line_number() const { return line_number_; }
  std::uint64_t remaining() const { return source_.size() - position_; }

 private:
  kernel::Status fill();

  ByteSource& source_;
  std::vector<std::uint8_t> buffer_;
  std::size_t begin_ = 0, end_ = 0;  // valid bytes of buffer_
  std::uint64_t file_position_;      // file offset of buffer_[end_]
  std::uint64_t position_;           // file offset of buffer_[begin_]
  std::uint64_t line_number_ = 0;
};

}  // namespace csgtile::geo::detail
