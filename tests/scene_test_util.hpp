// Shared by the scene-file tests: the message a scene's JSON is refused with, and substring checks on messages.
#pragma once

#include <string>

#include "drape/errors.hpp"
#include "drape/scene.hpp"

namespace drape::testing {

/// The InvalidInput message parse_scene gives for `json` (read as "test.json"), or "" when it is accepted.
inline std::string scene_error_of(const std::string& json) {
    try {
        parse_scene(json, "test.json");
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

inline bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

} // namespace drape::testing
