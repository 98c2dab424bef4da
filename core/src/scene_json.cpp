// Scene files' strict JSON reader (scene_json.hpp): nlohmann's SAX parser with the JSON path tracked, so that a
// duplicate key, too deep nesting or a number a double cannot hold is reported at its field.
#include "scene_json.hpp"

#include <cctype>
#include <cstdio>
#include <sstream>
#include <unordered_set>
#include <utility>

namespace drape {

namespace {

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

} // namespace

std::string format_number(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

std::string shorten(const std::string& s, std::size_t max_chars) {
    return s.size() <= max_chars ? s : s.substr(0, max_chars - 3) + "...";
}

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

} // namespace drape
