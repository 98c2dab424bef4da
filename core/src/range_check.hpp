// The range check of core's cold-tier builders (panels, colliders, grid scenes): a value outside [lo, hi] (or NaN)
// throws InvalidInput naming the value, its unit and the allowed range. Internal to core.
#pragma once

#include <string>

#include "drape/errors.hpp"

namespace drape {

template <class T> void check_range(const std::string& name, T value, T lo, T hi, const char* unit) {
    if (!(value >= lo && value <= hi))
        throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

} // namespace drape
