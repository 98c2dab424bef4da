// The range check of core's cold-tier builders (panels, colliders, grid scenes): a value outside [lo, hi] (or NaN)
// throws InvalidInput naming the value, its unit and the allowed range. Internal to core.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "drape/errors.hpp"

namespace drape {

template <class T> void check_range(const std::string& name, T value, T lo, T hi, const char* unit) {
    if (!(value >= lo && value <= hi))
        throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// A size, stiffness or rate that must be above zero (or at least zero: zero_allowed), finite and at most hi; the error
/// names the value, its unit and the range ("(0, 1000.000000]", "[0, inf)").
template <class T>
void check_positive(const std::string& name, T value, const char* unit, bool zero_allowed = false,
                    T hi = std::numeric_limits<T>::infinity()) {
    if (std::isfinite(value) && (zero_allowed ? value >= T(0) : value > T(0)) && value <= hi) return;
    const std::string top = std::isinf(hi) ? "inf)" : std::to_string(hi) + "]";
    throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range " +
                       (zero_allowed ? "[0, " : "(0, ") + top);
}

} // namespace drape
