// The range check of core's cold-tier builders (panels, colliders, grid scenes): a value outside [lo, hi] (or NaN)
// throws InvalidInput naming the value, its unit and the allowed range. Internal to core.
#pragma once

#include <cmath>
#include <cstdio>
#include <type_traits>
#include <limits>
#include <string>

#include "drape/errors.hpp"

namespace drape {

/// A number as a person writes it: integers whole, floating point with up to 7 significant digits ("1e-09", "1000",
/// not "0.000000" or "1000.000000", which hid a value of 1e-9 as zero).
template <class T> std::string range_number(T value) {
    if constexpr (std::is_floating_point_v<T>) {
        char text[32];
        std::snprintf(text, sizeof text, "%.7g", double(value));
        return text;
    } else {
        return std::to_string(value);
    }
}

template <class T> void check_range(const std::string& name, T value, T lo, T hi, const char* unit) {
    if (!(value >= lo && value <= hi))
        throw InvalidInput(name + " = " + range_number(value) + unit + " is outside the allowed range [" +
                           range_number(lo) + ", " + range_number(hi) + "]");
}

/// A size, stiffness or rate that must be above zero (or at least zero: zero_allowed), finite and at most hi; the error
/// names the value, its unit and the range ("(0, 1000]", "[0, inf)").
template <class T>
void check_positive(const std::string& name, T value, const char* unit, bool zero_allowed = false,
                    T hi = std::numeric_limits<T>::infinity()) {
    if (std::isfinite(value) && (zero_allowed ? value >= T(0) : value > T(0)) && value <= hi) return;
    const std::string top = std::isinf(hi) ? "inf)" : range_number(hi) + "]";
    throw InvalidInput(name + " = " + range_number(value) + unit + " is outside the allowed range " +
                       (zero_allowed ? "[0, " : "(0, ") + top);
}

} // namespace drape
