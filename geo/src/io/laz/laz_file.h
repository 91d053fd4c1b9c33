#pragma once
// LAZ (LASzip-compressed LAS) at the file level: the "laszip encoded" VLR that says how the
// point records were compressed, the chunk table that says where each independently decodable
// chunk lies, and the decoder of one chunk into uncompressed point records (byte for byte the
// records of the LAS file the LAZ was made from). Private to geo.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "csgtile/kernel/result.h"
#include "io/laz/items.h"

namespace csgtile::geo {
class ByteSource;
namespace detail {
using ByteSource = geo::ByteSource;
}  // namespace detail
}  // namespace csgtile::geo

namespace csgtile::geo::detail::laz {

inline constexpr std::uint16_t kCompressorPointwise = 1;
inline constexpr std::uint16_t kCompressorPointwiseChunked = 2;
inline constexpr std::uint16_t kCompressorLayeredChunked = 3;
inline constexpr std::uint32_t kVariableChunkSize = 0xFFFFFFFFu;

/// The laszip VLR (user id "laszip encoded", record 22204).
struct LazSpec {
  std::uint16_t compressor = 0;
  std::uint16_t coder = 0;
  std::uint8_t version_major = 0, version_minor = 0;
  std::uint16_t version_revision = 0;
  std::uint32_t options = 0;
  std::uint32_t chunk_size = 0;
  std::vector<Item> items;

  bool layered() const { return compressor == kCompressorLayeredChunked; }
  bool chunked() const { return compressor != kCompressorPointwise; }
  bool variable_chunks() const { return chunk_size == kVariableChunkSize; }
  /// "compressor 2 (point-wise, chunked), LASzip 3.4r3, chunks of 50000 points".
  std::string describe() const;
};

/// Parses the VLR payload and checks it against the header: a known compressor and coder,
/// items the compressor defines, item sizes adding up to the record length, and the items a
/// point format needs. Errors: CorruptData or Unsupported, with the file's name.
kernel::Result<LazSpec> parse_laszip_vlr(std::span<const std::uint8_t> payload, int point_format,
                                         std::size_t record_length, const std::string& name);

/// One independently decodable run of points.
struct Chunk {
  std::uint64_t offset = 0;  ///< file offset of its first byte
  std::uint64_t bytes = 0;
  std::uint64_t first_point = 0;
  std::uint64_t points = 0;
};

/// The chunks of the point data [data_begin, data_end) holding `point_count` points: one
/// chunk for compressor 1, else as the chunk table says (checked against the data area and
/// the point count). Errors: CorruptData naming the file and what is wrong.
kernel::Result<std::vector<Chunk>> read_chunks(ByteSource& source, const LazSpec& spec,
                                               std::uint64_t data_begin, std::uint64_t data_end,
                                               std::uint64_t point_count);

/// Decodes the records of one chunk, in runs: begin() on the chunk's bytes, then decode()
/// until its points are done. `layers` (LayerMask) are the layers of formats 6-10 to decode;
/// the attributes of skipped layers keep the chunk's first point's values.
class ChunkDecoder {
 public:
  ChunkDecoder(const LazSpec& spec, std::size_t record_length, std::uint32_t layers);
  ~ChunkDecoder();
  ChunkDecoder(const ChunkDecoder&) = delete;
  ChunkDecoder& operator=(const ChunkDecoder&) = delete;

  /// Starts a chunk of `points` points on `in` (kept until the chunk is done).
  void begin(ByteStream* in, std::uint64_t points);
  /// Decodes the next n records (n ≤ left()) into out (n × record_length bytes). Errors:
  /// CorruptData when the stream ran past the chunk's bytes or the layered chunk's own point
  /// count disagrees with the chunk table (`where` names the chunk), IoError.
  kernel::Status decode(std::size_t n, std::uint8_t* out, const std::string& where);
  std::uint64_t left() const { return left_; }

 private:
  kernel::Status check(const std::string& where) const;

  const LazSpec& spec_;
  std::size_t record_length_;
  std::uint32_t layers_;
  ByteStream* in_ = nullptr;
  std::uint64_t left_ = 0;
  bool started_ = false;
  std::uint32_t layered_count_ = 0;
  ArithmeticDecoder dec_;
  std::vector<std::unique_ptr<PointwiseItemDecoder>> pointwise_;
  std::vector<std::unique_ptr<LayeredItemDecoder>> layered_;
};

}  // namespace csgtile::geo::detail::laz
