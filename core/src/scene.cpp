// Scene files: strict JSON reading (every field typed and range-checked, unknown fields refused, messages naming the
// file and the JSON path) and cooking a SceneSpec into a cloth plus simulation parameters.
#include "drape/scene.hpp"

#include "drape/level_transfer.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <fstream>
#include <cstdio>
#include <cstring>
#include <map>
#include <unordered_set>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "drape/bending.hpp"
#include "drape/errors.hpp"
#include "drape/level_transfer.hpp"
#include "drape/pattern_seams.hpp"
#include "drape/stability.hpp"
#include "drape/triangle_fabric.hpp"

namespace drape {

// Generated at build time from scenes/*.json (cmake/embed_scenes.cmake).
extern const char* const builtin_scene_json[];
extern const char* const builtin_scene_json_names[];
extern const std::size_t builtin_scene_json_count;

namespace {

using json = nlohmann::json;

std::string format_number(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

/// Fabric model, mesh cloth: a warning when the OBJ is not flat (the hinge bending assumes a flat rest shape).
void warn_curved_mesh(SceneSpec& s) {
    if (s.model != MaterialModel::fabric || s.cloth != ClothType::mesh || !s.mesh.mesh) return;
    const TriangleMesh& m = *s.mesh.mesh;
    const std::vector<float> x(m.x.begin(), m.x.end()), y(m.y.begin(), m.y.end()), z(m.z.begin(), m.z.end());
    const double angle = hinge_rest_angle_max(x, y, z, m.triangles) * 180.0 / 3.14159265358979323846;
    if (angle > 1.0)
        s.warnings.push_back(s.source + ": cloth.file: the mesh is not flat (neighbouring triangles meet at up to " +
                             format_number(angle) +
                             " degrees); the fabric model's bending (Bergou et al. 2006) takes the flat sheet as "
                             "its rest shape, so curved parts of the mesh are pulled towards flat");
}

/// JSON paths ("cloth.n", "physics.gravity[1]") of numbers the file writes but a double cannot hold (1e400, a 400-digit
/// integer) or that JSON does not have (NaN, Infinity), each with its text as written. The document holds 0 there;
/// the reader reports the value at its field, with the field's allowed range.
using NonFiniteNumbers = std::map<std::string, std::string>;

/// nlohmann's DOM builder plus the JSON path of the value being parsed, so that a parse error can name its field.
class PathTrackingParser {
  public:
    using number_integer_t = json::number_integer_t;
    using number_unsigned_t = json::number_unsigned_t;
    using number_float_t = json::number_float_t;
    using string_t = json::string_t;
    using binary_t = json::binary_t;

    explicit PathTrackingParser(json& root) : dom_(root, false) {}

    bool null() { return value(dom_.null()); }
    bool boolean(bool v) { return value(dom_.boolean(v)); }
    bool number_integer(number_integer_t v) { return value(dom_.number_integer(v)); }
    bool number_unsigned(number_unsigned_t v) { return value(dom_.number_unsigned(v)); }
    bool number_float(number_float_t v, const string_t& s) { return value(dom_.number_float(v, s)); }
    bool string(string_t& v) { return value(dom_.string(v)); }
    bool binary(binary_t& v) { return value(dom_.binary(v)); }
    bool start_object(std::size_t n) {
        if (too_deep()) return false;
        frames_.push_back({false, 0, {}, {}});
        return dom_.start_object(n);
    }
    bool key(string_t& k) {
        frames_.back().key = k;
        // A key given twice in one object: nlohmann keeps the last, which would silently drop the first value.
        if (!frames_.back().keys.insert(k).second) {
            duplicate_path = path();
            return false;
        }
        return dom_.key(k);
    }
    bool end_object() {
        frames_.pop_back();
        return value(dom_.end_object());
    }
    bool start_array(std::size_t n) {
        if (too_deep()) return false;
        frames_.push_back({true, 0, {}, {}});
        return dom_.start_array(n);
    }
    bool end_array() {
        frames_.pop_back();
        return value(dom_.end_array());
    }
    bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception& e) {
        error_position = position;
        error_token = token;
        error_id = e.id;
        error_message = e.what();
        error_path = path();
        return false;
    }

    /// The JSON path of the value being parsed ("" at the top level).
    std::string path() const {
        std::string out;
        for (const Frame& f : frames_) {
            if (f.array) {
                out += '[';
                out += std::to_string(f.index);
                out += ']';
            } else if (!f.key.empty()) {
                if (!out.empty()) out += '.';
                out += f.key;
            }
        }
        return out;
    }

    std::size_t error_position = 0;
    int error_id = 0;
    std::string error_token, error_message, error_path;
    std::string duplicate_path; ///< set when a key appears twice in one object (the parse stops there)
    /// Arrays and objects nested deeper than this stop the parse (a scene nests 5 deep; 8 million levels took
    /// about 1 GB before being refused): deep_path is then set.
    static constexpr std::size_t max_depth = 256;
    std::string deep_path;

  private:
    struct Frame {
        bool array;
        std::size_t index;
        std::string key;
        std::unordered_set<std::string> keys; ///< an object's keys so far
    };
    bool too_deep() {
        if (frames_.size() < max_depth) return false;
        deep_path = path();
        return true;
    }
    /// After a value (scalar or closed container): the next array element has the next index.
    bool value(bool ok) {
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
        return ok;
    }
    nlohmann::detail::json_sax_dom_parser<json> dom_;
    std::vector<Frame> frames_;
};

bool is_word_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.';
}

/// The byte range [begin, end) of a non-finite number at a failed parse's position, or {0, 0}: an overflowing number
/// (error 406, the position is just past it) or a NaN / Infinity / inf literal (a syntax error inside it).
std::pair<std::size_t, std::size_t> non_finite_token(const std::string& text, const PathTrackingParser& p) {
    const std::size_t pos = std::min(p.error_position, text.size());
    if (pos == 0) return {0, 0};
    if (p.error_id != 406 && p.error_message.find("while parsing value") == std::string::npos) return {0, 0};
    std::size_t begin = pos, end = pos;
    while (begin > 0 && is_word_char(text[begin - 1])) --begin;
    while (end < text.size() && is_word_char(text[end])) ++end;
    if (p.error_id == 406) { // the lexer stopped just past the number
        const std::size_t n = p.error_token.size();
        if (n == 0 || n > pos || text.compare(pos - n, n, p.error_token) != 0) return {0, 0};
        return {pos - n, pos};
    }
    if (begin == end) return {0, 0};
    std::string word = text.substr(begin, end - begin);
    if (word[0] == '+' || word[0] == '-') word.erase(0, 1);
    for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (word == "nan" || word == "inf" || word == "infinity") return {begin, end};
    return {0, 0};
}

std::string shorten(const std::string& s, std::size_t max_chars = 40) {
    return s.size() <= max_chars ? s : s.substr(0, max_chars - 3) + "...";
}

/// Text from the file (a key, a string value, a parser message) made fit for a one-line message: control characters
/// escaped (\u000a), and at most about max_chars long, cut in the middle ("cloth[0][0]...[0][0]") on character
/// boundaries.
std::string printable(const std::string& s, std::size_t max_chars) {
    std::string out;
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x20 || c == 0x7f) {
            char esc[8];
            std::snprintf(esc, sizeof esc, "\\u%04x", unsigned(c));
            out += esc;
        } else {
            out += ch;
        }
    }
    if (out.size() <= max_chars) return out;
    auto boundary = [&](std::size_t k) { // back to the first byte of a UTF-8 character
        while (k > 0 && (static_cast<unsigned char>(out[k]) & 0xC0) == 0x80) --k;
        return k;
    };
    const std::size_t head = boundary(max_chars / 2), tail = boundary(out.size() - max_chars / 2);
    return out.substr(0, head) + "..." + out.substr(tail);
}

/// Parses JSON text, turning non-finite numbers into null and recording them (at most 32: past that, the first one
/// is reported without its field's range). Any other error is "malformed JSON" naming where it is.
json parse_json(std::string text, const std::string& source, NonFiniteNumbers& non_finite) {
    // The JSON reader takes a NUL byte for the end of the text: what follows one would be silently ignored.
    if (const std::size_t nul = text.find('\0'); nul != std::string::npos)
        throw InvalidInput(source + ": byte " + std::to_string(nul) + " is a NUL character (a scene file is JSON text)");
    for (int attempt = 0;; ++attempt) {
        json doc;
        PathTrackingParser parser(doc);
        if (json::sax_parse(text, &parser)) return doc;
        if (!parser.deep_path.empty())
            throw InvalidInput(source + ": arrays and objects nested more than " +
                               std::to_string(PathTrackingParser::max_depth) + " deep (at " +
                               printable(parser.deep_path, 160) + "); a scene file nests at most a few levels");
        if (!parser.duplicate_path.empty())
            throw InvalidInput(source + ": " + printable(parser.duplicate_path, 160) +
                               " appears twice in one object (each key once)");
        const auto [begin, end] = non_finite_token(text, parser);
        if (begin == end) {
            std::string where = parser.error_path.empty() ? "" : " (near " + printable(parser.error_path, 160) + ")";
            throw InvalidInput(source + ": malformed JSON" + where + ": " + printable(parser.error_message, 400));
        }
        const std::string token = text.substr(begin, end - begin);
        if (attempt == 32)
            throw InvalidInput(source + ": " + printable(parser.error_path, 160) + " = " + shorten(token) +
                               " is not a finite number (JSON numbers must be finite doubles)");
        non_finite.emplace(parser.error_path, token);
        // A 0 padded to the token's length: the reader reports the recorded token at this path whatever stands there,
        // and the line and column of any later syntax error stay those of the file.
        text[begin] = '0';
        std::fill(text.begin() + std::ptrdiff_t(begin) + 1, text.begin() + std::ptrdiff_t(end), ' ');
    }
}

/// A field the reader refused (its message already names the file and the field).
class FieldError : public InvalidInput {
  public:
    using InvalidInput::InvalidInput;
};

/// Reads one JSON object: typed, range-checked fields; remembers which keys were read so that finish() can refuse
/// unknown ones.
class ObjectReader {
  public:
    ObjectReader(const json& j, std::string path, const std::string& source, const NonFiniteNumbers* non_finite = nullptr)
        : j_(j), path_(std::move(path)), source_(source), non_finite_(non_finite) {
        if (!j_.is_object()) {
            check_finite(path_, "");
            fail(path_.empty() ? "the document" : path_, "must be a JSON object");
        }
    }

    [[noreturn]] void fail(const std::string& where, const std::string& what) const {
        throw FieldError(source_ + ": " + printable(where, 160) + " " + what);
    }
    /// A number as the file wrote it (every digit of 18446744073709551615, 1.0000001 not "1"), shortened.
    static std::string written(const json& v) { return shorten(v.dump()); }
    std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
    /// Refuses a number the file wrote that is not finite (1e400, NaN): `range` is the field's allowed range.
    void check_finite(const std::string& where, const std::string& range) const {
        if (!non_finite_) return;
        const auto it = non_finite_->find(where);
        if (it != non_finite_->end())
            fail(where.empty() ? "the document" : where, "= " + shorten(it->second) + " is not a finite number" +
                            (range.empty() ? std::string() : "; allowed range " + range));
    }
    bool has(const std::string& key) const { return j_.contains(key); }
    bool has_array(const std::string& key) const { return j_.contains(key) && j_[key].is_array(); }
    bool has_string(const std::string& key) const { return j_.contains(key) && j_[key].is_string(); }

    double number(const std::string& key, double lo, double hi, const char* unit, double fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        check_finite(at(key), "[" + format_number(lo) + ", " + format_number(hi) + "]" + unit);
        if (!v.is_number()) fail(at(key), "must be a number in [" + format_number(lo) + ", " + format_number(hi) + "]" + unit);
        const double d = v.get<double>();
        if (!(d >= lo && d <= hi))
            fail(at(key), "= " + written(v) + " is outside the allowed range [" + format_number(lo) + ", " +
                              format_number(hi) + "]" + unit);
        return d;
    }
    std::uint32_t integer(const std::string& key, std::uint32_t lo, std::uint32_t hi, std::uint32_t fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        check_finite(at(key), "[" + std::to_string(lo) + ", " + std::to_string(hi) + "] (a whole number)");
        if (!v.is_number_integer() && !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
            fail(at(key), "must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        const double d = v.get<double>();
        if (!(d >= lo && d <= hi))
            fail(at(key), "= " + written(v) + " is outside the allowed range [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "]");
        return static_cast<std::uint32_t>(d);
    }
    bool boolean(const std::string& key, bool fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        if (!j_[key].is_boolean()) {
            check_finite(at(key), "");
            fail(at(key), "must be true or false");
        }
        return j_[key].get<bool>();
    }
    std::string text(const std::string& key, const std::vector<std::string>& allowed, const std::string& fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("\"" + a + "\"");
        if (!j_[key].is_string()) {
            check_finite(at(key), "");
            fail(at(key), allowed.empty() ? "must be a string" : "must be one of " + list);
        }
        const std::string s = j_[key].get<std::string>();
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end())
            fail(at(key), "= \"" + printable(s, 60) + "\" is not one of " + list);
        if (s.size() > 4096) fail(at(key), "is longer than 4096 characters");
        return s;
    }
    std::array<double, 3> vec3_double(const std::string& key, double limit, const char* unit,
                                      std::array<double, 3> fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        check_finite(at(key), "");
        if (!v.is_array() || v.size() != 3)
            fail(at(key), std::string("must be an array of 3 numbers in [-") + format_number(limit) + ", " +
                              format_number(limit) + "]" + unit);
        std::array<double, 3> out{};
        for (int k = 0; k < 3; ++k) {
            check_finite(at(key) + "[" + std::to_string(k) + "]",
                         "[-" + format_number(limit) + ", " + format_number(limit) + "]" + unit);
            if (!v[k].is_number()) fail(at(key) + "[" + std::to_string(k) + "]", "must be a number");
            const double d = v[k].get<double>();
            if (!(std::fabs(d) <= limit))
                fail(at(key) + "[" + std::to_string(k) + "]", "= " + written(v[k]) + " is outside the allowed range [-" +
                                                                  format_number(limit) + ", " + format_number(limit) +
                                                                  "]" + unit);
            out[k] = d;
        }
        return out;
    }
    std::array<float, 3> vec3(const std::string& key, double limit, const char* unit, std::array<float, 3> fallback) {
        const std::array<double, 3> d = vec3_double(key, limit, unit, {fallback[0], fallback[1], fallback[2]});
        return {static_cast<float>(d[0]), static_cast<float>(d[1]), static_cast<float>(d[2])};
    }
    /// A nested object (absent = empty object).
    ObjectReader object(const std::string& key) {
        seen_.insert(key);
        static const json empty = json::object();
        return ObjectReader(j_.contains(key) ? j_[key] : empty, at(key), source_, non_finite_);
    }
    const json* array(const std::string& key, std::size_t max_items) {
        seen_.insert(key);
        if (!j_.contains(key)) return nullptr;
        if (!j_[key].is_array()) {
            check_finite(at(key), "");
            fail(at(key), "must be an array");
        }
        if (j_[key].size() > max_items) fail(at(key), "has " + std::to_string(j_[key].size()) + " entries (at most " +
                                                          std::to_string(max_items) + ")");
        return &j_[key];
    }
    void finish() const {
        for (auto it = j_.begin(); it != j_.end(); ++it)
            if (!seen_.count(it.key())) fail(at(it.key()), "is not a known field");
    }
    const std::string& source() const { return source_; }
    const NonFiniteNumbers* non_finite() const { return non_finite_; }

  private:
    const json& j_;
    std::string path_;
    const std::string& source_;
    const NonFiniteNumbers* non_finite_;
    std::set<std::string> seen_;
};

ColliderSurface read_surface(ObjectReader& r) {
    ColliderSurface s;
    s.thickness = static_cast<float>(r.number("thickness", 0.0, 1.0, " m", s.thickness));
    s.friction = static_cast<float>(r.number("friction", 0.0, 1.0, "", s.friction));
    return s;
}

Collider read_collider(ObjectReader& r) {
    const std::string type = r.text("type", {"ground", "plane", "sphere", "disc", "capsule", "ellipsoid"}, "");
    if (type.empty()) r.fail(r.at("type"), "is required (\"ground\", \"plane\", \"sphere\", \"disc\", \"capsule\", \"ellipsoid\")");
    const ColliderSurface surface = read_surface(r);
    Collider c;
    try {
        if (type == "ground") {
            c = make_ground(static_cast<float>(r.number("height", -1000.0, 1000.0, " m", 0.0)), surface);
        } else if (type == "plane") {
            c = make_plane(r.vec3("point", 1000.0, " m", {0, 0, 0}), r.vec3("normal", 1.0, "", {0, 1, 0}), surface);
        } else if (type == "sphere") {
            c = make_sphere(r.vec3("centre", 1000.0, " m", {0, 0, 0}),
                            static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.3)), surface);
        } else if (type == "disc") {
            c = make_disc(r.vec3("top_centre", 1000.0, " m", {0, 0, 0}),
                          static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.15)),
                          static_cast<float>(r.number("height", 1e-4, 1000.0, " m", 0.02)), surface);
        } else if (type == "capsule") {
            c = make_capsule(r.vec3("a", 1000.0, " m", {-0.3f, 0, 0}), r.vec3("b", 1000.0, " m", {0.3f, 0, 0}),
                             static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.1)), surface);
        } else {
            c = make_ellipsoid(r.vec3("centre", 1000.0, " m", {0, 0, 0}), r.vec3("semi_axes", 1000.0, " m", {0.3f, 0.2f, 0.2f}),
                               surface);
        }
    } catch (const FieldError&) {
        throw;
    } catch (const InvalidInput& e) {
        r.fail(r.at("type") + " \"" + type + "\":", e.what());
    }
    r.finish();
    return c;
}


/// cloth.type = "mesh": the fields, then the OBJ file (read here, so a broken file is an input error at load).
void read_mesh_cloth(ObjectReader& cloth, const std::string& base_dir, SceneSpec& s) {
    MeshClothSpec& m = s.mesh;
    const std::string file = cloth.text("file", {}, "");
    if (file.empty()) cloth.fail(cloth.at("file"), "is required: the OBJ file, relative to the scene file's directory");
    m.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", m.density));
    m.scale = static_cast<float>(cloth.number("scale", 1e-4, 1e4, "", m.scale));
    m.centre = cloth.vec3("centre", 1000.0, " m", m.centre);
    const std::filesystem::path resolved =
        (base_dir.empty() ? std::filesystem::path(file) : std::filesystem::path(base_dir) / file).lexically_normal();
    try {
        m.mesh = std::make_shared<const TriangleMesh>(load_obj_mesh(resolved.string()));
    } catch (const InvalidInput& e) {
        cloth.fail(cloth.at("file") + " \"" + file + "\":", e.what());
    }
    m.file = std::filesystem::absolute(resolved).lexically_normal().string();
    const std::size_t vertices = m.mesh->obj_vertices();
    if (cloth.has_array("pins")) {
        const json* list = cloth.array("pins", vertices);
        m.pins = MeshPins::list;
        for (std::size_t k = 0; k < list->size(); ++k) {
            const json& v = (*list)[k];
            const std::string where = cloth.at("pins") + "[" + std::to_string(k) + "]";
            if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= vertices)
                cloth.fail(where, "must be an OBJ vertex index in [0, " + std::to_string(vertices - 1) +
                                      "] (0-based, file order)");
            const auto i = v.get<std::uint32_t>();
            if (m.mesh->particle_of_vertex[i] < 0)
                cloth.fail(where, "= " + std::to_string(i) + " is a vertex in no triangle (dropped from the cloth)");
            m.pin_vertices.push_back(i);
        }
    } else {
        const std::string pins = cloth.text("pins", {"none", "top"}, "none");
        m.pins = pins == "top" ? MeshPins::top : MeshPins::none;
    }
    const std::string note = m.mesh->cleaning_note();
    if (!note.empty()) s.warnings.push_back(cloth.source() + ": cloth.file \"" + file + "\": " + note);
}

/// A mask panel's frame: the file's axes normalised, the origin relative to the cloth's origin.
PanelFrame mask_frame(const MaskPanelSpec& p, const std::array<double, 3>& cloth_origin) {
    PanelFrame f;
    const auto unit = [](const std::array<float, 3>& a) {
        const double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
        return std::array<float, 3>{float(a[0] / len), float(a[1] / len), float(a[2] / len)};
    };
    f.axis_u = unit(p.axis_u);
    f.axis_v = unit(p.axis_v);
    for (int k = 0; k < 3; ++k)
        f.origin[k] = static_cast<float>(p.origin[k] - cloth_origin[k]);
    return f;
}

/// Whether every mask panel's u axis is that of the first (or its opposite): the fabric's weave then has one
/// direction in the cloth (WeaveAlignment::aligned along it).
bool mask_weave_aligned(const MaskClothSpec& m) {
    if (m.panels.empty()) return true;
    const PanelFrame f0 = mask_frame(m.panels[0], {0.0, 0.0, 0.0});
    for (const MaskPanelSpec& p : m.panels) {
        const PanelFrame f = mask_frame(p, {0.0, 0.0, 0.0});
        const double d = double(f.axis_u[0]) * f0.axis_u[0] + double(f.axis_u[1]) * f0.axis_u[1] +
                         double(f.axis_u[2]) * f0.axis_u[2];
        if (std::fabs(d) < 0.9999) return false;
    }
    return true;
}

/// "[row, column]" of a mask cell, for messages.
std::string cell_text(std::int64_t row, std::int64_t column) {
    std::string out(1, '['); // (built up: GCC 12 warns falsely on "[" + std::to_string(...), -Wrestrict)
    out += std::to_string(row);
    out += ", ";
    out += std::to_string(column);
    out += ']';
    return out;
}

/// A [row, column] pair from the file: whole numbers below the mask's size.
std::array<std::uint32_t, 2> read_cell(const ObjectReader& r, const json& v, const std::string& where,
                                       const MaskPanel& mask) {
    const std::size_t rows = mask.rows.size(), columns = mask.rows[0].size();
    const std::string range =
        "rows [0, " + std::to_string(rows - 1) + "], columns [0, " + std::to_string(columns - 1) + "]";
    for (const std::string& w : {where, where + "[0]", where + "[1]"})
        r.check_finite(w, range);
    if (!v.is_array() || v.size() != 2 || !v[0].is_number_unsigned() || !v[1].is_number_unsigned())
        r.fail(where, "must be a cell [row, column] (whole numbers; " + range + ")");
    const std::uint64_t row = v[0].get<std::uint64_t>(), column = v[1].get<std::uint64_t>();
    if (row >= rows || column >= columns)
        r.fail(where,
               "= [" + std::to_string(row) + ", " + std::to_string(column) + "] is outside the mask (" + range + ")");
    return {static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(column)};
}

/// An in-plane axis of a mask panel: 3 numbers, length 1e-6..1e6 (normalised when built).
std::array<float, 3> read_axis(ObjectReader& p, const std::string& key, std::array<float, 3> fallback) {
    const std::array<float, 3> a = p.vec3(key, 1e6, "", fallback);
    const double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    if (!(len >= 1e-6 * (1.0 - 1e-6))) // the bound itself passes (1e-6 read into a float is 9.99999997e-7)
        p.fail(p.at(key), "has length " + format_number(len) + "; an axis needs a length of at least 1e-6");
    return a;
}

/// One panel of a mask cloth (cloth.panels[k]).
MaskPanelSpec read_mask_panel(ObjectReader& p) {
    MaskPanelSpec out;
    out.name = p.text("name", {}, "");
    if (out.name.empty()) p.fail(p.at("name"), "is required: a name that seams use to refer to the panel");
    if (out.name.size() > 64) p.fail(p.at("name"), "is longer than 64 characters");
    const json* rows = p.array("rows", mask_max_side);
    if (!rows || rows->empty())
        p.fail(p.at("rows"), "must list 1 to " + std::to_string(mask_max_side) +
                                 " rows of '0' and '1' characters ('1' = a particle)");
    std::size_t ones = 0;
    for (std::size_t r = 0; r < rows->size(); ++r) {
        const std::string where = p.at("rows") + "[" + std::to_string(r) + "]";
        const json& v = (*rows)[r];
        p.check_finite(where, "");
        if (!v.is_string()) p.fail(where, "must be a string of '0' and '1' characters");
        const std::string& row = v.get_ref<const std::string&>();
        if (row.empty() || row.size() > mask_max_side)
            p.fail(where,
                   "has " + std::to_string(row.size()) + " characters; allowed 1 to " + std::to_string(mask_max_side));
        if (r > 0 && row.size() != out.mask.rows[0].size())
            p.fail(where, "has " + std::to_string(row.size()) + " characters but " + p.at("rows") + "[0] has " +
                              std::to_string(out.mask.rows[0].size()) +
                              " (a mask is rectangular: rows of equal length)");
        for (std::size_t c = 0; c < row.size(); ++c) {
            if (row[c] == '1') {
                ++ones;
            } else if (row[c] != '0') {
                const auto uc = static_cast<unsigned char>(row[c]);
                char what[32];
                if (uc >= 32 && uc < 127)
                    std::snprintf(what, sizeof what, "'%c'", row[c]);
                else
                    std::snprintf(what, sizeof what, "byte 0x%02x", unsigned(uc));
                p.fail(where, "column " + std::to_string(c) + " holds " + what + "; only '0' and '1' are allowed");
            }
        }
        out.mask.rows.push_back(row);
    }
    if (ones == 0) p.fail(p.at("rows"), "holds no '1': a panel needs at least one particle");
    out.cell_size = static_cast<float>(p.number("cell_size", 1e-3, 1.0, " m", out.cell_size));
    out.origin = p.vec3_double("origin", 1000.0, " m", out.origin);
    out.axis_u = read_axis(p, "axis_u", out.axis_u);
    out.axis_v = read_axis(p, "axis_v", out.axis_v);
    const auto& u = out.axis_u;
    const auto& v = out.axis_v;
    const double cosine = (double(u[0]) * v[0] + double(u[1]) * v[1] + double(u[2]) * v[2]) /
                          (std::sqrt(double(u[0]) * u[0] + double(u[1]) * u[1] + double(u[2]) * u[2]) *
                           std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]));
    if (!(std::fabs(cosine) <= 1e-5))
        p.fail(p.at("axis_v"), "is not perpendicular to " + p.at("axis_u") + " (cosine of the angle " +
                                   format_number(cosine) + "; allowed within 1e-5 of 0)");
    if (p.has_array("pins")) {
        const json* list = p.array("pins", ones);
        out.pins = MaskPins::list;
        for (std::size_t k = 0; k < list->size(); ++k) {
            const std::string where = p.at("pins") + "[" + std::to_string(k) + "]";
            const auto cell = read_cell(p, (*list)[k], where, out.mask);
            if (out.mask.rows[cell[0]][cell[1]] != '1')
                p.fail(where, "= " + cell_text(cell[0], cell[1]) + " is a '0' cell (no particle to pin)");
            out.pin_cells.push_back(cell);
        }
    } else {
        out.pins = p.text("pins", {"none", "top_row"}, "none") == "top_row" ? MaskPins::top_row : MaskPins::none;
    }
    p.finish();
    return out;
}

/// One side of a seam (cloth.seams[k].a or .b): the panel by name and the path along its boundary.
MaskEdgeSpec read_mask_edge(ObjectReader& e, const std::vector<MaskPanelSpec>& panels) {
    MaskEdgeSpec out;
    std::string names; // the first 8, for messages
    for (std::size_t k = 0; k < panels.size() && k < 8; ++k)
        names += (k ? ", \"" : "\"") + printable(panels[k].name, 64) + "\"";
    if (panels.size() > 8) names += ", ... (" + std::to_string(panels.size()) + " panels)";
    const std::string name = e.text("panel", {}, "");
    if (name.empty()) e.fail(e.at("panel"), "is required: the name of a panel (" + names + ")");
    const auto it = std::find_if(panels.begin(), panels.end(), [&](const MaskPanelSpec& p) { return p.name == name; });
    if (it == panels.end())
        e.fail(e.at("panel"), "= \"" + printable(name, 60) + "\" is not a panel of this cloth (" + names + ")");
    out.panel = static_cast<std::uint32_t>(it - panels.begin());
    const MaskPanel& mask = it->mask;
    const std::string shown = printable(name, 64); // the name as messages show it (no control characters)
    const json* path = e.array("path", 4096);
    if (!path || path->empty())
        e.fail(e.at("path"),
               "must list 1 to 4096 cells [row, column]: the edge's first cell, its corners, its last cell");
    for (std::size_t k = 0; k < path->size(); ++k) {
        const std::string where = e.at("path") + "[" + std::to_string(k) + "]";
        out.path.push_back(read_cell(e, (*path)[k], where, mask));
        if (k == 0) continue;
        const std::int64_t dr = std::int64_t(out.path[k][0]) - out.path[k - 1][0];
        const std::int64_t dc = std::int64_t(out.path[k][1]) - out.path[k - 1][1];
        if (dr == 0 && dc == 0) e.fail(where, "repeats the cell before it");
        if (dr != 0 && dc != 0 && std::llabs(dr) != std::llabs(dc))
            e.fail(where, "is not on the same row, column or 45-degree diagonal as " + e.at("path") + "[" +
                              std::to_string(k - 1) + "] (each leg of an edge is straight)");
    }
    std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
    for (const auto& [r, c] : mask_edge_cells(out)) {
        if (mask.rows[r][c] != '1')
            e.fail(e.at("path"), "passes cell " + cell_text(r, c) + " of panel \"" + shown +
                                     "\", a '0' (an edge runs along particles)");
        if (!mask_cell_on_boundary(mask, r, c))
            e.fail(e.at("path"), "passes cell " + cell_text(r, c) + ", inside panel \"" + shown +
                                     "\": an edge runs along the panel's boundary");
        if (!seen.insert({r, c}).second) e.fail(e.at("path"), "passes cell " + cell_text(r, c) + " twice");
    }
    e.finish();
    return out;
}

/// cloth.type = "mask": panels, seams, density.
void read_mask_cloth(ObjectReader& cloth, SceneSpec& s) {
    MaskClothSpec& m = s.masks;
    m.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", m.density));
    const json* panels = cloth.array("panels", 256);
    if (!panels || panels->empty()) cloth.fail(cloth.at("panels"), "must list 1 to 256 panels");
    std::size_t particles = 0;
    for (std::size_t k = 0; k < panels->size(); ++k) {
        ObjectReader p((*panels)[k], cloth.at("panels") + "[" + std::to_string(k) + "]", cloth.source(),
                       cloth.non_finite());
        MaskPanelSpec panel = read_mask_panel(p);
        for (const MaskPanelSpec& other : m.panels)
            if (other.name == panel.name)
                p.fail(p.at("name"),
                       "= \"" + printable(panel.name, 60) + "\" names an earlier panel too (names are unique)");
        for (const std::string& row : panel.mask.rows)
            particles += std::size_t(std::count(row.begin(), row.end(), '1'));
        if (particles > (std::size_t{1} << 24))
            p.fail(p.at("rows"),
                   "brings the cloth to " + std::to_string(particles) + " particles; at most 16,777,216 are allowed");
        m.panels.push_back(std::move(panel));
    }
    if (const json* seams = cloth.array("seams", 4096)) {
        for (std::size_t k = 0; k < seams->size(); ++k) {
            const std::string where = cloth.at("seams") + "[" + std::to_string(k) + "]";
            ObjectReader sr((*seams)[k], where, cloth.source(), cloth.non_finite());
            MaskSeamSpec seam;
            ObjectReader a = sr.object("a");
            if (!sr.has("a")) sr.fail(sr.at("a"), "is required: {\"panel\": name, \"path\": [[row, column], ...]}");
            seam.a = read_mask_edge(a, m.panels);
            ObjectReader b = sr.object("b");
            if (!sr.has("b")) sr.fail(sr.at("b"), "is required: {\"panel\": name, \"path\": [[row, column], ...]}");
            seam.b = read_mask_edge(b, m.panels);
            seam.rest_ratio = static_cast<float>(sr.number("rest_ratio", 0.01, 2.0, "", seam.rest_ratio));
            sr.finish();
            const std::size_t na = mask_edge_cells(seam.a).size(), nb = mask_edge_cells(seam.b).size();
            if (na != nb)
                sr.fail(sr.at("b") + ".path",
                        "has " + std::to_string(nb) + " cells but " + sr.at("a") + ".path has " + std::to_string(na) +
                            "; a seam joins two edges cell to cell, so they must have equal lengths");
            m.seams.push_back(std::move(seam));
        }
    }
}

/// The "material" object: the seeds' spring fields ("model": "springs", the default when none is given) or a fabric
/// ("model": "fabric"): a preset in "fabric" with any fields overriding it, or every figure of a custom fabric, in
/// file units (g/m^2, N/m, micro-N*m, s). A material with fields of both models is refused naming one of each.
void read_material(ObjectReader& mat, SceneSpec& s) {
    static const char* const spring_keys[] = {"stiffness", "shear_ratio", "bend_ratio", "damping_ratio"};
    static const char* const fabric_keys[] = {"fabric",  "density_gsm", "stretch_u", "stretch_v",
                                              "shear",   "bend_u_uNm",  "bend_v_uNm", "damping"};
    const char* spring_key = nullptr;
    const char* fabric_key = nullptr;
    for (const char* k : spring_keys)
        if (!spring_key && mat.has(k)) spring_key = k;
    for (const char* k : fabric_keys)
        if (!fabric_key && mat.has(k)) fabric_key = k;
    if (spring_key && fabric_key)
        mat.fail(mat.at(fabric_key), "is a fabric field but " + mat.at(spring_key) +
                                         " is a spring-model field; a material is one or the other "
                                         "(docs/scene_format.md \"material\")");
    const std::string model = mat.text("model", {"fabric", "springs"}, fabric_key ? "fabric" : "springs");
    if (model == "springs" && fabric_key)
        mat.fail(mat.at(fabric_key), "is a fabric field but " + mat.at("model") + " is \"springs\"");
    if (model == "fabric" && spring_key)
        mat.fail(mat.at(spring_key), "is a spring-model field but " + mat.at("model") + " is \"fabric\"");
    s.seam_stiffness = static_cast<float>(mat.number("seam_stiffness", 100.0, 25000.0, " N/m", s.seam_stiffness));
    if (model == "springs") {
        s.model = MaterialModel::springs;
        s.stiffness = static_cast<float>(mat.number("stiffness", 100.0, 25000.0, " N/m", s.stiffness));
        s.shear_ratio = static_cast<float>(mat.number("shear_ratio", 0.0, 1.0, "", s.shear_ratio));
        s.bend_ratio = static_cast<float>(mat.number("bend_ratio", 0.0, 1.0, "", s.bend_ratio));
        s.damping_ratio = static_cast<float>(mat.number("damping_ratio", 0.0, 1.0, "", s.damping_ratio));
        return;
    }
    s.model = MaterialModel::fabric;
    const std::string base = mat.text("fabric", {}, "");
    Fabric f;
    if (!base.empty()) {
        const std::optional<Fabric> preset = find_fabric(base);
        if (!preset) mat.fail(mat.at("fabric"), "= \"" + printable(base, 60) + "\" is not a fabric preset (presets: " +
                                                    fabric_preset_names() + ")");
        f = *preset;
    } else {
        f.damping = 0.0f;
        for (const char* k : {"density_gsm", "stretch_u", "stretch_v", "shear", "bend_u_uNm", "bend_v_uNm"})
            if (!mat.has(k))
                mat.fail(mat.at(k), std::string("is required for a custom fabric (or name a preset in ") +
                                        mat.at("fabric") + ": " + fabric_preset_names() + ")");
    }
    const Fabric before = f;
    const auto field = [&](const char* key, const FabricRange& r, double scale, float& value) {
        const std::string unit = std::string(" ") + r.unit;
        value = static_cast<float>(mat.number(key, r.lo, r.hi, unit.c_str(), double(value) * scale) / scale);
    };
    field("density_gsm", fabric_range_density_gsm, fabric_gsm_per_kg_m2, f.density);
    field("stretch_u", fabric_range_stretch, 1.0, f.stretch_u);
    field("stretch_v", fabric_range_stretch, 1.0, f.stretch_v);
    field("shear", fabric_range_shear, 1.0, f.shear);
    field("bend_u_uNm", fabric_range_bend_uNm, fabric_uNm_per_Nm, f.bend_u);
    field("bend_v_uNm", fabric_range_bend_uNm, fabric_uNm_per_Nm, f.bend_v);
    field("damping", fabric_range_damping, 1.0, f.damping);
    const bool same = f.density == before.density && f.stretch_u == before.stretch_u &&
                      f.stretch_v == before.stretch_v && f.shear == before.shear && f.bend_u == before.bend_u &&
                      f.bend_v == before.bend_v && f.damping == before.damping;
    f.name = !base.empty() && same ? base : "custom";
    try {
        validate_fabric(f, mat.source() + ": material");
    } catch (const InvalidInput& e) {
        throw FieldError(e.what());
    }
    s.fabric = f;
}

inline constexpr double state_limit = 1e6; ///< |position| (m) and |velocity| (m/s) in a saved state

/// The "state" section: positions and velocities ([x, y, z] per particle) and the pinned particles. Counts are
/// checked against the cloth in build_scene (the cloth is not built yet).
SceneState read_state(ObjectReader& st) {
    SceneState out;
    const std::size_t max_particles = std::size_t{1} << 24;
    auto triples = [&](const char* key, std::vector<float>& x, std::vector<float>& y, std::vector<float>& z,
                       const char* unit) {
        const json* list = st.array(key, max_particles);
        if (!list) st.fail(st.at(key), "is required: one [x, y, z] per particle");
        x.resize(list->size());
        y.resize(list->size());
        z.resize(list->size());
        for (std::size_t i = 0; i < list->size(); ++i) {
            const json& v = (*list)[i];
            if (!v.is_array() || v.size() != 3)
                st.fail(st.at(key) + "[" + std::to_string(i) + "]", "must be [x, y, z], three numbers");
            float* dst[3] = {&x[i], &y[i], &z[i]};
            for (int k = 0; k < 3; ++k) {
                // NaN or 1e400 written in the file: named with the range (the safety net below has none).
                st.check_finite(st.at(key) + "[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                                "[-1e+06, 1e+06]" + std::string(unit));
                const double d = v[k].is_number() ? v[k].get<double>() : std::nan("");
                if (!(std::fabs(d) <= state_limit))
                    st.fail(st.at(key) + "[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                            "must be a finite number in [-1e+06, 1e+06]" + std::string(unit));
                *dst[k] = static_cast<float>(d);
            }
        }
    };
    out.origin = st.vec3_double("origin", 1000.0, " m", {0.0, 0.0, 0.0});
    triples("positions", out.x, out.y, out.z, " m");
    triples("velocities", out.vx, out.vy, out.vz, " m/s");
    if (out.vx.size() != out.x.size())
        st.fail(st.at("velocities"), "has " + std::to_string(out.vx.size()) + " entries; state.positions has " +
                                         std::to_string(out.x.size()));
    const json* pinned = st.array("pinned", max_particles);
    if (!pinned) st.fail(st.at("pinned"), "is required: the pinned particles' indices ([] for none)");
    for (std::size_t k = 0; k < pinned->size(); ++k) {
        const json& v = (*pinned)[k];
        if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= out.x.size())
            st.fail(st.at("pinned") + "[" + std::to_string(k) + "]",
                    "must be a particle index in [0, " + std::to_string(out.x.size()) + ")");
        out.pinned.push_back(v.get<std::uint32_t>());
    }
    if (st.has("self_collision_snapshot")) {
        triples("self_collision_snapshot", out.snapshot_x, out.snapshot_y, out.snapshot_z, " m");
        if (out.snapshot_x.size() != out.x.size())
            st.fail(st.at("self_collision_snapshot"), "has " + std::to_string(out.snapshot_x.size()) +
                                                          " entries; state.positions has " + std::to_string(out.x.size()));
    }
    if (const json* planes = st.array("self_collision_planes", max_particles)) {
        if (out.snapshot_x.empty())
            st.fail(st.at("self_collision_planes"), "needs self_collision_snapshot (the planes belong to its run)");
        SelfCollisionPlanes& pl = out.sc_planes;
        for (std::size_t k = 0; k < planes->size(); ++k) {
            const json& v = (*planes)[k];
            const std::string at = st.at("self_collision_planes") + "[" + std::to_string(k) + "]";
            if (!v.is_array() || v.size() != 6 || !v[0].is_number_unsigned() || v[0].get<std::uint64_t>() >= out.x.size() ||
                (k > 0 && v[0].get<std::uint64_t>() <= pl.index.back()) || !v[1].is_number_unsigned() ||
                v[1].get<std::uint64_t>() >= out.x.size())
                st.fail(at, "must be [particle, partner, nx, ny, nz, c]: particle indices in [0, " +
                                std::to_string(out.x.size()) + ") (the first ascending), then four numbers");
            double d[4];
            for (int j = 0; j < 4; ++j) d[j] = v[j + 2].is_number() ? v[j + 2].get<double>() : std::nan("");
            const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(std::fabs(len - 1.0) <= 1e-3))
                st.fail(at, "must have a unit normal nx, ny, nz (its length is " + std::to_string(len) + ")");
            const std::uint32_t i = v[0].get<std::uint32_t>();
            // The plane goes through where the run left the particle: the snapshot, up to rounding.
            const double on = d[0] * out.snapshot_x[i] + d[1] * out.snapshot_y[i] + d[2] * out.snapshot_z[i];
            if (!(std::fabs(d[3] - on) <= 1e-3))
                st.fail(at, "must have an offset c within 1 mm of n . self_collision_snapshot[" + std::to_string(i) +
                                "] (" + std::to_string(on) + " m)");
            pl.index.push_back(i);
            pl.partner.push_back(v[1].get<std::uint32_t>());
            pl.nx.push_back(static_cast<float>(d[0]));
            pl.ny.push_back(static_cast<float>(d[1]));
            pl.nz.push_back(static_cast<float>(d[2]));
            pl.c.push_back(static_cast<float>(d[3]));
        }
    }
    if (const json* sewn = st.array("seam_rest", max_particles))
        for (std::size_t k = 0; k < sewn->size(); ++k) {
            const json& v = (*sewn)[k];
            const double d = v.is_number() ? v.get<double>() : std::nan("");
            if (!(d > 0.0 && d <= 100.0))
                st.fail(st.at("seam_rest") + "[" + std::to_string(k) + "]",
                        "must be a seam's rest length in (0, 100] m (a seam being sewn)");
            out.seam_rest.push_back(static_cast<float>(d));
        }
    st.finish();
    return out;
}
} // namespace

std::vector<std::array<std::uint32_t, 2>> mask_edge_cells(const MaskEdgeSpec& edge) {
    std::vector<std::array<std::uint32_t, 2>> out;
    if (edge.path.empty()) return out;
    out.push_back(edge.path[0]);
    for (std::size_t k = 1; k < edge.path.size(); ++k) {
        std::int64_t r = edge.path[k - 1][0], c = edge.path[k - 1][1];
        const std::int64_t tr = edge.path[k][0], tc = edge.path[k][1];
        const std::int64_t sr = (tr > r) - (tr < r), sc = (tc > c) - (tc < c);
        while (r != tr || c != tc) {
            r += sr;
            c += sc;
            out.push_back({static_cast<std::uint32_t>(r), static_cast<std::uint32_t>(c)});
        }
    }
    return out;
}

bool mask_cell_on_boundary(const MaskPanel& mask, std::int64_t row, std::int64_t column) {
    const auto present = [&](std::int64_t r, std::int64_t c) {
        return r >= 0 && c >= 0 && r < std::int64_t(mask.rows.size()) && c < std::int64_t(mask.rows[0].size()) &&
               mask.rows[std::size_t(r)][std::size_t(c)] == '1';
    };
    if (!present(row, column)) return false;
    // add_mask_panel's triangles: a cell with four particles is covered by two triangles, one with three by the
    // triangle of those three. The quarter of a cell at (row, column) is covered when the cell has all four corners,
    // or three with the missing one opposite (row, column): exactly when both corners beside it are present. The
    // particle is inside the mesh when all four quarters around it are covered; otherwise a triangle edge through it
    // belongs to one triangle, or it is in none.
    for (const std::int64_t dr : {-1, 1})
        for (const std::int64_t dc : {-1, 1})
            if (!present(row + dr, column) || !present(row, column + dc)) return true;
    return false;
}

std::vector<std::string> builtin_scene_names() {
    std::vector<std::string> out;
    for (std::size_t k = 0; k < builtin_scene_json_count; ++k) out.emplace_back(builtin_scene_json_names[k]);
    return out;
}

// A function-try-block: whatever nlohmann throws (a type or range error the reader did not foresee) becomes
// InvalidInput naming the file; nothing else escapes but InvalidInput and std::bad_alloc.
SceneSpec parse_scene(const std::string& text, const std::string& source, const std::string& base_dir) try {
    if (text.size() > scene_file_max_bytes) throw InvalidInput(source + ": file is larger than 16 MiB");
    NonFiniteNumbers non_finite;
    const json doc = parse_json(text, source, non_finite);
    ObjectReader root(doc, "", source, &non_finite);
    SceneSpec s;
    s.source = source;
    s.name = root.text("scene", {}, "unnamed");
    s.description = root.text("description", {}, "");

    // cloth
    ObjectReader cloth = root.object("cloth");
    const std::string type = cloth.text("type", {"grid", "tshirt", "outline", "mesh", "mask"}, "grid");
    s.cloth = type == "tshirt"    ? ClothType::tshirt
              : type == "outline" ? ClothType::outline
              : type == "mesh"    ? ClothType::mesh
              : type == "mask"    ? ClothType::mask
                                  : ClothType::grid;
    if (s.cloth == ClothType::mesh) {
        read_mesh_cloth(cloth, base_dir, s);
    } else if (s.cloth == ClothType::mask) {
        read_mask_cloth(cloth, s);
    } else if (s.cloth == ClothType::outline) {
        OutlineClothSpec& o = s.outline;
        const json* pts = cloth.array("outline", 4096);
        if (!pts || pts->size() < 3) cloth.fail(cloth.at("outline"), "must list 3 to 4096 [u, v] vertices (m)");
        for (std::size_t k = 0; k < pts->size(); ++k) {
            const json& v = (*pts)[k];
            const std::string where = cloth.at("outline") + "[" + std::to_string(k) + "]";
            for (const std::string& w : {where, where + "[0]", where + "[1]"}) cloth.check_finite(w, "[-100, 100] m");
            if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
                cloth.fail(where, "must be [u, v], two numbers in metres");
            const double u = v[0].get<double>(), w = v[1].get<double>();
            if (!(std::fabs(u) <= 100.0 && std::fabs(w) <= 100.0))
                cloth.fail(where, "is outside the allowed range [-100, 100] m");
            o.outline.outline.push_back({u, w});
        }
        o.spacing = static_cast<float>(cloth.number("spacing", 1e-3, 1.0, " m", o.spacing));
        o.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", o.density));
        o.plane = cloth.text("plane", {"horizontal", "vertical"}, "horizontal") == "vertical" ? GridPlane::vertical
                                                                                             : GridPlane::horizontal;
        o.centre = cloth.vec3("centre", 1000.0, " m", o.centre);
        o.pin_top = cloth.text("pins", {"none", "top_edge"}, "none") == "top_edge";
        ObjectReader copy = cloth.object("copy");
        o.copy = cloth.has("copy");
        o.gap = static_cast<float>(copy.number("gap", 1e-3, 2.0, " m", o.gap));
        o.seam_rest_ratio = static_cast<float>(copy.number("seam_rest_ratio", 0.01, 2.0, "", o.seam_rest_ratio));
        if (const json* sew = copy.array("sew", 4096)) {
            for (std::size_t k = 0; k < sew->size(); ++k) {
                const json& v = (*sew)[k];
                const std::string where = copy.at("sew") + "[" + std::to_string(k) + "]";
                for (const std::string& w : {where, where + "[0]", where + "[1]"})
                    copy.check_finite(w, "[0, " + std::to_string(pts->size() - 1) + "] (vertex indices)");
                if (!v.is_array() || v.size() != 2 || !v[0].is_number_unsigned() || !v[1].is_number_unsigned() ||
                    v[0].get<std::uint64_t>() >= pts->size() || v[1].get<std::uint64_t>() >= pts->size())
                    cloth.fail(where, "must be [from vertex, to vertex], indices in [0, " +
                                          std::to_string(pts->size() - 1) + "]");
                if (v[0].get<std::uint64_t>() == v[1].get<std::uint64_t>()) // was read as the whole loop
                    cloth.fail(where, "= [" + std::to_string(v[0].get<std::uint64_t>()) + ", " +
                                          std::to_string(v[1].get<std::uint64_t>()) +
                                          "]: from and to must be different vertices (a seam runs along the outline "
                                          "from one to the other; for the whole outline give two ranges, e.g. [0, 2] "
                                          "and [2, 0])");
                o.sew.push_back({v[0].get<std::uint32_t>(), v[1].get<std::uint32_t>()});
            }
            // Each outline edge sewn once: a stretch given twice (or two overlapping ones) sewed its particles again,
            // where the second seam joined nothing new.
            const std::size_t corners = pts->size();
            std::vector<std::size_t> sewn_by(corners, SIZE_MAX);
            for (std::size_t k = 0; k < o.sew.size(); ++k)
                for (std::size_t e = o.sew[k][0]; e != o.sew[k][1]; e = (e + 1) % corners) {
                    if (sewn_by[e] != SIZE_MAX)
                        cloth.fail(copy.at("sew") + "[" + std::to_string(k) + "]",
                                   "= [" + std::to_string(o.sew[k][0]) + ", " + std::to_string(o.sew[k][1]) +
                                       "] sews outline edge " + std::to_string(e) + " (vertices " + std::to_string(e) +
                                       "-" + std::to_string((e + 1) % corners) + ") that " + copy.at("sew") + "[" +
                                       std::to_string(sewn_by[e]) + "] sews already (each stretch is sewn once)");
                    sewn_by[e] = k;
                }
        }
        copy.finish();
        try {
            check_outline(o.outline);
        } catch (const InvalidInput& e) {
            cloth.fail(cloth.at("outline") + ":", e.what());
        }
        const double points = outline_panel_point_estimate(o.outline, o.spacing);
        const std::size_t max_points = OutlinePanelParams{}.max_points;
        if (points > double(max_points))
            cloth.fail(cloth.at("spacing"), "= " + format_number(o.spacing) + " m gives this outline up to " +
                                                (points < 1e15 ? std::to_string(static_cast<long long>(points)) : format_number(points)) + " points per panel; at most " +
                                                std::to_string(max_points) + " are allowed (raise the spacing)");
    } else if (s.cloth == ClothType::grid) {
        HangParams& g = s.grid;
        g.n = cloth.integer("n", hang_min_n, hang_max_n, 100);
        g.size = static_cast<float>(cloth.number("size", 0.01, 100.0, " m", 1.0));
        g.total_mass = static_cast<float>(cloth.number("mass", 1e-6, 1000.0, " kg", 0.1));
        const std::string plane = cloth.text("plane", {"horizontal", "vertical"}, "horizontal");
        g.plane = plane == "vertical" ? GridPlane::vertical : GridPlane::horizontal;
        g.centre = cloth.vec3("centre", 1000.0, " m", {0, 0, 0});
        const std::string pins = cloth.text("pins", {"corners", "top_edge", "left_edge", "none"}, "corners");
        g.pins = pins == "top_edge"    ? GridPins::top_edge
                 : pins == "left_edge" ? GridPins::left_edge
                 : pins == "none"      ? GridPins::none
                                       : GridPins::corners;
        g.pin_radius = static_cast<float>(cloth.number("pin_radius", 0.0, hang_max_pin_radius, " m", 0.0));
    } else {
        TShirtParams& t = s.tshirt;
        t.cells_per_metre = static_cast<float>(cloth.number("cells_per_metre", 10.0, 1000.0, " 1/m", t.cells_per_metre));
        t.total_mass = static_cast<float>(cloth.number("mass", 0.001, 10.0, " kg", t.total_mass));
        t.shoulder_y = static_cast<float>(cloth.number("shoulder_y", -10.0, 10.0, " m", t.shoulder_y));
        t.gap = static_cast<float>(cloth.number("gap", 0.001, 2.0, " m", t.gap));
        t.seam_rest_ratio = static_cast<float>(cloth.number("seam_rest_ratio", 0.01, 2.0, "", t.seam_rest_ratio));
    }
    cloth.finish();

    // material: a preset's name, or an object (fabric fields, or the seeds' spring fields)
    if (root.has_string("material")) {
        const std::string preset = root.text("material", {}, "");
        const std::optional<Fabric> f = find_fabric(preset);
        if (!f) root.fail("material", "= \"" + printable(preset, 60) + "\" is not a fabric preset (presets: " +
                                          fabric_preset_names() + "; or an object, docs/scene_format.md)");
        s.model = MaterialModel::fabric;
        s.fabric = *f;
    } else {
        ObjectReader mat = root.object("material");
        read_material(mat, s);
        mat.finish();
    }
    if (s.model == MaterialModel::fabric && s.cloth == ClothType::mask && !mask_weave_aligned(s.masks))
        s.warnings.push_back(source + ": cloth.panels: the panels' axis_u differ, so the fabric's weave has no single "
                                      "direction in the cloth; the membrane uses the direction-free rule (unaligned, "
                                      "docs/fabric.md) along the first panel's axis_u");
    // With a fabric the mass comes from its areal density: a cloth's own mass or density would be a second answer.
    if (s.model == MaterialModel::fabric) {
        const char* key = s.cloth == ClothType::grid || s.cloth == ClothType::tshirt ? "mass" : "density";
        if (cloth.has(key))
            cloth.fail(cloth.at(key), std::string("is a spring-model field: with a fabric material the mass comes from "
                                                  "the fabric's areal density (material.density_gsm); remove ") +
                                          cloth.at(key) + " or use \"model\": \"springs\"");
    } else if (s.cloth == ClothType::grid) {
        // Node mass in seed 000's range 0.001 - 1 g.
        const HangParams& g = s.grid;
        const double node_mass = double(g.total_mass) / (double(g.n) * g.n);
        if (!(node_mass >= 1e-6 * 0.999 && node_mass <= 1e-3 * 1.001)) {
            if (cloth.has("mass"))
                cloth.fail(cloth.at("mass"), "gives a node mass of " + format_number(node_mass * 1000.0) +
                                                 " g; allowed range [0.001, 1] g per particle (seed 000)");
            // Not in the file: say where the mass came from (it read "cloth.mass gives ..." of a field not there).
            cloth.fail(cloth.at("n"), "gives the default cloth mass of " + format_number(double(g.total_mass)) +
                                          " kg a node mass of " + format_number(node_mass * 1000.0) +
                                          " g; allowed range [0.001, 1] g per particle (seed 000): set " +
                                          cloth.at("mass") + " (kg) or a fabric material");
        }
    }

    // physics
    ObjectReader ph = root.object("physics");
    SimulationParams& p = s.physics;
    p.gravity = ph.vec3("gravity", 100.0, " m/s^2", p.gravity);
    p.air_drag = static_cast<float>(ph.number("drag", 0.0, 100.0, " 1/s", p.air_drag));
    p.sewing_speed = static_cast<float>(
        ph.number("sewing_speed", 0.0, 10.0, " m/s (0 = off: every seam must then start closed)", p.sewing_speed));
    p.integrator = ph.text("integrator", {"euler", "verlet"}, "euler") == "verlet" ? Integrator::verlet
                                                                                 : Integrator::symplectic_euler;
    p.solver = ph.text("solver", {"explicit", "implicit"}, "explicit") == "implicit" ? Solver::implicit
                                                                                    : Solver::explicit_euler;
    if (p.solver == Solver::implicit && p.integrator == Integrator::verlet)
        ph.fail(ph.at("integrator"), "= \"verlet\" is a choice of the explicit solver only; " + ph.at("solver") +
                                         " = \"implicit\" keeps velocities: use \"euler\" (or leave it out)");
    if (ph.has("dt")) s.dt = static_cast<float>(ph.number("dt", 1e-9, 0.1, " s", 0.0));
    ObjectReader im = ph.object("implicit");
    p.implicit.iterations = im.integer("iterations", 1, implicit_max_iterations, p.implicit.iterations);
    p.implicit.tolerance = static_cast<float>(
        im.number("tolerance", 0.0, 1.0, " (0 = run every iteration)", double(p.implicit.tolerance)));
    const double rho = im.number("chebyshev_rho", 0.0, 1.0, " (1 excluded; 0 = no acceleration)", double(p.implicit.chebyshev_rho));
    if (!(rho < 1.0))
        im.fail(im.at("chebyshev_rho"), "= 1 is outside the allowed range [0, 1) (0 = no acceleration)");
    p.implicit.chebyshev_rho = static_cast<float>(rho);
    p.implicit.fas = im.boolean("fas", p.implicit.fas);
    p.implicit.fas_at_rest = im.boolean("fas_at_rest", p.implicit.fas_at_rest);
    p.implicit.multilevel = im.boolean("multilevel", p.implicit.multilevel);
    p.implicit.method = im.text("method", {"gauss_seidel", "jacobi"}, "gauss_seidel") == "jacobi"
                            ? ImplicitMethod::jacobi
                            : ImplicitMethod::gauss_seidel;
    im.finish();
    ObjectReader wind = ph.object("wind");
    p.wind.enabled = wind.boolean("enabled", false);
    p.wind.strength = static_cast<float>(wind.number("strength", 0.0, 100.0, " m/s^2", p.wind.strength));
    wind.finish();
    ObjectReader aero = ph.object("aero");
    p.aero.enabled = aero.boolean("enabled", false);
    p.aero.density = static_cast<float>(aero.number("density", 0.0, 100.0, " kg/m^3", p.aero.density));
    p.aero.drag_coefficient = static_cast<float>(aero.number("drag_coefficient", 0.0, 10.0, "", p.aero.drag_coefficient));
    p.aero.velocity = aero.vec3("velocity", 100.0, " m/s", p.aero.velocity);
    aero.finish();
    ObjectReader sl = ph.object("strain_limit");
    p.strain_limit.ratio = static_cast<float>(sl.number("ratio", 0.0, 10.0, "", 0.0));
    p.strain_limit.passes = sl.integer("passes", 1, 100, 4);
    p.strain_limit.every = sl.integer("every", 1, 1000, 1);
    sl.finish();
    ObjectReader sc = ph.object("self_collision");
    const double thickness = sc.number("thickness", 0.0, double(self_collision_max_thickness), " m (0 = off)", 0.0);
    if (thickness != 0.0 && thickness < double(self_collision_min_thickness))
        sc.fail(sc.at("thickness"), "= " + format_number(thickness) +
                                        " m is outside the allowed range 0 (off) or [0.0005, 0.05] m");
    p.self_collision.thickness = static_cast<float>(thickness);
    p.self_collision.friction =
        static_cast<float>(sc.number("friction", 0.0, 2.0, "", double(p.self_collision.friction)));
    p.self_collision.substeps = sc.integer("substeps", 1, self_collision_max_substeps, p.self_collision.substeps);
    sc.finish();
    ph.finish();

    // colliders
    if (const json* list = root.array("colliders", 64)) {
        for (std::size_t k = 0; k < list->size(); ++k) {
            ObjectReader r((*list)[k], "colliders[" + std::to_string(k) + "]", source, &non_finite);
            p.colliders.push_back(read_collider(r));
        }
    }
    s.body = root.boolean("body", false);
    if (root.has("state")) {
        ObjectReader st = root.object("state");
        s.state = read_state(st);
    }

    root.finish();
    // Every field was read or refused above, so a non-finite number has been reported; this is a safety net.
    if (!non_finite.empty())
        throw InvalidInput(source + ": " + printable(non_finite.begin()->first, 160) + " = " + shorten(non_finite.begin()->second) +
                           " is not a finite number");

    const std::size_t particles = scene_particle_count(s);
    if (particles > (std::size_t{1} << 24))
        throw InvalidInput(source + ": the cloth would have " + std::to_string(particles) +
                           " particles; at most 16,777,216 are allowed");
    warn_curved_mesh(s);
    return s;
} catch (const json::exception& e) {
    throw InvalidInput(source + ": " + e.what());
}

SceneSpec load_scene(const std::string& name_or_path) {
    const bool is_file = name_or_path.size() > 5 && name_or_path.substr(name_or_path.size() - 5) == ".json";
    if (!is_file) {
        for (std::size_t k = 0; k < builtin_scene_json_count; ++k)
            if (name_or_path == builtin_scene_json_names[k])
                return parse_scene(builtin_scene_json[k], "built-in scene '" + name_or_path + "'");
        std::string names;
        for (const std::string& n : builtin_scene_names()) names += (names.empty() ? "" : ", ") + n;
        throw InvalidInput("unknown scene '" + name_or_path + "' (built-in scenes: " + names + "; or a path to a .json file)");
    }
    // What the path is, before opening it: opening a FIFO would block until a writer comes, a directory "opens".
    const std::string& path = name_or_path;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT) throw InvalidInput(path + ": the scene file does not exist");
        if (err == ENOTDIR) throw InvalidInput(path + ": the scene file does not exist (a part of the path is not a directory)");
        if (err == EACCES) throw InvalidInput(path + ": the scene file cannot be read (permission denied)");
        throw InvalidInput(path + ": the scene file cannot be read (" + std::strerror(err) + ")");
    }
    auto kind = [](mode_t mode) -> const char* {
        if (S_ISFIFO(mode)) return "a FIFO";
        if (S_ISSOCK(mode)) return "a socket";
        if (S_ISCHR(mode)) return "a character device";
        if (S_ISBLK(mode)) return "a block device";
        return "not a plain file";
    };
    if (S_ISDIR(st.st_mode)) throw InvalidInput(path + ": is a directory, not a scene file");
    if (!S_ISREG(st.st_mode)) throw InvalidInput(path + ": is not a regular file (" + kind(st.st_mode) + ")");
    const auto too_big = [&](std::uintmax_t bytes) {
        // In bytes too: a file just over the limit read "16.0 MiB; ... limited to 16 MiB".
        char text[96];
        std::snprintf(text, sizeof text, "%ju bytes (%.2f MiB)", std::uintmax_t(bytes), double(bytes) / (1024.0 * 1024.0));
        return InvalidInput(path + ": the file is " + text + "; scene files are limited to 16 MiB (" +
                            std::to_string(scene_file_max_bytes) + " bytes)");
    };
    if (std::uintmax_t(st.st_size) > std::uintmax_t(scene_file_max_bytes)) throw too_big(std::uintmax_t(st.st_size));

    // Opened without blocking and checked again on the descriptor: the path may have been replaced since the stat.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        throw InvalidInput(path + ": the scene file cannot be read (" +
                           (err == EACCES ? std::string("permission denied") : std::string(std::strerror(err))) + ")");
    }
    std::string text;
    std::string failure;
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        failure = "is not a regular file";
    } else {
        char buf[65536];
        for (;;) {
            const ssize_t got = ::read(fd, buf, sizeof buf);
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) {
                failure = std::string("the scene file cannot be read (") + std::strerror(errno) + ")";
                break;
            }
            if (got == 0) break;
            text.append(buf, static_cast<std::size_t>(got));
            if (text.size() > scene_file_max_bytes) break;
        }
    }
    ::close(fd);
    if (!failure.empty()) throw InvalidInput(path + ": " + failure);
    if (text.size() > scene_file_max_bytes) throw too_big(text.size());
    return parse_scene(text, name_or_path, std::filesystem::path(name_or_path).parent_path().string());
}

std::size_t scene_particle_count(const SceneSpec& s) {
    if (s.cloth == ClothType::grid) return std::size_t{s.grid.n} * s.grid.n;
    if (s.cloth == ClothType::mask) { // exact: the '1' cells
        std::size_t n = 0;
        for (const MaskPanelSpec& p : s.masks.panels)
            for (const std::string& row : p.mask.rows)
                n += static_cast<std::size_t>(std::count(row.begin(), row.end(), '1'));
        return n;
    }
    if (s.cloth == ClothType::mesh) return s.mesh.mesh ? s.mesh.mesh->particle_count() : 0;
    if (s.cloth == ClothType::outline) { // bounding box / spacing^2, per panel (an upper bound)
        double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
        for (const auto& v : s.outline.outline.outline)
            for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
        const double h = s.outline.spacing;
        const double per_panel = ((hi[0] - lo[0]) / h + 2) * ((hi[1] - lo[1]) / h + 2);
        return static_cast<std::size_t>(std::min(per_panel * (s.outline.copy ? 2 : 1), 1e12));
    }
    const double r = s.tshirt.cells_per_metre;
    return static_cast<std::size_t>(0.8 * r * r) + 64; // the mask's area is ~0.39 m^2 per panel (panels.hpp)
}

std::optional<std::uint32_t> scene_resolution(const SceneSpec& s) {
    switch (s.cloth) {
    case ClothType::grid:
        return s.grid.n;
    case ClothType::tshirt:
        return static_cast<std::uint32_t>(std::lround(s.tshirt.cells_per_metre));
    case ClothType::outline:
        return static_cast<std::uint32_t>(std::max(1L, std::lround(1.0 / double(s.outline.spacing))));
    case ClothType::mesh:
    case ClothType::mask:
        return std::nullopt;
    }
    return std::nullopt;
}

void set_scene_resolution(SceneSpec& s, std::uint32_t size, const std::string& flag) {
    const auto out_of_range = [&](std::uint32_t lo, std::uint32_t hi, const std::string& what) {
        return InvalidInput(flag + ": value " + std::to_string(size) + " is outside the allowed range [" +
                            std::to_string(lo) + ", " + std::to_string(hi) + "] (" + what + ")");
    };
    switch (s.cloth) {
    case ClothType::grid:
        if (size < hang_min_n || size > hang_max_n) throw out_of_range(hang_min_n, hang_max_n, "particles per side");
        s.grid.n = size;
        return;
    case ClothType::tshirt:
        if (size < 10 || size > 1000) throw out_of_range(10, 1000, "cells per metre of the T-shirt");
        s.tshirt.cells_per_metre = static_cast<float>(size);
        return;
    case ClothType::outline: {
        if (size < 10 || size > 1000)
            throw out_of_range(10, 1000, "cells per metre of the outline: spacing 1 / size m");
        const float spacing = 1.0f / static_cast<float>(size);
        const double points = outline_panel_point_estimate(s.outline.outline, spacing);
        const std::size_t max_points = OutlinePanelParams{}.max_points;
        if (points > double(max_points))
            throw InvalidInput(flag + " " + std::to_string(size) + ": a spacing of " + format_number(spacing) +
                               " m gives this outline up to " + format_number(std::floor(points)) +
                               " points per panel; at most " + std::to_string(max_points) + " are allowed");
        s.outline.spacing = spacing;
        return;
    }
    case ClothType::mesh:
        throw InvalidInput(flag + ": the scene's cloth is a mesh; its resolution is that of its OBJ file");
    case ClothType::mask:
        throw InvalidInput(flag + ": the scene's cloth is made of masks; its resolution is their cells "
                                  "(cloth.panels[k].rows and cell_size)");
    }
}

namespace {

/// Cooks an assembly (outline and mesh cloths; the T-shirt with the fabric model). Springs model: stiffness per kind as
/// for the other cloths, the damping ratio uses the mean particle mass. Fabric model: triangle_fabric.hpp (membrane
/// springs per edge, hinge bending, seams), the weave's u axis `axis_u`.
void cook_assembly(const SceneSpec& s, const GarmentAssembly& a, const std::vector<float>& inv_mass,
                   const std::vector<float>& free_inv_mass, BuiltScene& out,
                   const std::array<float, 3>& axis_u = {1.0f, 0.0f, 0.0f},
                   WeaveAlignment alignment = WeaveAlignment::aligned) {
    if (s.model == MaterialModel::fabric) {
        out.cloth = cook_triangle_fabric(a, inv_mass, {s.fabric, axis_u, alignment});
    } else {
        double total = 0.0;
        for (float m : a.mass) total += m;
        const float mean_mass = float(total / double(std::max<std::size_t>(1, a.particle_count())));
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mean_mass * 0.5f)};
        out.cloth = cook_cloth(inv_mass, a.edges, material);
        out.cloth.triangles = a.triangles;
    }
    out.cloth.free_inv_mass = free_inv_mass;
    out.initial = a.initial_state();
}

/// cloth.type = "mask": the panels (add_mask_panel), masses from the areal density (a third of each triangle's area
/// to its corners; a particle in no triangle gets a third of a half cell, as the T-shirt's), the seams (cell k of
/// edge a to cell k of edge b; a pair already joined or a particle with itself is skipped), the pins.
void build_mask_cloth(const SceneSpec& s, BuiltScene& out) {
    const MaskClothSpec& m = s.masks;
    if (m.panels.empty()) throw InvalidInput(s.source + ": cloth.panels: a mask cloth needs at least one panel");
    // The cloth's origin: the middle of the panels' origins (positions are stored relative to it).
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const MaskPanelSpec& p : m.panels)
        for (int k = 0; k < 3; ++k)
            lo[k] = std::min(lo[k], p.origin[k]), hi[k] = std::max(hi[k], p.origin[k]);
    const std::array<double, 3> origin{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double density = s.model == MaterialModel::fabric ? double(s.fabric.density) : double(m.density);
    GarmentAssembly a;
    std::vector<MaskPanelBuild> panels;
    panels.reserve(m.panels.size());
    for (std::size_t k = 0; k < m.panels.size(); ++k) {
        const MaskPanelSpec& p = m.panels[k];
        const double h = p.cell_size;
        try {
            // (The mass is replaced below; clamped into add_mask_panel's range.)
            panels.push_back(add_mask_panel(a, p.mask, p.cell_size, float(std::clamp(density * h * h, 1e-6, 1.0)),
                                            mask_frame(p, origin)));
        } catch (const InvalidInput& e) {
            throw InvalidInput(s.source + ": cloth.panels[" + std::to_string(k) + "] \"" + printable(p.name, 64) +
                               "\": " + e.what());
        }
    }
    const std::vector<double> lumped = lumped_masses(a.x, a.y, a.z, a.triangles, density);
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const double h = m.panels[k].cell_size, lone = density * h * h / 6.0;
        for (std::uint32_t i = panels[k].first_particle; i < panels[k].first_particle + panels[k].particle_count; ++i)
            a.mass[i] = float(lumped[i] > 0.0 ? lumped[i] : lone);
    }
    std::set<std::pair<std::uint32_t, std::uint32_t>> joined;
    for (const Edge& e : a.edges)
        joined.insert({std::min(e.a, e.b), std::max(e.a, e.b)});
    for (std::size_t k = 0; k < m.seams.size(); ++k) {
        const MaskSeamSpec& seam = m.seams[k];
        const auto ca = mask_edge_cells(seam.a), cb = mask_edge_cells(seam.b);
        if (ca.size() != cb.size() || seam.a.panel >= panels.size() || seam.b.panel >= panels.size())
            throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) +
                               "]: edges of unequal length or an unknown panel");
        const float rest =
            seam.rest_ratio * 0.5f * (m.panels[seam.a.panel].cell_size + m.panels[seam.b.panel].cell_size);
        std::size_t itself = 0, before = 0;
        for (std::size_t j = 0; j < ca.size(); ++j) {
            const std::int32_t pa = panels[seam.a.panel].particle_at(ca[j][0], ca[j][1]);
            const std::int32_t pb = panels[seam.b.panel].particle_at(cb[j][0], cb[j][1]);
            if (pa < 0 || pb < 0)
                throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) +
                                   "]: a cell of the seam holds no particle");
            const auto lo_i = static_cast<std::uint32_t>(std::min(pa, pb)),
                       hi_i = static_cast<std::uint32_t>(std::max(pa, pb));
            if (lo_i == hi_i) {
                ++itself;
                continue;
            }
            if (!joined.insert({lo_i, hi_i}).second) {
                ++before;
                continue;
            }
            a.edges.push_back({lo_i, hi_i, SpringKind::seam, rest});
        }
        // A seam that joins nothing is a mistake in the file (the same edge twice, or two rows of one panel that its
        // springs already join), not a seam: refused rather than run as if sewn.
        if (itself + before == ca.size())
            throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) + "] joins nothing: of its " +
                               std::to_string(ca.size()) + " cell pairs " + std::to_string(itself) +
                               " pair a cell with itself and " + std::to_string(before) +
                               " pair cells already joined (by the panel's springs or an earlier seam); a seam "
                               "sews two different edges, cell k of a to cell k of b");
    }
    // A '1' with no '1' beside, above or below it (or across a corner with a shared neighbour) and no seam would be
    // a loose particle falling on its own: refused, naming the first such cell (a checkerboard mask ran "healthy"
    // with 0 springs).
    std::vector<std::uint32_t> degree(a.particle_count(), 0);
    for (const Edge& e : a.edges)
        ++degree[e.a], ++degree[e.b];
    const std::size_t loose = std::size_t(std::count(degree.begin(), degree.end(), 0u));
    for (std::size_t k = 0; k < panels.size() && loose > 0; ++k)
        for (std::size_t cell = 0; cell < panels[k].cell_particle.size(); ++cell) {
            const std::int32_t i = panels[k].cell_particle[cell];
            if (i < 0 || degree[std::size_t(i)] > 0) continue;
            throw InvalidInput(s.source + ": cloth.panels[" + std::to_string(k) + "] \"" +
                               printable(m.panels[k].name, 64) + "\": the '1' at row " +
                               std::to_string(cell / panels[k].columns) + ", column " +
                               std::to_string(cell % panels[k].columns) +
                               " touches no other '1' (beside, above or below it) and no seam: it would be a loose "
                               "particle falling on its own (" + std::to_string(loose) +
                               (loose == 1 ? " such cell" : " such cells") +
                               " in the cloth); join it to the panel or make it '0'");
        }
    std::vector<float> inv_mass = a.inverse_masses();
    const std::vector<float> free_inv_mass = inv_mass;
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const MaskPanelSpec& p = m.panels[k];
        if (p.pins == MaskPins::top_row) { // the first row holding a particle
            for (std::uint32_t r = 0; r < panels[k].rows; ++r) {
                bool any = false;
                for (std::uint32_t c = 0; c < panels[k].columns; ++c)
                    if (const std::int32_t i = panels[k].particle_at(r, c); i >= 0)
                        inv_mass[std::size_t(i)] = 0.0f, any = true;
                if (any) break;
            }
        } else if (p.pins == MaskPins::list) {
            for (const auto& [r, c] : p.pin_cells)
                if (const std::int32_t i = panels[k].particle_at(r, c); i >= 0) inv_mass[std::size_t(i)] = 0.0f;
        }
    }
    // The fabric's u: the first panel's (mask columns); unaligned when the panels' u axes differ (a warning on load).
    const bool aligned = mask_weave_aligned(m);
    cook_assembly(s, a, inv_mass, free_inv_mass, out, mask_frame(m.panels[0], origin).axis_u,
                  aligned ? WeaveAlignment::aligned : WeaveAlignment::unaligned);
    out.cloth.origin = origin;
}

/// A saved state replaces the initial state and the pins (after dt is chosen, so the default dt is that of the
/// scene's own pins, as when the state was saved).
void apply_state(const SceneState& st, BuiltScene& out) {
    Cloth& c = out.cloth;
    const std::size_t n = c.particle_count;
    if (st.x.size() != n)
        throw InvalidInput("state.positions has " + std::to_string(st.x.size()) + " entries but the cloth has " +
                           std::to_string(n) + " particles");
    if (st.vx.size() != n)
        throw InvalidInput("state.velocities has " + std::to_string(st.vx.size()) + " entries but the cloth has " +
                           std::to_string(n) + " particles");
    for (std::uint32_t i : st.pinned)
        if (i >= n)
            throw InvalidInput("state.pinned names particle " + std::to_string(i) + "; the cloth has " +
                               std::to_string(n) + " particles");
    if (c.free_inv_mass.size() != n) c.free_inv_mass.assign(c.inv_mass.begin(), c.inv_mass.begin() + n);
    for (std::size_t i = 0; i < n; ++i) c.inv_mass[i] = c.free_inv_mass[i];
    for (std::uint32_t i : st.pinned) c.inv_mass[i] = 0.0f;
    // Positions into the cloth's frame: exact when the state was saved from the same frame (the usual case).
    const std::array<double, 3> shift{st.origin[0] - c.origin[0], st.origin[1] - c.origin[1], st.origin[2] - c.origin[2]};
    out.initial.x = st.x;
    out.initial.y = st.y;
    out.initial.z = st.z;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0})
        for (std::size_t i = 0; i < n; ++i) {
            out.initial.x[i] = static_cast<float>(double(st.x[i]) + shift[0]);
            out.initial.y[i] = static_cast<float>(double(st.y[i]) + shift[1]);
            out.initial.z[i] = static_cast<float>(double(st.z[i]) + shift[2]);
        }
    out.initial.vx = st.vx;
    out.initial.vy = st.vy;
    out.initial.vz = st.vz;
    if (!st.seam_rest.empty() && st.seam_rest.size() != c.seams.a.size())
        throw InvalidInput("state.seam_rest has " + std::to_string(st.seam_rest.size()) + " entries but the cloth has " +
                           std::to_string(c.seams.a.size()) + " seams");
    out.initial.seam_rest = st.seam_rest;
    out.initial.snapshot_x = st.snapshot_x;
    out.initial.snapshot_y = st.snapshot_y;
    out.initial.snapshot_z = st.snapshot_z;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0})
        for (std::size_t i = 0; i < st.snapshot_x.size(); ++i) {
            out.initial.snapshot_x[i] = static_cast<float>(double(st.snapshot_x[i]) + shift[0]);
            out.initial.snapshot_y[i] = static_cast<float>(double(st.snapshot_y[i]) + shift[1]);
            out.initial.snapshot_z[i] = static_cast<float>(double(st.snapshot_z[i]) + shift[2]);
        }
    out.initial.sc_planes = st.sc_planes;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0}) {
        SelfCollisionPlanes& pl = out.initial.sc_planes;
        for (std::size_t k = 0; k < pl.index.size(); ++k)
            pl.c[k] = static_cast<float>(double(pl.c[k]) + pl.nx[k] * shift[0] + pl.ny[k] * shift[1] + pl.nz[k] * shift[2]);
    }
}

} // namespace

namespace {

/// Fabric model: an outline narrower than its spacing somewhere (a spike a fraction of the spacing wide) is
/// triangulated there into needles, which the cook refuses (NeedleTriangleError: a membrane spring past
/// membrane_stiffness_ratio_max); this names the place in the outline's coordinates (cu, cv: the outline's centre)
/// rather than two particle numbers.
[[noreturn]] void refuse_outline_needle(const SceneSpec& s, const GarmentAssembly& a, float cu, float cv,
                                        const NeedleTriangleError& e) {
    const bool horizontal = s.outline.plane == GridPlane::horizontal;
    const double u = 0.5 * (double(a.x[e.a]) + a.x[e.b]) + cu,
                 v = (horizontal ? 0.5 * (double(a.z[e.a]) + a.z[e.b]) : -0.5 * (double(a.y[e.a]) + a.y[e.b])) + cv;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  ": cloth.outline at cloth.spacing = %g m: near (%.4g, %.4g) the outline is narrower than the spacing "
                  "(a spike or a slit): its triangles there are needles whose short edge would be %.0f times as stiff "
                  "as the fabric (at most %.0f); widen the outline there, or lower cloth.spacing",
                  double(s.outline.spacing), u, v, e.ratio, membrane_stiffness_ratio_max);
    throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + msg);
}

/// The same for an OBJ mesh (fabric model): names the needle's short edge by its OBJ vertices (1-based, as the file
/// numbers them; the first of any welded duplicates) and its middle in the file's units.
[[noreturn]] void refuse_mesh_needle(const SceneSpec& s, const TriangleMesh& mesh, const NeedleTriangleError& e) {
    const auto obj_vertex = [&](std::uint32_t particle) {
        const auto& pv = mesh.particle_of_vertex;
        return std::size_t(std::find(pv.begin(), pv.end(), std::int64_t(particle)) - pv.begin()) + 1;
    };
    char msg[500];
    std::snprintf(msg, sizeof msg,
                  ": cloth.file: the edge from OBJ vertex %zu to vertex %zu (numbered from 1 as in the file's faces; near "
                  "(%.4g, %.4g, %.4g) in the file) is "
                  "the short side of a needle triangle: its membrane spring would be %.0f times as stiff as the fabric "
                  "(at most %.0f); remesh there (collapse the short edge or split the wide triangle)",
                  obj_vertex(e.a), obj_vertex(e.b), 0.5 * (mesh.x[e.a] + mesh.x[e.b]), 0.5 * (mesh.y[e.a] + mesh.y[e.b]),
                  0.5 * (mesh.z[e.a] + mesh.z[e.b]), e.ratio, membrane_stiffness_ratio_max);
    throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + msg);
}

/// cloth.type = "outline": the panel (and its sewn copy) at the spec's spacing, pinned along the top when asked.
void build_outline_cloth(const SceneSpec& s, BuiltScene& out) {
    const OutlineClothSpec& o = s.outline;
    double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
    for (const auto& v : o.outline.outline)
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    const float cu = float(0.5 * (lo[0] + hi[0])), cv = float(0.5 * (lo[1] + hi[1]));
    // Panel frame: u along +x; v along +z (horizontal) or -y (vertical); the normal u x v is -y or -z.
    PanelFrame frame;
    frame.axis_v = o.plane == GridPlane::horizontal ? std::array{0.0f, 0.0f, 1.0f} : std::array{0.0f, -1.0f, 0.0f};
    const std::array<float, 3> normal = o.plane == GridPlane::horizontal ? std::array{0.0f, -1.0f, 0.0f}
                                                                       : std::array{0.0f, 0.0f, -1.0f};
    const float half_gap = o.copy ? 0.5f * o.gap : 0.0f;
    // Positions relative to o.centre, the frame's origin (Cloth::origin, set below).
    for (int k = 0; k < 3; ++k)
        frame.origin[k] = -cu * frame.axis_u[k] - cv * frame.axis_v[k] - half_gap * normal[k];
    OutlinePanelParams op;
    op.spacing = o.spacing;
    op.areal_density = s.model == MaterialModel::fabric ? s.fabric.density : o.density;
    GarmentAssembly a;
    // Panel errors the file could not be checked for before triangulating (an outline too thin for its
    // spacing) name the file and the fields.
    const auto panel = [&](const PanelFrame& f) {
        try {
            return add_outline_panel(a, o.outline, op, f);
        } catch (const InvalidInput& e) {
            throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + ": cloth.outline at cloth.spacing = " +
                               format_number(o.spacing) + " m: " + e.what());
        }
    };
    const OutlinePanelBuild front = panel(frame);
    if (o.copy) {
        PanelFrame back = frame;
        for (int k = 0; k < 3; ++k) back.origin[k] += 2.0f * half_gap * normal[k];
        const OutlinePanelBuild rear = panel(back);
        for (const auto& [from, to] : o.sew) {
            const OutlineStretch stretch{from, to, false};
            sew_by_arc_length(a, outline_stretch_particles(front, stretch), outline_stretch_particles(rear, stretch),
                              o.seam_rest_ratio * o.spacing);
        }
    }
    std::vector<float> inv_mass = a.inverse_masses();
    const std::vector<float> free_inv_mass = inv_mass;
    if (o.pin_top) { // the particles along the top (vertical) or the far edge (horizontal: largest z)
        const bool vertical = o.plane == GridPlane::vertical;
        float top = -1e30f;
        for (std::size_t i = 0; i < a.particle_count(); ++i) top = std::max(top, vertical ? a.y[i] : a.z[i]);
        for (std::size_t i = 0; i < a.particle_count(); ++i)
            if ((vertical ? a.y[i] : a.z[i]) >= top - 0.25f * o.spacing) inv_mass[i] = 0.0f;
    }
    try {
        cook_assembly(s, a, inv_mass, free_inv_mass, out);
    } catch (const NeedleTriangleError& e) {
        refuse_outline_needle(s, a, cu, cv, e);
    }
    out.cloth.origin = {double(o.centre[0]), double(o.centre[1]), double(o.centre[2])};
}

/// A cloth of the fabric model that its builder can make at any spacing (an outline) rebuilds itself at
/// 2^level times its spacing for the implicit solver's coarse levels (Cloth::coarsen); `build(level)` makes that copy
/// (nullopt where the builder refuses it: too coarse). Both copies lie where they were built (flat panels), so the
/// maps between them are taken there: the closest point on the other copy's triangles (surface_transfer); the
/// cloth's own built layout is kept for it.
void set_rebuild_coarsen(BuiltScene& out, std::function<std::optional<BuiltScene>(std::uint32_t level)> build) {
    struct Layout {
        std::vector<float> x, y, z;
        std::vector<std::uint32_t> triangles;
    };
    auto fine = std::make_shared<const Layout>(Layout{out.initial.x, out.initial.y, out.initial.z, out.cloth.triangles});
    out.cloth.coarsen = [build = std::move(build), fine](std::uint32_t level) -> std::optional<CoarseCloth> {
        if (level == 0 || level > 16) return std::nullopt;
        const auto attempt = [&](std::uint32_t k) -> std::optional<BuiltScene> {
            try {
                return build(k);
            } catch (const InvalidInput&) { // too coarse for the builder: no such level
                return std::nullopt;
            }
        };
        std::optional<BuiltScene> coarse = attempt(level);
        if (!coarse) return std::nullopt;
        std::optional<BuiltScene> finer;
        if (level > 1 && !(finer = attempt(level - 1))) return std::nullopt;
        const std::vector<float>& fx = finer ? finer->initial.x : fine->x;
        const std::vector<float>& fy = finer ? finer->initial.y : fine->y;
        const std::vector<float>& fz = finer ? finer->initial.z : fine->z;
        const InitialState& c = coarse->initial;
        CoarseCloth copy;
        copy.from_fine = surface_transfer(fine->x, fine->y, fine->z, fine->triangles, c.x, c.y, c.z);
        copy.to_finer = surface_transfer(c.x, c.y, c.z, coarse->cloth.triangles, fx, fy, fz);
        copy.x = c.x;
        copy.y = c.y;
        copy.z = c.z;
        copy.cloth = std::move(coarse->cloth);
        return copy;
    };
}

BuiltScene build_scene_body(const SceneSpec& s) {
    BuiltScene out;
    if (s.cloth == ClothType::grid) {
        HangParams g = s.grid;
        g.stiffness = s.stiffness;
        g.shear_ratio = s.shear_ratio;
        g.bend_ratio = s.bend_ratio;
        g.damping_ratio = s.damping_ratio;
        g.model = s.model;
        g.fabric = s.fabric;
        SceneBuild b = build_hang_scene(g);
        out.cloth = std::move(b.cloth);
        out.initial = std::move(b.initial);
    } else if (s.cloth == ClothType::outline) {
        build_outline_cloth(s, out);
        if (s.model == MaterialModel::fabric) {
            SceneSpec base = s; // what the rebuilds need (not a saved state's arrays)
            base.state.reset();
            set_rebuild_coarsen(out, [base](std::uint32_t k) {
                const SceneSpec& s = base;
                SceneSpec c = s;
                c.outline.spacing = s.outline.spacing * float(1u << k);
                c.outline.seam_rest_ratio = s.outline.seam_rest_ratio / float(1u << k); // the seams' own rest length
                BuiltScene b;
                build_outline_cloth(c, b);
                return std::optional<BuiltScene>(std::move(b));
            });
        }
    } else if (s.cloth == ClothType::mask) {
        build_mask_cloth(s, out);
    } else if (s.cloth == ClothType::mesh) {
        const MeshClothSpec& m = s.mesh;
        if (!m.mesh) throw InvalidInput("mesh cloth: no mesh loaded (cloth.file)");
        GarmentAssembly a;
        // Positions relative to m.centre, the cloth's origin (Cloth::origin, set below).
        add_mesh_panel(a, *m.mesh,
                       {m.scale, {0.0f, 0.0f, 0.0f}, s.model == MaterialModel::fabric ? s.fabric.density : m.density});
        // Sizes float arithmetic can carry: a mesh of 1e30 m gave inf areas (node mass 0, strain inf) and NaN
        // normals with exit 0; two vertices 1e-7 apart gave a spring stiffness scale of 6e6 and a default dt of 0.
        double extent = 0.0, shortest = std::numeric_limits<double>::max();
        for (std::size_t i = 0; i < a.particle_count(); ++i)
            extent = std::max({extent, std::fabs(double(a.x[i])), std::fabs(double(a.y[i])), std::fabs(double(a.z[i]))});
        for (const Edge& e : a.edges) // the triangles' edges (bend springs join opposite vertices, not edges)
            if (e.kind == SpringKind::structural || e.kind == SpringKind::shear) shortest = std::min(shortest, double(e.rest));
        if (!(extent <= 1e4))
            throw InvalidInput(s.source + ": cloth.file: the mesh reaches " + format_number(extent) +
                               " m from its centre after cloth.scale (at most 1e4 m): lower cloth.scale");
        if (shortest != std::numeric_limits<double>::max() && !(shortest >= 1e-5))
            throw InvalidInput(s.source + ": cloth.file: the mesh's shortest edge is " + format_number(shortest) +
                               " m after cloth.scale (at least 1e-5 m): weld vertices that nearly coincide, or raise "
                               "cloth.scale");
        std::vector<float> inv_mass = a.inverse_masses();
        const std::vector<float> free_inv_mass = inv_mass;
        if (m.pins == MeshPins::top) {
            const std::vector<std::uint32_t> top = mesh_top_particles(*m.mesh);
            // A mesh lying flat and level has every vertex at its top: nothing would move.
            if (top.size() == a.particle_count())
                throw InvalidInput(s.source + ": cloth.pins = \"top\" would pin every particle of this mesh (all " +
                                   std::to_string(top.size()) + " are at its top: it lies flat and level); use "
                                   "\"none\", a list of vertex indices, or stand the mesh up");
            for (std::uint32_t i : top) inv_mass[i] = 0.0f;
        }
        for (std::uint32_t v : m.pin_vertices) inv_mass[static_cast<std::size_t>(m.mesh->particle_of_vertex.at(v))] = 0.0f;
        // An OBJ's edges need not follow any weave: the unaligned membrane (triangle_fabric.hpp); u = the file's x.
        try {
            cook_assembly(s, a, inv_mass, free_inv_mass, out, {1.0f, 0.0f, 0.0f}, WeaveAlignment::unaligned);
        } catch (const NeedleTriangleError& e) { // the assembly's particles are the mesh's, in order
            refuse_mesh_needle(s, *m.mesh, e);
        }
        out.cloth.origin = {double(m.centre[0]), double(m.centre[1]), double(m.centre[2])};
    } else if (s.model == MaterialModel::fabric) {
        // Fabric: node masses from the fabric's density and the panels' triangles (TShirtParams::total_mass is not
        // used); a particle in no triangle gets a third of a half cell. Both panels' u is +-x (mask columns). No coarse
        // levels: tried (rebuilt at half the cells per metre), the shirt settled less symmetric at the seed's 35
        // cells/m (docs/implicit.md, "Outline cloths on their coarse levels").
        TShirtBuild t = build_tshirt(s.tshirt);
        GarmentAssembly& a = t.assembly;
        const std::vector<double> m = lumped_masses(a.x, a.y, a.z, a.triangles, s.fabric.density);
        const double lone = double(s.fabric.density) * t.spacing * t.spacing / 6.0;
        for (std::size_t i = 0; i < a.particle_count(); ++i) a.mass[i] = float(m[i] > 0.0 ? m[i] : lone);
        const std::vector<float> inv_mass = a.inverse_masses();
        cook_assembly(s, a, inv_mass, inv_mass, out);
        out.cloth.free_inv_mass.clear();
    } else {
        const TShirtBuild t = build_tshirt(s.tshirt);
        const GarmentAssembly& a = t.assembly;
        const float mass = s.tshirt.total_mass / static_cast<float>(a.particle_count());
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mass * 0.5f)};
        out.cloth = cook_cloth(a.inverse_masses(), a.edges, material);
        out.cloth.triangles = a.triangles;
        out.initial = a.initial_state();
    }
    out.params = s.physics;
    if (s.body) {
        const std::vector<Collider> body = default_body();
        out.params.colliders.insert(out.params.colliders.end(), body.begin(), body.end());
    }
    // The colliders into the cloth's frame (positions relative to Cloth::origin, the cloth's centre).
    const std::array<double, 3>& origin = out.cloth.origin;
    for (Collider& c : out.params.colliders)
        c = translated(c, {-origin[0], -origin[1], -origin[2]});
    // The implicit solver's default step is a frame (any length is stable); the explicit one's 0.9 x the bound.
    out.params.dt = s.dt                                     ? *s.dt
                    : out.params.solver == Solver::implicit ? implicit_default_dt
                                                            : static_cast<float>(default_dt(out.cloth, out.params));
    if (s.state) apply_state(*s.state, out);
    return out;
}
} // namespace

BuiltScene build_scene(const SceneSpec& s) {
    // Every error names the scene: the build's own checks (the fabric's constants, a saved state's size) do not know
    // the file (the fuzzer found "fabric.shear = 40 N/m is too large ..." without it).
    const std::string name = s.source.empty() ? std::string("scene") : s.source;
    try {
        return build_scene_body(s);
    } catch (const InvalidInput& e) {
        const std::string message = e.what();
        if (message.compare(0, name.size() + 2, name + ": ") == 0) throw;
        throw InvalidInput(name + ": " + message);
    }
}

} // namespace drape
