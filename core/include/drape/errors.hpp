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

/// The simulation stayed finite but left the healthy range the scene allows (kinetic energy far above what gravity,
/// wind and the user can supply, a runaway strain or speed): an explosion. The message names the substep, the
/// quantity, its value and bound, and the likely cause. The CLI maps it to exit code 4.
class BlowUpError : public SimulationError {
  public:
    using SimulationError::SimulationError;
};

/// An output file (a screenshot, an OBJ frame, a recording) could not be written; the message names the path and
/// why. The CLI maps it to exit code 5.
class WriteError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Exit codes of the `drape` executable (docs/user_guide.md states them).
namespace exit_code {
inline constexpr int ok = 0;
inline constexpr int internal = 1;      ///< an unexpected failure (a bug): the message says what
inline constexpr int bad_input = 2;     ///< a flag, scene file or size out of range, or more memory than there is
inline constexpr int non_finite = 3;    ///< the simulation produced a non-finite value
inline constexpr int blow_up = 4;       ///< the health monitor stopped an explosion (BlowUpError)
inline constexpr int write_failed = 5;  ///< an output file (screenshot, OBJ frame, recording) could not be written
} // namespace exit_code

} // namespace drape
