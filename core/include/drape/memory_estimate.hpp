// Memory a scene needs, estimated before anything is built, so that a build that cannot fit is refused at once
// with the figure (instead of failing after tens of seconds and gigabytes).
#pragma once

#include <cstddef>
#include <string>

#include "drape/scene.hpp"

namespace drape {

/// Peak bytes to cook and run the scene (cooking temporaries included), from its particle count.
std::size_t scene_memory_bytes(const SceneSpec& spec);

/// Bytes this process may still allocate: the smaller of the system's available memory (/proc/meminfo
/// MemAvailable) and the address-space limit (RLIMIT_AS) less what the process already maps. SIZE_MAX if unknown.
std::size_t available_memory_bytes();

/// "9.2 GiB", "310 MiB", ...
std::string format_bytes(std::size_t bytes);

/// Throws InvalidInput naming `what` (e.g. "--size 4096"), the memory needed and the memory available when the
/// scene cannot fit.
void check_scene_memory(const SceneSpec& spec, const std::string& what);

} // namespace drape
