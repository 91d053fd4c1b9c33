#include "io/lzf.h"

#include <cstring>

namespace csgtile::geo::detail {

// Each control byte c starts either
//   a literal run (c < 32): the next c + 1 input bytes are copied to the output; or
//   a back reference: length L = c >> 5, extended by the next byte when L == 7; distance
//   D = ((c & 31) << 8) + next byte + 1; L + 2 bytes are copied from D bytes back in the
//   output, byte by byte (the source may overlap the destination: runs repeat).
std::optional<std::size_t> lzf_decompress(std::span<const std::uint8_t> in,
                                          std::span<std::uint8_t> out, std::string* error) {
  auto fail = [&](std::string text) -> std::optional<std::size_t> {
    if (error != nullptr) *error = std::move(text);
    return std::nullopt;
  };
  std::size_t ip = 0;
  std::size_t op = 0;
  while (ip < in.size()) {
    const unsigned ctrl = in[ip++];
    if (ctrl < 32) {
      const std::size_t length = ctrl + 1;
      if (length > in.size() - ip) {
        return fail("literal run of " + std::to_string(length) + " bytes at input byte " +
                    std::to_string(ip - 1) + " passes the end of the compressed data");
      }
      if (length > out.size() - op) {
        return fail("decoded data exceeds the declared size " + std::to_string(out.size()));
      }
      std::memcpy(out.data() + op, in.data() + ip, length);
      ip += length;
      op += length;
      continue;
    }
    std::size_t length = ctrl >> 5;
    if (length == 7) {
      if (ip >= in.size()) return fail("back reference truncated at the end of the data");
      length += in[ip++];
    }
    length += 2;
    if (ip >= in.size()) return fail("back reference truncated at the end of the data");
    const std::size_t distance = ((ctrl & 31u) << 8) + in[ip++] + 1;
    if (distance > op) {
      return fail("back reference " + std::to_string(distance) + " bytes back at output byte " +
                  std::to_string(op) + " points before the start of the data");
    }
    if (length > out.size() - op) {
      return fail("decoded data exceeds the declared size " + std::to_string(out.size()));
    }
    const std::size_t from = op - distance;
    for (std::size_t i = 0; i < length; ++i) out[op + i] = out[from + i];
    op += length;
  }
  return op;
}

}  // namespace csgtile::geo::detail
