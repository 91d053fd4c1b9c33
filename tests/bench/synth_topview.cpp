// synth_topview IN.las OUT.ppm [OUT.png] [--size PIXELS] [--side] [--source ID]
//
// Looks at a point cloud (typically from `csgtile synth`): rasterises it seen from above
// (or, with --side, from the south), keeping the nearest point of each pixel, coloured by
// class — ground grey-green shaded by height, buildings on a blue-to-red height ramp,
// unclassified violet, noise dark magenta (low) and black (high). Writes binary PPM and, when
// asked, PNG (stored deflate, no compression library needed). --source keeps one strip or station.
// A viewing aid for people, not a product tool.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"

namespace {

using Rgb = std::array<std::uint8_t, 3>;

struct Image {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;
};

bool write_ppm(const std::string& path, const Image& image) {
  std::ofstream out(path, std::ios::binary);
  out << "P6\n" << image.width << " " << image.height << "\n255\n";
  out.write(reinterpret_cast<const char*>(image.pixels.data()),
            static_cast<std::streamsize>(image.pixels.size() * 3));
  return static_cast<bool>(out);
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320U ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void chunk(std::vector<std::uint8_t>& file, const char* type,
           const std::vector<std::uint8_t>& data) {
  put_u32(file, static_cast<std::uint32_t>(data.size()));
  std::vector<std::uint8_t> body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  file.insert(file.end(), body.begin(), body.end());
  put_u32(file, crc32(body.data(), body.size()));
}

// PNG with the image data in stored (uncompressed) deflate blocks.
bool write_png(const std::string& path, const Image& image) {
  std::vector<std::uint8_t> raw;
  for (int y = 0; y < image.height; ++y) {
    raw.push_back(0);  // filter: none
    for (int x = 0; x < image.width; ++x) {
      const Rgb& p =
          image.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) +
                       static_cast<std::size_t>(x)];
      raw.insert(raw.end(), p.begin(), p.end());
    }
  }
  std::vector<std::uint8_t> z{0x78, 0x01};
  for (std::size_t at = 0; at < raw.size() || at == 0;) {
    const std::size_t n = std::min<std::size_t>(65535, raw.size() - at);
    const bool last = at + n == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<std::uint8_t>(n));
    z.push_back(static_cast<std::uint8_t>(n >> 8));
    z.push_back(static_cast<std::uint8_t>(~n));
    z.push_back(static_cast<std::uint8_t>(~n >> 8));
    z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(at),
             raw.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += n;
    if (last) break;
  }
  std::uint32_t a = 1, b = 0;
  for (std::uint8_t v : raw) {
    a = (a + v) % 65521;
    b = (b + a) % 65521;
  }
  put_u32(z, (b << 16) | a);
  std::vector<std::uint8_t> file{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<std::uint8_t> header;
  put_u32(header, static_cast<std::uint32_t>(image.width));
  put_u32(header, static_cast<std::uint32_t>(image.height));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8-bit RGB
  chunk(file, "IHDR", header);
  chunk(file, "IDAT", z);
  chunk(file, "IEND", {});
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size()));
  return static_cast<bool>(out);
}

// Blue → green → yellow → red over [0, 1].
Rgb ramp(double v) {
  v = std::clamp(v, 0.0, 1.0);
  const double r = std::clamp(1.5 - std::abs(4 * v - 3), 0.0, 1.0);
  const double g = std::clamp(1.5 - std::abs(4 * v - 2), 0.0, 1.0);
  const double b = std::clamp(1.5 - std::abs(4 * v - 1), 0.0, 1.0);
  return {static_cast<std::uint8_t>(255 * r), static_cast<std::uint8_t>(255 * g),
          static_cast<std::uint8_t>(255 * b)};
}

int run(int argc, char** argv) {
  std::vector<std::string> files;
  int size = 900;
  bool side = false;
  int source = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--size" && i + 1 < argc) {
      size = std::max(16, std::atoi(argv[++i]));
    } else if (a == "--source" && i + 1 < argc) {
      source = std::atoi(argv[++i]);
    } else if (a == "--side") {
      side = true;
    } else {
      files.push_back(a);
    }
  }
  if (files.size() < 2) {
    std::fprintf(stderr,
                 "usage: synth_topview IN.las OUT.ppm [OUT.png] [--size PIXELS] [--side] "
                 "[--source ID]\n");
    return 64;
  }
  auto reader = csgtile::geo::LasReader::open(files[0]);
  if (!reader.ok()) {
    std::fprintf(stderr, "synth_topview: %s\n", reader.error().message.c_str());
    return 74;
  }
  struct P {
    double u, v, depth, z;
    std::uint8_t c;
  };
  std::vector<P> points;
  csgtile::geo::PointBatch batch;
  for (;;) {
    auto n = reader.value()->read(batch, 1 << 16);
    if (!n.ok()) {
      std::fprintf(stderr, "synth_topview: %s\n", n.error().message.c_str());
      return 65;
    }
    if (n.value() == 0) break;
    for (const auto& p : batch.points) {
      if (source >= 0 && p.point_source_id != source) continue;
      // Top: u = x, v = y, nearest = highest. Side (from the south): u = x, v = z, nearest = min y.
      points.push_back(side ? P{p.x, p.z, p.y, p.z, p.classification}
                            : P{p.x, p.y, -p.z, p.z, p.classification});
    }
  }
  if (points.empty()) {
    std::fprintf(stderr, "synth_topview: no points\n");
    return 65;
  }
  // Bounds from the 0.1 % and 99.9 % quantiles: stray outliers do not shrink the picture.
  auto quantiles = [&](auto field) {
    std::vector<double> v;
    v.reserve(points.size());
    for (const auto& p : points) v.push_back(field(p));
    const std::size_t lo = v.size() / 1000, hi = v.size() - 1 - v.size() / 1000;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(lo), v.end());
    const double a = v[lo];
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(hi), v.end());
    return std::array<double, 2>{a, v[hi]};
  };
  const auto ur = quantiles([](const P& p) { return p.u; });
  const auto vr = quantiles([](const P& p) { return p.v; });
  double zlo = 1e300, zhi = -1e300;
  for (const auto& p : points) {
    if (p.c == 6 || p.c == 1) {
      zlo = std::min(zlo, p.z);
      zhi = std::max(zhi, p.z);
    }
  }
  const double zg_lo = quantiles([](const P& p) { return p.z; })[0];
  if (!(zlo < zhi)) {
    zlo = zg_lo;
    zhi = zg_lo + 1;
  }
  const double span = std::max(ur[1] - ur[0], vr[1] - vr[0]);
  // Pixel: at most `size` across, at least about one point spacing (fewer holes).
  const double spacing =
      std::sqrt((ur[1] - ur[0]) * (vr[1] - vr[0]) / static_cast<double>(points.size()));
  const double pixel = std::max(span / size, side ? span / size : 1.5 * spacing);
  Image image;
  image.width = static_cast<int>((ur[1] - ur[0]) / pixel) + 1;
  image.height = static_cast<int>((vr[1] - vr[0]) / pixel) + 1;
  image.pixels.assign(
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height),
      Rgb{250, 250, 250});
  std::vector<double> depth(image.pixels.size(), 1e300);
  for (const auto& p : points) {
    const int x = static_cast<int>((p.u - ur[0]) / pixel);
    const int y = image.height - 1 - static_cast<int>((p.v - vr[0]) / pixel);
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
    const std::size_t at = static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) +
                           static_cast<std::size_t>(x);
    if (p.depth >= depth[at]) continue;
    depth[at] = p.depth;
    Rgb colour;
    switch (p.c) {
      case 2: {
        const double shade = std::clamp(0.75 + 0.25 * (p.z - zg_lo), 0.5, 1.0);
        colour = {static_cast<std::uint8_t>(150 * shade), static_cast<std::uint8_t>(160 * shade),
                  static_cast<std::uint8_t>(130 * shade)};
        break;
      }
      case 6:
        colour = ramp(0.15 + 0.85 * (p.z - zlo) / (zhi - zlo));
        break;
      case 7:
        colour = {120, 0, 120};
        break;
      case 18:
        colour = {0, 0, 0};
        break;
      default:
        colour = {170, 60, 210};
        break;
    }
    image.pixels[at] = colour;
  }
  if (!write_ppm(files[1], image)) {
    std::fprintf(stderr, "synth_topview: cannot write %s\n", files[1].c_str());
    return 74;
  }
  if (files.size() > 2 && !write_png(files[2], image)) {
    std::fprintf(stderr, "synth_topview: cannot write %s\n", files[2].c_str());
    return 74;
  }
  std::printf("%zu points, %d x %d pixels of %.3f m\n", points.size(), image.width, image.height,
              pixel);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "synth_topview: %s\n", e.what());
    return 70;
  }
}
