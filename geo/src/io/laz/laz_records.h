#pragma once
// The uncompressed point records of a LAZ file, served in file order or from any point on.
// Chunks are decoded whole into a small window, several at once on the TBB pool (each chunk
// is independent, so the bytes are the same whatever the thread count); the one un-chunked
// compressor, and chunks too large to hold, are decoded as a stream. Memory: the window, a
// few chunks, never the file. Private to geo.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "csgtile/kernel/result.h"
#include "io/laz/laz_file.h"

namespace csgtile::geo::detail::laz {

class LazRecords {
 public:
  /// `source` outlives this; `spec` and `chunks` as parse_laszip_vlr / read_chunks made them.
  LazRecords(ByteSource& source, LazSpec spec, std::vector<Chunk> chunks, std::size_t record_length,
             std::uint32_t layers);
  ~LazRecords();

  /// Copies records [first, first + n) into out (n × record_length bytes). Errors: CorruptData
  /// or IoError naming the file and the chunk.
  kernel::Status read(std::uint64_t first, std::size_t n, std::uint8_t* out);

  const LazSpec& spec() const { return spec_; }
  const std::vector<Chunk>& chunks() const { return chunks_; }

 private:
  struct Decoded {
    std::size_t chunk = 0;
    std::vector<std::uint8_t> records;
  };
  struct Stream;

  std::size_t chunk_of(std::uint64_t point) const;
  std::string where(std::size_t chunk) const;
  bool streamed(std::size_t chunk) const;
  kernel::Status decode_window(std::size_t from);
  kernel::Status read_streamed(std::size_t chunk, std::uint64_t first, std::size_t n,
                               std::uint8_t* out);

  ByteSource& source_;
  LazSpec spec_;
  std::vector<Chunk> chunks_;
  std::size_t record_length_;
  std::uint32_t layers_;
  std::vector<Decoded> window_;
  std::unique_ptr<Stream> stream_;
};

}  // namespace csgtile::geo::detail::laz
