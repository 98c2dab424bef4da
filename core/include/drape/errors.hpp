// Error types. Every message names what is wrong and, where there is one, the allowed range.
#pragma once

#include <stdexcept>
#include <string>

namespace drape {

/// Bad input: a parameter out of range, a malformed scene, a time step above the stability bound.
/// The CLI maps it to exit code 2.
class InvalidInput : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// The simulation produced a non-finite value; the message names the step and the particle.
/// The CLI maps it to exit code 3.
class SimulationError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

} // namespace drape
