#pragma once
// Loads and stores of little- and big-endian values from byte buffers (alignment-free).

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace csgtile::geo::detail {

template <class T>
T byte_swapped(T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T) / 2; ++i) {
    const unsigned char t = bytes[i];
    bytes[i] = bytes[sizeof(T) - 1 - i];
    bytes[sizeof(T) - 1 - i] = t;
  }
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

/// Value of type T stored little-endian at `p`.
template <class T>
inline T load_le(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    value = byte_swapped(value);
  }
  return value;
}

/// Value of type T stored big-endian at `p`.
template <class T>
inline T load_be(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::little && sizeof(T) > 1) {
    value = byte_swapped(value);
  }
  return value;
}

/// Stores `value` little-endian at `p`.
template <class T>
inline void store_le(std::uint8_t* p, T value) {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    value = byte_swapped(value);
  }
  std::memcpy(p, &value, sizeof(T));
}

}  // namespace csgtile::geo::detail
