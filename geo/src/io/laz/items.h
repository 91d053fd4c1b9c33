#pragma once
// Decoders of the LASzip items: the runs of bytes a point record is cut into (POINT10,
// GPSTIME11, RGB12, WAVEPACKET13 and extra BYTEs for point formats 0-5; POINT14, RGB14,
// RGBNIR14, WAVEPACKET14 and BYTE14 for 6-10). Each decoder turns the compressed stream back
// into its item's bytes exactly as the uncompressed LAS record holds them. State lives for one
// chunk: a decoder is made fresh for every chunk. Private to geo.

#include <cstdint>
#include <memory>
#include <string>

#include "io/laz/arithmetic.h"

namespace csgtile::geo::detail::laz {

enum class ItemType : std::uint16_t {
  Byte = 0,
  Point10 = 6,
  GpsTime11 = 7,
  Rgb12 = 8,
  WavePacket13 = 9,
  Point14 = 10,
  Rgb14 = 11,
  RgbNir14 = 12,
  WavePacket14 = 13,
  Byte14 = 14,
};

struct Item {
  ItemType type = ItemType::Byte;
  std::uint16_t size = 0;
  std::uint16_t version = 0;
};

/// "POINT10 v2 (20 bytes)".
std::string item_label(const Item& item);

/// Layers of the layered (point formats 6-10) compressor a caller may leave undecoded. XY,
/// return numbers, scanner channel and classification are always decoded.
enum LayerMask : std::uint32_t {
  LayerZ = 1u << 0,
  LayerFlags = 1u << 1,  // classification flags, scan direction, edge of flight line
  LayerIntensity = 1u << 2,
  LayerScanAngle = 1u << 3,
  LayerUserData = 1u << 4,
  LayerPointSource = 1u << 5,
  LayerGpsTime = 1u << 6,
  LayerRgb = 1u << 7,
  LayerNir = 1u << 8,
  LayerWavePacket = 1u << 9,
  LayerExtraBytes = 1u << 10,
  AllLayers = (1u << 11) - 1,
};

/// An item of the point-wise compressors (1 and 2): one arithmetic stream for all items.
class PointwiseItemDecoder {
 public:
  virtual ~PointwiseItemDecoder() = default;
  /// The chunk's first point, stored raw.
  virtual void first(const std::uint8_t* raw) = 0;
  /// Decodes the next point's item into `out` (item.size bytes).
  virtual void next(ArithmeticDecoder& dec, std::uint8_t* out) = 0;
};

/// An item of the layered compressor (3): each of its layers has a stream of its own.
class LayeredItemDecoder {
 public:
  virtual ~LayeredItemDecoder() = default;
  /// Reads the byte count of each of its layers (after the chunk's point count).
  virtual void read_sizes(ByteStream& chunk) = 0;
  /// Takes its layers' bytes from `chunk` (skipping the layers not in `layers`) and starts
  /// from the chunk's first point `raw`; `context` is the scanner channel (set by POINT14).
  virtual void start(ByteStream& chunk, const std::uint8_t* raw, std::uint32_t& context,
                     std::uint32_t layers) = 0;
  /// Decodes the next point's item into `out`.
  virtual void next(std::uint8_t* out, std::uint32_t& context) = 0;
  /// Bytes read past the end of its layers.
  virtual std::uint64_t overrun() const = 0;
};

/// Null for an item type / version the point-wise compressors do not define.
std::unique_ptr<PointwiseItemDecoder> make_pointwise_decoder(const Item& item);
/// Null for an item type / version the layered compressor does not define.
std::unique_ptr<LayeredItemDecoder> make_layered_decoder(const Item& item);

}  // namespace csgtile::geo::detail::laz
