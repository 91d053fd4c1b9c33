// Items of the layered compressor (point formats 6-10): POINT14, RGB14, RGBNIR14,
// WAVEPACKET14 and BYTE14, versions 3 and 4 (2 is an alias of 3). Each attribute group is a
// layer with its own arithmetic stream, so a reader can skip the layers it does not need.
// Every item keeps a context per scanner channel, started from the previous channel's point
// when a channel first appears in the chunk. Version 3 hands the channel to the other items
// only on points where it changes (0 otherwise) and, after a switch to a channel seen before,
// predicts from the previous channel's last values; version 4 fixed both, and both are kept
// as written because files were encoded that way.

#include <array>
#include <cstring>
#include <vector>

#include "io/endian.h"
#include "io/laz/items.h"
#include "io/laz/tables.h"

namespace csgtile::geo::detail::laz {

namespace {

using detail::load_le;
using detail::store_le;

// One layer: its bytes, its stream and its decoder. `active` when requested and non-empty.
// The decoder always reads from the layer's own stream, even when the layer is inactive (an
// empty stream then): a layer a file claims empty but must decode (the xy layer of a chunk of
// several points) reads past its end and fails the chunk, never a null stream.
struct Layer {
  std::uint32_t size = 0;
  ByteStream stream;
  ArithmeticDecoder dec;
  bool active = false;

  void take(ByteStream& chunk, bool requested) {
    active = requested && size > 0;
    if (active) {
      stream = chunk.take(size);
      dec.start(&stream);
    } else {
      if (size > 0) (void)chunk.take(size);
      stream = ByteStream();
      dec.start(&stream, /*read_start=*/false);
    }
  }
};

// The fields of a point record of formats 6-10 (30 bytes).
struct Point14 {
  std::int32_t x = 0, y = 0, z = 0;
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 0, number_of_returns = 0;
  std::uint8_t class_flags = 0, channel = 0, scan_direction = 0, edge = 0;
  std::uint8_t classification = 0, user_data = 0;
  std::int16_t scan_angle = 0;
  std::uint16_t point_source = 0;
  std::uint64_t gps = 0;
  bool gps_changed = false;

  static Point14 read(const std::uint8_t* p) {
    Point14 q;
    q.x = load_le<std::int32_t>(p);
    q.y = load_le<std::int32_t>(p + 4);
    q.z = load_le<std::int32_t>(p + 8);
    q.intensity = load_le<std::uint16_t>(p + 12);
    q.return_number = p[14] & 15;
    q.number_of_returns = p[14] >> 4;
    q.class_flags = p[15] & 15;
    q.channel = (p[15] >> 4) & 3;
    q.scan_direction = (p[15] >> 6) & 1;
    q.edge = p[15] >> 7;
    q.classification = p[16];
    q.user_data = p[17];
    q.scan_angle = load_le<std::int16_t>(p + 18);
    q.point_source = load_le<std::uint16_t>(p + 20);
    q.gps = load_le<std::uint64_t>(p + 22);
    return q;
  }
  void write(std::uint8_t* p) const {
    store_le<std::int32_t>(p, x);
    store_le<std::int32_t>(p + 4, y);
    store_le<std::int32_t>(p + 8, z);
    store_le<std::uint16_t>(p + 12, intensity);
    p[14] = static_cast<std::uint8_t>(return_number | (number_of_returns << 4));
    p[15] = static_cast<std::uint8_t>(class_flags | (channel << 4) | (scan_direction << 6) |
                                      (edge << 7));
    p[16] = classification;
    p[17] = user_data;
    store_le<std::int16_t>(p + 18, scan_angle);
    store_le<std::uint16_t>(p + 20, point_source);
    store_le<std::uint64_t>(p + 22, gps);
  }
};

// ---------------------------------------------------------------- POINT14 (30 bytes)

class Point14V3 final : public LayeredItemDecoder {
 public:
  explicit Point14V3(bool v4) : v4_(v4) {}

  void read_sizes(ByteStream& chunk) override {
    for (auto& layer : layers_) layer.size = chunk.get_u32();
  }

  void start(ByteStream& chunk, const std::uint8_t* raw, std::uint32_t& context,
             std::uint32_t requested) override {
    xy().take(chunk, true);
    layers_[1].take(chunk, (requested & LayerZ) != 0);
    layers_[2].take(chunk, true);  // classification
    layers_[3].take(chunk, (requested & LayerFlags) != 0);
    layers_[4].take(chunk, (requested & LayerIntensity) != 0);
    layers_[5].take(chunk, (requested & LayerScanAngle) != 0);
    layers_[6].take(chunk, (requested & LayerUserData) != 0);
    layers_[7].take(chunk, (requested & LayerPointSource) != 0);
    layers_[8].take(chunk, (requested & LayerGpsTime) != 0);
    const Point14 first = Point14::read(raw);
    current_ = first.channel;
    context = current_;
    create(current_, first);
  }

  void next(std::uint8_t* out, std::uint32_t& context) override {
    Context* c = contexts_[current_].get();
    const std::uint32_t lpr = (c->last.return_number == 1 ? 1u : 0u) +
                              (c->last.return_number >= c->last.number_of_returns ? 2u : 0u) +
                              (c->last.gps_changed ? 4u : 0u);
    ArithmeticDecoder& dec = xy().dec;
    const std::uint32_t changed = dec.decode_symbol(c->changed[lpr]);
    if (changed & 64) {
      const std::uint32_t diff = dec.decode_symbol(c->scanner_channel);
      const std::uint32_t channel = (current_ + diff + 1) % 4;
      if (!contexts_[channel]) create(channel, c->last);
      current_ = channel;
      if (!v4_) context = current_;
      c = contexts_[current_].get();
      c->last.channel = static_cast<std::uint8_t>(channel);
    }
    if (v4_) context = current_;
    Point14& p = c->last;
    const bool source_changed = (changed & 32) != 0;
    const bool gps_changed = (changed & 16) != 0;
    const bool angle_changed = (changed & 8) != 0;
    std::uint32_t n = p.number_of_returns;
    std::uint32_t r = p.return_number;
    if (changed & 4) {
      n = dec.decode_symbol(lazy_model<16>(c->number_of_returns[n]));
      p.number_of_returns = static_cast<std::uint8_t>(n);
    }
    switch (changed & 3) {
      case 0:
        break;
      case 1:
        r = (r + 1) % 16;
        break;
      case 2:
        r = (r + 15) % 16;
        break;
      default:
        if (gps_changed) {
          r = dec.decode_symbol(lazy_model<16>(c->return_number[r]));
        } else {
          r = (r + dec.decode_symbol(c->return_number_gps_same) + 2) % 16;
        }
        break;
    }
    p.return_number = static_cast<std::uint8_t>(r);
    const std::uint32_t m = kNumberReturnMap6[n][r];
    const std::uint32_t l = number_return_level8(n, r);
    const std::uint32_t cpr = (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u);
    const std::uint32_t single = n == 1;
    const std::uint32_t xy_ctx = (m << 1) | (gps_changed ? 1u : 0u);

    std::int32_t diff = c->dx.decode(dec, c->median_x[xy_ctx].get(), single);
    p.x = wrap_add(p.x, diff);
    c->median_x[xy_ctx].add(diff);
    std::uint32_t k = c->dx.k();
    diff = c->dy.decode(dec, c->median_y[xy_ctx].get(), single + (k < 20 ? (k & ~1u) : 20));
    p.y = wrap_add(p.y, diff);
    c->median_y[xy_ctx].add(diff);
    if (layers_[1].active) {
      k = (c->dx.k() + c->dy.k()) / 2;
      p.z = c->z.decode(layers_[1].dec, c->last_z[l], single + (k < 18 ? (k & ~1u) : 18));
      c->last_z[l] = p.z;
    }
    if (layers_[2].active) {
      const std::uint32_t ccc = ((p.classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
      p.classification = static_cast<std::uint8_t>(
          layers_[2].dec.decode_symbol(lazy_model<256>(c->classification[ccc])));
    }
    if (layers_[3].active) {
      const std::uint32_t last_flags = (p.edge << 5) | (p.scan_direction << 4) | p.class_flags;
      const std::uint32_t flags =
          layers_[3].dec.decode_symbol(lazy_model<64>(c->flags[last_flags]));
      p.edge = (flags >> 5) & 1;
      p.scan_direction = (flags >> 4) & 1;
      p.class_flags = flags & 0x0F;
    }
    if (layers_[4].active) {
      const std::uint32_t ictx = (cpr << 1) | (gps_changed ? 1u : 0u);
      p.intensity = static_cast<std::uint16_t>(
          c->intensity.decode(layers_[4].dec, c->last_intensity[ictx], cpr));
      c->last_intensity[ictx] = p.intensity;
    }
    if (layers_[5].active && angle_changed) {
      p.scan_angle = static_cast<std::int16_t>(
          c->scan_angle.decode(layers_[5].dec, p.scan_angle, gps_changed ? 1u : 0u));
    }
    if (layers_[6].active) {
      p.user_data = static_cast<std::uint8_t>(
          layers_[6].dec.decode_symbol(lazy_model<256>(c->user_data[p.user_data / 4])));
    }
    if (layers_[7].active && source_changed) {
      p.point_source =
          static_cast<std::uint16_t>(c->point_source.decode(layers_[7].dec, p.point_source));
    }
    if (layers_[8].active && gps_changed) p.gps = c->gps.decode(layers_[8].dec);
    p.write(out);
    p.gps_changed = gps_changed;
  }

  std::uint64_t overrun() const override {
    std::uint64_t total = 0;
    for (const auto& layer : layers_) total += layer.stream.overrun();
    return total;
  }

 private:
  struct Context {
    Point14 last;
    std::array<SymbolModel, 8> changed{SymbolModel(128), SymbolModel(128), SymbolModel(128),
                                       SymbolModel(128), SymbolModel(128), SymbolModel(128),
                                       SymbolModel(128), SymbolModel(128)};
    SymbolModel scanner_channel{3};
    std::array<std::unique_ptr<SymbolModel>, 16> number_of_returns, return_number;
    SymbolModel return_number_gps_same{13};
    IntegerDecoder dx{32, 2}, dy{32, 22}, z{32, 20};
    std::array<std::unique_ptr<SymbolModel>, 64> classification, flags, user_data;
    IntegerDecoder intensity{16, 4}, scan_angle{16, 2}, point_source{16};
    GpsTimeState gps{GpsTimeState::Coding::V3};
    std::array<StreamingMedian5, 12> median_x{}, median_y{};
    std::array<std::int32_t, 8> last_z{};
    std::array<std::uint16_t, 8> last_intensity{};
  };

  Layer& xy() { return layers_[0]; }

  void create(std::uint32_t channel, const Point14& from) {
    auto c = std::make_unique<Context>();
    c->last = from;
    c->last.gps_changed = false;
    c->last_z.fill(from.z);
    c->last_intensity.fill(from.intensity);
    c->gps.reset(from.gps);
    contexts_[channel] = std::move(c);
  }

  bool v4_;
  std::array<Layer, 9> layers_;
  std::array<std::unique_ptr<Context>, 4> contexts_;
  std::uint32_t current_ = 0;
};

// Channel bookkeeping of the items that follow POINT14: a context per channel, started from
// the current one's last values when a channel first appears.
template <class State>
class Channels {
 public:
  explicit Channels(bool v4) : v4_(v4) {}
  template <class Make>
  void start(std::uint32_t context, Make&& make) {
    current_ = context;
    states_[current_] = make(nullptr);
  }
  /// The state to decode with (the new channel's) and the one whose last values predict
  /// (version 3: the previous channel's after a switch to a channel seen before).
  template <class Make>
  std::pair<State*, State*> switch_to(std::uint32_t context, Make&& make) {
    State* last = states_[current_].get();
    if (current_ != context) {
      current_ = context;
      if (!states_[current_]) {
        states_[current_] = make(last);
        last = states_[current_].get();
      } else if (v4_) {
        last = states_[current_].get();
      }
    }
    return {states_[current_].get(), last};
  }

 private:
  bool v4_;
  std::array<std::unique_ptr<State>, 4> states_;
  std::uint32_t current_ = 0;
};

// ---------------------------------------------------------------- RGB14 and RGBNIR14

class Rgb14V3 final : public LayeredItemDecoder {
 public:
  Rgb14V3(bool nir, bool v4) : nir_(nir), channels_(v4) {}

  void read_sizes(ByteStream& chunk) override {
    rgb_.size = chunk.get_u32();
    if (nir_) nir_layer_.size = chunk.get_u32();
  }
  void start(ByteStream& chunk, const std::uint8_t* raw, std::uint32_t& context,
             std::uint32_t requested) override {
    rgb_.take(chunk, (requested & LayerRgb) != 0);
    if (nir_) nir_layer_.take(chunk, (requested & LayerNir) != 0);
    std::array<std::uint16_t, 4> first{};
    for (int i = 0; i < (nir_ ? 4 : 3); ++i) first[i] = load_le<std::uint16_t>(raw + 2 * i);
    channels_.start(context, [&](const State*) { return make(first); });
  }
  void next(std::uint8_t* out, std::uint32_t& context) override {
    auto [state, last] =
        channels_.switch_to(context, [&](const State* from) { return make(from->last); });
    if (rgb_.active) {
      const auto c =
          decode_rgb(rgb_.dec, state->rgb, {last->last[0], last->last[1], last->last[2]});
      for (int i = 0; i < 3; ++i) last->last[i] = c[i];
    }
    if (nir_ && nir_layer_.active) {
      const std::uint32_t sym = nir_layer_.dec.decode_symbol(state->nir_used);
      const std::uint16_t prev = last->last[3];
      std::uint16_t v = (sym & 1)
                            ? static_cast<std::uint8_t>(
                                  nir_layer_.dec.decode_symbol(state->nir_diff[0]) + (prev & 0xFF))
                            : (prev & 0xFF);
      v |= (sym & 2) ? static_cast<std::uint16_t>(
                           static_cast<std::uint8_t>(
                               nir_layer_.dec.decode_symbol(state->nir_diff[1]) + (prev >> 8))
                           << 8)
                     : (prev & 0xFF00);
      last->last[3] = v;
    }
    for (int i = 0; i < (nir_ ? 4 : 3); ++i) store_le<std::uint16_t>(out + 2 * i, last->last[i]);
  }
  std::uint64_t overrun() const override {
    return rgb_.stream.overrun() + nir_layer_.stream.overrun();
  }

 private:
  struct State {
    std::array<std::uint16_t, 4> last{};
    RgbModels rgb;
    SymbolModel nir_used{4};
    std::array<SymbolModel, 2> nir_diff{SymbolModel(256), SymbolModel(256)};
  };
  static std::unique_ptr<State> make(const std::array<std::uint16_t, 4>& from) {
    auto s = std::make_unique<State>();
    s->last = from;
    return s;
  }

  bool nir_;
  Layer rgb_, nir_layer_;
  Channels<State> channels_;
};

// ---------------------------------------------------------------- WAVEPACKET14 (29 bytes)

class WavePacket14V3 final : public LayeredItemDecoder {
 public:
  explicit WavePacket14V3(bool v4) : channels_(v4) {}
  void read_sizes(ByteStream& chunk) override { layer_.size = chunk.get_u32(); }
  void start(ByteStream& chunk, const std::uint8_t* raw, std::uint32_t& context,
             std::uint32_t requested) override {
    layer_.take(chunk, (requested & LayerWavePacket) != 0);
    channels_.start(context, [&](const State*) { return make(raw); });
  }
  void next(std::uint8_t* out, std::uint32_t& context) override {
    auto [state, last] =
        channels_.switch_to(context, [&](const State* from) { return make(from->last.data()); });
    if (layer_.active) {
      state->coder.decode(layer_.dec, last->last.data(), out);
      std::memcpy(last->last.data(), out, 29);
    } else {
      std::memcpy(out, last->last.data(), 29);
    }
  }
  std::uint64_t overrun() const override { return layer_.stream.overrun(); }

 private:
  struct State {
    std::array<std::uint8_t, 29> last{};
    WavePacketCoder coder;
  };
  static std::unique_ptr<State> make(const std::uint8_t* raw) {
    auto s = std::make_unique<State>();
    std::memcpy(s->last.data(), raw, 29);
    return s;
  }
  Layer layer_;
  Channels<State> channels_;
};

// ---------------------------------------------------------------- BYTE14 (n bytes)

class Byte14V3 final : public LayeredItemDecoder {
 public:
  Byte14V3(std::size_t n, bool v4) : n_(n), layers_(n), channels_(v4) {}
  void read_sizes(ByteStream& chunk) override {
    for (auto& layer : layers_) layer.size = chunk.get_u32();
  }
  void start(ByteStream& chunk, const std::uint8_t* raw, std::uint32_t& context,
             std::uint32_t requested) override {
    for (auto& layer : layers_) layer.take(chunk, (requested & LayerExtraBytes) != 0);
    channels_.start(context, [&](const State*) { return make(raw); });
  }
  void next(std::uint8_t* out, std::uint32_t& context) override {
    auto [state, last] =
        channels_.switch_to(context, [&](const State* from) { return make(from->last.data()); });
    for (std::size_t i = 0; i < n_; ++i) {
      if (layers_[i].active) {
        last->last[i] = static_cast<std::uint8_t>(last->last[i] +
                                                  layers_[i].dec.decode_symbol(state->models[i]));
      }
      out[i] = last->last[i];
    }
  }
  std::uint64_t overrun() const override {
    std::uint64_t total = 0;
    for (const auto& layer : layers_) total += layer.stream.overrun();
    return total;
  }

 private:
  struct State {
    std::vector<std::uint8_t> last;
    std::vector<SymbolModel> models;
  };
  std::unique_ptr<State> make(const std::uint8_t* from) const {
    auto s = std::make_unique<State>();
    s->last.assign(from, from + n_);
    s->models.assign(n_, SymbolModel(256));
    return s;
  }
  std::size_t n_;
  std::vector<Layer> layers_;
  Channels<State> channels_;
};

}  // namespace

std::unique_ptr<LayeredItemDecoder> make_layered_decoder(const Item& item) {
  // Version 2 is what some writers put for 3; 4 is 3 with the channel fixes.
  if (item.version < 2 || item.version > 4) return nullptr;
  const bool v4 = item.version == 4;
  switch (item.type) {
    case ItemType::Point14:
      return item.size == 30 ? std::make_unique<Point14V3>(v4) : nullptr;
    case ItemType::Rgb14:
      return item.size == 6 ? std::make_unique<Rgb14V3>(false, v4) : nullptr;
    case ItemType::RgbNir14:
      return item.size == 8 ? std::make_unique<Rgb14V3>(true, v4) : nullptr;
    case ItemType::WavePacket14:
      return item.size == 29 ? std::make_unique<WavePacket14V3>(v4) : nullptr;
    case ItemType::Byte14:
      return item.size > 0 ? std::make_unique<Byte14V3>(item.size, v4) : nullptr;
    default:
      return nullptr;
  }
}

}  // namespace csgtile::geo::detail::laz
