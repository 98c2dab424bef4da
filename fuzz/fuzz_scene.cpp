// libFuzzer target: the scene loader on arbitrary bytes (scripts/fuzz.sh, the 'fuzz' CMake preset).
//
// The contract under test (docs/scene_format.md): whatever the bytes, parse_scene either returns a scene or throws
// InvalidInput with ONE line that names the file; it never aborts, hangs or throws anything else. A scene that parses
// and is small (<= 20,000 particles, so that one input stays fast) is also cooked with build_scene, which may refuse it
// only with InvalidInput naming the file. Anything else escapes and crashes the fuzzer, as do ASan and UBSan reports;
// a message that breaks the one-line rule is reported through __builtin_trap.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "drape/errors.hpp"
#include "drape/scene.hpp"

namespace {

constexpr const char* source = "fuzz.json";
constexpr std::size_t max_particles = 20'000;

/// One line, naming the file, of a sane length.
void check_message(const drape::InvalidInput& e) {
    const std::string msg = e.what();
    const std::string prefix = std::string(source) + ": ";
    const bool ok = msg.size() > prefix.size() && msg.compare(0, prefix.size(), prefix) == 0 &&
                    msg.find('\n') == std::string::npos && msg.find('\r') == std::string::npos && msg.size() < 2048;
    if (!ok) {
        std::fprintf(stderr, "fuzz_scene: bad error message (%zu chars): %.2048s\n", msg.size(), msg.c_str());
        __builtin_trap();
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    drape::SceneSpec spec;
    try {
        spec = drape::parse_scene(text, source);
    } catch (const drape::InvalidInput& e) {
        check_message(e);
        return 0;
    }
    if (drape::scene_particle_count(spec) > max_particles) return 0;
    try {
        const drape::BuiltScene built = drape::build_scene(spec);
        if (built.cloth.particle_count == 0 || !(built.params.dt > 0.0f)) __builtin_trap();
    } catch (const drape::InvalidInput& e) {
        check_message(e);
    }
    return 0;
}
