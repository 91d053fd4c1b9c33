#include "io/laz/laz_file.h"

#include <algorithm>
#include <array>

#include "io/byte_source.h"
#include "io/endian.h"

namespace csgtile::geo::detail::laz {

namespace {

using kernel::Error;
using kernel::ErrorCode;

std::string num(std::uint64_t v) { return std::to_string(v); }

Error corrupt(const std::string& name, const std::string& what) {
  return Error{ErrorCode::CorruptData, name + ": " + what};
}

const char* type_name(ItemType t) {
  switch (t) {
    case ItemType::Byte:
      return "BYTE";
    case ItemType::Point10:
      return "POINT10";
    case ItemType::GpsTime11:
      return "GPSTIME11";
    case ItemType::Rgb12:
      return "RGB12";
    case ItemType::WavePacket13:
      return "WAVEPACKET13";
    case ItemType::Point14:
      return "POINT14";
    case ItemType::Rgb14:
      return "RGB14";
    case ItemType::RgbNir14:
      return "RGBNIR14";
    case ItemType::WavePacket14:
      return "WAVEPACKET14";
    case ItemType::Byte14:
      return "BYTE14";
  }
  return "?";
}

// The items each point format is made of, before any extra bytes.
std::vector<ItemType> format_items(int format) {
  using T = ItemType;
  switch (format) {
    case 0:
      return {T::Point10};
    case 1:
      return {T::Point10, T::GpsTime11};
    case 2:
      return {T::Point10, T::Rgb12};
    case 3:
      return {T::Point10, T::GpsTime11, T::Rgb12};
    case 4:
      return {T::Point10, T::GpsTime11, T::WavePacket13};
    case 5:
      return {T::Point10, T::GpsTime11, T::Rgb12, T::WavePacket13};
    case 6:
      return {T::Point14};
    case 7:
      return {T::Point14, T::Rgb14};
    case 8:
      return {T::Point14, T::RgbNir14};
    case 9:
      return {T::Point14, T::WavePacket14};
    case 10:
      return {T::Point14, T::RgbNir14, T::WavePacket14};
    default:
      return {};
  }
}

const char* compressor_name(std::uint16_t c) {
  switch (c) {
    case 0:
      return "none";
    case kCompressorPointwise:
      return "point-wise";
    case kCompressorPointwiseChunked:
      return "point-wise, chunked";
    case kCompressorLayeredChunked:
      return "layered, chunked";
    default:
      return "unknown";
  }
}

}  // namespace

std::string item_label(const Item& item) {
  return std::string(type_name(item.type)) + " v" + num(item.version) + " (" + num(item.size) +
         " bytes)";
}

std::string LazSpec::describe() const {
  std::string s = "compressor " + num(compressor) + " (" + compressor_name(compressor) +
                  "), LASzip " + num(version_major) + "." + num(version_minor) + "r" +
                  num(version_revision);
  if (chunked()) {
    s += variable_chunks() ? ", chunks of variable size"
                           : ", chunks of " + num(chunk_size) + " points";
  }
  return s;
}

kernel::Result<LazSpec> parse_laszip_vlr(std::span<const std::uint8_t> p, int point_format,
                                         std::size_t record_length, const std::string& name) {
  const std::string what = "laszip VLR (\"laszip encoded\", 22204)";
  if (p.size() < 34) {
    return corrupt(name, what + " has " + num(p.size()) + " bytes; it needs at least 34");
  }
  LazSpec s;
  s.compressor = load_le<std::uint16_t>(p.data());
  s.coder = load_le<std::uint16_t>(p.data() + 2);
  s.version_major = p[4];
  s.version_minor = p[5];
  s.version_revision = load_le<std::uint16_t>(p.data() + 6);
  s.options = load_le<std::uint32_t>(p.data() + 8);
  s.chunk_size = load_le<std::uint32_t>(p.data() + 12);
  const std::uint16_t item_count = load_le<std::uint16_t>(p.data() + 32);
  if (p.size() < 34 + 6u * item_count) {
    return corrupt(name, what + " lists " + num(item_count) + " items (" +
                             num(34 + 6u * item_count) + " bytes) in " + num(p.size()) + " bytes");
  }
  if (s.compressor < kCompressorPointwise || s.compressor > kCompressorLayeredChunked) {
    return Error{ErrorCode::Unsupported,
                 name + ": " + what + ": compressor " + num(s.compressor) +
                     " is not one of LASzip's (1 point-wise, 2 point-wise chunked, 3 layered)"};
  }
  if (s.coder != 0) {
    return Error{ErrorCode::Unsupported, name + ": " + what + ": coder " + num(s.coder) +
                                             " is not the arithmetic coder (0)"};
  }
  if (s.chunked() && s.chunk_size == 0) {
    return corrupt(name, what + ": chunk size 0");
  }
  std::size_t total = 0;
  std::vector<ItemType> main;
  for (std::uint16_t i = 0; i < item_count; ++i) {
    const std::uint8_t* e = p.data() + 34 + 6 * i;
    Item item;
    item.type = static_cast<ItemType>(load_le<std::uint16_t>(e));
    item.size = load_le<std::uint16_t>(e + 2);
    item.version = load_le<std::uint16_t>(e + 4);
    const std::string label =
        "item " + num(i + 1) + " of " + num(item_count) + ", " +
        (std::string(type_name(item.type)) == "?" ? "type " + num(static_cast<unsigned>(item.type))
                                                  : item_label(item));
    const bool known = s.layered() ? make_layered_decoder(item) != nullptr
                                   : make_pointwise_decoder(item) != nullptr;
    if (!known) {
      return Error{ErrorCode::Unsupported, name + ": " + what + ": " + label + " is not an item " +
                                               compressor_name(s.compressor) +
                                               " compression defines"};
    }
    if (item.type != ItemType::Byte && item.type != ItemType::Byte14) main.push_back(item.type);
    total += item.size;
    s.items.push_back(item);
  }
  if (main != format_items(point_format)) {
    std::string have;
    for (const auto t : main) have += std::string(have.empty() ? "" : ", ") + type_name(t);
    std::string want;
    for (const auto t : format_items(point_format)) {
      want += std::string(want.empty() ? "" : ", ") + type_name(t);
    }
    return corrupt(name, what + ": its items (" + have + ") are not those of point format " +
                             num(static_cast<std::uint64_t>(point_format)) + " (" + want + ")");
  }
  if (total != record_length) {
    return corrupt(name, what + ": its items add up to " + num(total) +
                             " bytes, but the header's point record length is " +
                             num(record_length));
  }
  return s;
}

kernel::Result<std::vector<Chunk>> read_chunks(ByteSource& src, const LazSpec& spec,
                                               std::uint64_t data_begin, std::uint64_t data_end,
                                               std::uint64_t point_count) {
  const std::string& name = src.name();
  std::vector<Chunk> chunks;
  if (!spec.chunked()) {
    if (point_count > 0) chunks.push_back({data_begin, data_end - data_begin, 0, point_count});
    return chunks;
  }
  if (data_end < data_begin + 8) {
    return corrupt(name, "LAZ point data (bytes " + num(data_begin) + "-" + num(data_end) +
                             ") is too short for the chunk table's 8-byte offset");
  }
  std::array<std::uint8_t, 8> head{};
  if (auto st = src.read_at(data_begin, head); !st.ok()) return st.error();
  std::int64_t table = load_le<std::int64_t>(head.data());
  const std::uint64_t chunks_start = data_begin + 8;
  if (table == -1) {  // streamed writers put the table's offset at the end of the file
    if (src.size() < 8) return corrupt(name, "LAZ chunk table offset missing at the end");
    if (auto st = src.read_at(src.size() - 8, head); !st.ok()) return st.error();
    table = load_le<std::int64_t>(head.data());
  }
  if (static_cast<std::uint64_t>(table) == data_begin) {
    return corrupt(name,
                   "LAZ chunk table was never written (the compressor was interrupted): "
                   "its offset points at itself");
  }
  if (table < 0 || static_cast<std::uint64_t>(table) < chunks_start ||
      static_cast<std::uint64_t>(table) + 8 > data_end) {
    return corrupt(name, "LAZ chunk table offset " + std::to_string(table) +
                             " lies outside the point data (bytes " + num(chunks_start) + "-" +
                             num(data_end) + "): the file is truncated or the offset is wrong");
  }
  const auto table_at = static_cast<std::uint64_t>(table);
  if (auto st = src.read_at(table_at, head); !st.ok()) return st.error();
  const std::uint32_t version = load_le<std::uint32_t>(head.data());
  const std::uint32_t count = load_le<std::uint32_t>(head.data() + 4);
  const std::string where = "LAZ chunk table at byte " + num(table_at);
  if (version != 0) return corrupt(name, where + ": version " + num(version) + " (not 0)");
  const std::uint64_t area = table_at - chunks_start;
  if (count > area || count > std::max<std::uint64_t>(point_count, 1) ||
      (count == 0 && point_count > 0)) {
    return corrupt(name, where + ": " + num(count) + " chunks for " + num(point_count) +
                             " points in " + num(area) + " bytes");
  }
  if (count == 0) return chunks;
  ByteStream in(src, table_at + 8, data_end - table_at - 8, 1 << 16);
  ArithmeticDecoder dec(&in);
  IntegerDecoder ic(32, 2);
  chunks.resize(count);
  std::uint32_t last_points = 0, last_bytes = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (spec.variable_chunks()) {
      last_points =
          static_cast<std::uint32_t>(ic.decode(dec, static_cast<std::int32_t>(last_points), 0));
      chunks[i].points = last_points;
    }
    last_bytes =
        static_cast<std::uint32_t>(ic.decode(dec, static_cast<std::int32_t>(last_bytes), 1));
    chunks[i].bytes = last_bytes;
  }
  if (!in.io_status().ok()) return in.io_status().error();
  if (in.overrun() > 0) {
    return corrupt(name,
                   where + ": its " + num(count) + " entries run past the end of the point data");
  }
  std::uint64_t at = chunks_start, first = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    Chunk& c = chunks[i];
    if (!spec.variable_chunks()) {
      c.points =
          std::min<std::uint64_t>(spec.chunk_size, point_count - std::min(point_count, first));
    }
    const std::string label = where + ", chunk " + num(i + 1) + " of " + num(count);
    if (c.bytes == 0 || c.points == 0) {
      return corrupt(name, label + ": " + num(c.points) + " points in " + num(c.bytes) + " bytes");
    }
    if (c.bytes > table_at - at) {
      return corrupt(name, label + ": " + num(c.bytes) + " bytes from byte " + num(at) +
                               " pass the chunk table");
    }
    c.offset = at;
    c.first_point = first;
    at += c.bytes;
    first += c.points;
  }
  if (first != point_count) {
    return corrupt(name, where + ": its " + num(count) + " chunks hold " + num(first) +
                             " points, the header " + num(point_count));
  }
  return chunks;
}

ChunkDecoder::ChunkDecoder(const LazSpec& spec, std::size_t record_length, std::uint32_t layers)
    : spec_(spec), record_length_(record_length), layers_(layers) {}

ChunkDecoder::~ChunkDecoder() = default;

void ChunkDecoder::begin(ByteStream* in, std::uint64_t points) {
  in_ = in;
  left_ = points;
  started_ = false;
  pointwise_.clear();
  layered_.clear();
  // Fresh item decoders: every chunk starts from new models.
  for (const Item& item : spec_.items) {
    if (spec_.layered()) {
      layered_.push_back(make_layered_decoder(item));
    } else {
      pointwise_.push_back(make_pointwise_decoder(item));
    }
  }
}

kernel::Status ChunkDecoder::check(const std::string& where) const {
  if (!in_->io_status().ok()) return in_->io_status();
  std::uint64_t overrun = in_->overrun();
  for (const auto& d : layered_) overrun += d->overrun();
  if (overrun > 0) {
    return {kernel::ErrorCode::CorruptData,
            where + ": the compressed stream runs " + num(overrun) +
                " bytes past the end of the chunk (corrupt or truncated data)"};
  }
  return {};
}

kernel::Status ChunkDecoder::decode(std::size_t n, std::uint8_t* out, const std::string& where) {
  n = static_cast<std::size_t>(std::min<std::uint64_t>(n, left_));
  std::size_t done = 0;
  if (n > 0 && !started_) {
    // The first point is stored raw; the decoders start from it.
    in_->get(out, record_length_);
    std::uint32_t context = 0;
    if (spec_.layered()) {
      layered_count_ = in_->get_u32();
      for (auto& d : layered_) d->read_sizes(*in_);
      std::size_t at = 0;
      for (std::size_t i = 0; i < layered_.size(); ++i) {
        layered_[i]->start(*in_, out + at, context, layers_);
        at += spec_.items[i].size;
      }
      if (layered_count_ != left_) {
        return {kernel::ErrorCode::CorruptData, where + ": the chunk says it holds " +
                                                    num(layered_count_) +
                                                    " points, the chunk table " + num(left_)};
      }
    } else {
      std::size_t at = 0;
      for (std::size_t i = 0; i < pointwise_.size(); ++i) {
        pointwise_[i]->first(out + at);
        at += spec_.items[i].size;
      }
      dec_.start(in_);
    }
    started_ = true;
    done = 1;
  }
  for (; done < n; ++done) {
    std::uint8_t* rec = out + done * record_length_;
    std::size_t at = 0;
    if (spec_.layered()) {
      std::uint32_t context = 0;  // set by POINT14 for the items after it
      for (std::size_t i = 0; i < layered_.size(); ++i) {
        layered_[i]->next(rec + at, context);
        at += spec_.items[i].size;
      }
    } else {
      for (std::size_t i = 0; i < pointwise_.size(); ++i) {
        pointwise_[i]->next(dec_, rec + at);
        at += spec_.items[i].size;
      }
    }
  }
  left_ -= n;
  return check(where);
}

}  // namespace csgtile::geo::detail::laz
