// The strict JSON reader of scene files: parse_json (duplicate keys, too deep nesting and non-finite numbers reported
// at their JSON path) and ObjectReader (typed, range-checked fields, unknown fields refused, messages naming the
// file and the JSON path). Internal to core: scene.cpp reads scenes with it.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "drape/errors.hpp"

namespace drape {

using json = nlohmann::json;

/// A number for messages, as an ostream writes a double ("0.001", "1e+06").
std::string format_number(double v);

/// JSON paths ("cloth.n", "physics.gravity[1]") of numbers the file writes but a double cannot hold (1e400, a 400-digit
/// integer) or that JSON does not have (NaN, Infinity), each with its text as written. The document holds 0 there;
/// the reader reports the value at its field, with the field's allowed range.
using NonFiniteNumbers = std::map<std::string, std::string>;

/// s itself, or its first max_chars - 3 characters and "...".
std::string shorten(const std::string& s, std::size_t max_chars = 40);

/// Text from the file (a key, a string value, a parser message) made fit for a one-line message: control characters
/// escaped (\u000a), and at most about max_chars long, cut in the middle ("cloth[0][0]...[0][0]") on character
/// boundaries.
std::string printable(const std::string& s, std::size_t max_chars);

/// Parses JSON text, turning non-finite numbers into null and recording them (at most 32: past that, the first one
/// is reported without its field's range). Any other error is "malformed JSON" naming where it is.
json parse_json(std::string text, const std::string& source, NonFiniteNumbers& non_finite);

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

} // namespace drape
