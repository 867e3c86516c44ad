// Numbers read from files converted to narrower types only when they fit: a
// static_cast of an out-of-range double is undefined behaviour, and a file may
// say anything.
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>

namespace semrec {

/// `value` as T when T can represent it: integers must be whole (after
/// rounding when `round` is set) and in range; floating-point targets take
/// NaN, infinities and every finite value within range.
template <typename T>
std::optional<T> CheckedCast(double value, bool round = false) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isfinite(value) &&
        std::abs(value) > static_cast<double>(std::numeric_limits<T>::max())) {
      return std::nullopt;
    }
    return static_cast<T>(value);
  } else {
    if (round) value = std::round(value);
    // The bounds are exact as doubles for every integer type up to 32 bits;
    // for 64 bits `max` rounds up, so the upper test is strict.
    if (!(value >= static_cast<double>(std::numeric_limits<T>::lowest()) &&
          value < static_cast<double>(std::numeric_limits<T>::max()) + 1.0) ||
        value != std::floor(value)) {
      return std::nullopt;
    }
    return static_cast<T>(value);
  }
}

}  // namespace semrec
