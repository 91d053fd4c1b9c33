#pragma once
// LZF decompression (the format of liblzf, used by PCD "binary_compressed"), written from the
// format's description: a stream of literal runs and back references.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace csgtile::geo::detail {

/// Decodes `in` into `out`. Returns the number of bytes produced, or an error text when the
/// stream is malformed (a run passes the end of the input, a reference points before the
/// start of the output, or the output would pass out.size()). Never reads or writes outside
/// the two spans. Linear in the output size.
std::optional<std::size_t> lzf_decompress(std::span<const std::uint8_t> in,
                                          std::span<std::uint8_t> out, std::string* error);

}  // namespace csgtile::geo::detail
