#include "io/laz/laz_records.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>

#include "io/byte_source.h"

namespace csgtile::geo::detail::laz {

namespace {
// A chunk whose records exceed this is decoded as a stream rather than held whole.
constexpr std::uint64_t kMaxHeldBytes = 64u << 20;
// Chunks decoded together, at most.
constexpr std::size_t kMaxWindow = 8;

std::string num(std::uint64_t v) { return std::to_string(v); }
}  // namespace

struct LazRecords::Stream {
  std::size_t chunk = 0;
  std::uint64_t next = 0;  // file index of the next point the decoder gives
  std::unique_ptr<ByteStream> bytes;
  std::unique_ptr<ChunkDecoder> decoder;
  std::vector<std::uint8_t> scratch;
};

LazRecords::LazRecords(ByteSource& source, LazSpec spec, std::vector<Chunk> chunks,
                       std::size_t record_length, std::uint32_t layers)
    : source_(source),
      spec_(std::move(spec)),
      chunks_(std::move(chunks)),
      record_length_(record_length),
      layers_(layers) {}

LazRecords::~LazRecords() = default;

std::size_t LazRecords::chunk_of(std::uint64_t point) const {
  auto it = std::upper_bound(chunks_.begin(), chunks_.end(), point,
                             [](std::uint64_t p, const Chunk& c) { return p < c.first_point; });
  return static_cast<std::size_t>(it - chunks_.begin()) - 1;
}

std::string LazRecords::where(std::size_t i) const {
  const Chunk& c = chunks_[i];
  return source_.name() + ": LAZ chunk " + num(i + 1) + " of " + num(chunks_.size()) + " (points " +
         num(c.first_point) + "-" + num(c.first_point + c.points - 1) + ", " + num(c.bytes) +
         " bytes at byte " + num(c.offset) + ")";
}

bool LazRecords::streamed(std::size_t i) const {
  return !spec_.chunked() || chunks_[i].points * record_length_ > kMaxHeldBytes;
}

kernel::Status LazRecords::decode_window(std::size_t from) {
  const auto threads =
      static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  const std::size_t width = std::min(kMaxWindow, threads);
  std::size_t to = from;
  while (to < chunks_.size() && to - from < width && !streamed(to)) ++to;
  // Bytes are read here, in order; the chunks are then decoded in parallel.
  std::vector<std::vector<std::uint8_t>> bytes(to - from);
  for (std::size_t i = from; i < to; ++i) {
    bytes[i - from].resize(static_cast<std::size_t>(chunks_[i].bytes));
    if (auto st = source_.read_at(chunks_[i].offset, bytes[i - from]); !st.ok()) return st;
  }
  window_.assign(to - from, {});
  std::vector<kernel::Status> status(to - from);
  tbb::parallel_for(std::size_t{0}, to - from, [&](std::size_t k) {
    const std::size_t i = from + k;
    Decoded& d = window_[k];
    d.chunk = i;
    d.records.resize(static_cast<std::size_t>(chunks_[i].points * record_length_));
    ByteStream in(bytes[k]);
    ChunkDecoder decoder(spec_, record_length_, layers_);
    decoder.begin(&in, chunks_[i].points);
    status[k] =
        decoder.decode(static_cast<std::size_t>(chunks_[i].points), d.records.data(), where(i));
  });
  for (std::size_t k = 0; k < status.size(); ++k) {
    if (!status[k].ok()) {
      window_.clear();
      return status[k];
    }
  }
  return {};
}

kernel::Status LazRecords::read_streamed(std::size_t i, std::uint64_t first, std::size_t n,
                                         std::uint8_t* out) {
  const Chunk& c = chunks_[i];
  if (!stream_ || stream_->chunk != i || stream_->next > first) {
    stream_ = std::make_unique<Stream>();
    stream_->chunk = i;
    stream_->next = c.first_point;
    stream_->bytes = std::make_unique<ByteStream>(source_, c.offset, c.bytes);
    stream_->decoder = std::make_unique<ChunkDecoder>(spec_, record_length_, layers_);
    stream_->decoder->begin(stream_->bytes.get(), c.points);
  }
  Stream& s = *stream_;
  while (s.next < first) {  // skip to `first` (a seek inside the chunk)
    const std::size_t k = static_cast<std::size_t>(std::min<std::uint64_t>(first - s.next, 4096));
    s.scratch.resize(k * record_length_);
    if (auto st = s.decoder->decode(k, s.scratch.data(), where(i)); !st.ok()) {
      stream_.reset();
      return st;
    }
    s.next += k;
  }
  if (auto st = s.decoder->decode(n, out, where(i)); !st.ok()) {
    stream_.reset();
    return st;
  }
  s.next += n;
  return {};
}

kernel::Status LazRecords::read(std::uint64_t first, std::size_t n, std::uint8_t* out) {
  while (n > 0) {
    const std::size_t i = chunk_of(first);
    const Chunk& c = chunks_[i];
    const std::size_t k =
        static_cast<std::size_t>(std::min<std::uint64_t>(n, c.first_point + c.points - first));
    if (streamed(i)) {
      if (auto st = read_streamed(i, first, k, out); !st.ok()) return st;
    } else {
      auto held = std::find_if(window_.begin(), window_.end(),
                               [&](const Decoded& d) { return d.chunk == i; });
      if (held == window_.end()) {
        if (auto st = decode_window(i); !st.ok()) return st;
        held = window_.begin();
      }
      std::memcpy(out, held->records.data() + (first - c.first_point) * record_length_,
                  k * record_length_);
    }
    first += k;
    out += k * record_length_;
    n -= k;
  }
  return {};
}

}  // namespace csgtile::geo::detail::laz
