// Strict reading of JSON configuration files (scenario files, expectations).
//
// Every error is a JsonError whose message starts with the path of the offending key,
// e.g. "stages[2].segments[0].duration: must be a number in (0, 3600], got -1".
//  - parse_json_text(): syntax errors, truncated input, number overflow (1e400) and
//    duplicate keys are reported with the path being parsed (and line/column).
//    Comments (// and /* */) are allowed and ignored, so configuration files can be
//    annotated; nothing else beyond standard JSON is accepted.
//  - ObjectReader: reads the keys of one JSON object with a default for every optional
//    key, checks types (a string such as "NaN" or "inf" is not a number, 1.5 is not an
//    integer) and closed/open ranges, and finish() rejects any key that was not read,
//    listing the accepted ones. JSON has no NaN or infinity; numbers that parse to a
//    non-finite double are rejected.
#pragma once

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace inhand::examples {

using Json = nlohmann::json;

/// A configuration error; what() = "<path>: <reason>".
class JsonError : public std::runtime_error {
 public:
  JsonError(const std::string& path, const std::string& reason)
      : std::runtime_error(path.empty() ? reason : path + ": " + reason),
        path_(path),
        reason_(reason) {}
  const std::string& path() const noexcept { return path_; }
  const std::string& reason() const noexcept { return reason_; }

 private:
  std::string path_, reason_;
};

/// Numeric range [lo, hi] with optionally open ends.
struct Range {
  double lo = -std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::max();
  bool lo_open = false;
  bool hi_open = false;

  static Range closed(double a, double b) { return Range{a, b, false, false}; }
  /// (a, b]
  static Range positive_up_to(double b) { return Range{0.0, b, true, false}; }
  /// [0, b]
  static Range non_negative_up_to(double b) { return Range{0.0, b, false, false}; }
  bool contains(double x) const noexcept {
    return std::isfinite(x) && (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  std::string describe() const {
    return std::string(lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
           (hi_open ? ")" : "]");
  }
  static std::string format_number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", x);
    return buf;
  }
};

namespace detail {
/// Tracks where the parser is (for messages) and rejects duplicate keys.
class ParsePathTracker {
 public:
  bool on_event(Json::parse_event_t e, const Json& parsed) {
    switch (e) {
      case Json::parse_event_t::object_start:
      case Json::parse_event_t::array_start:
        if (!frames_.empty() && frames_.back().array) ++frames_.back().count;
        frames_.push_back(Frame{e == Json::parse_event_t::array_start, false, 0, {}, {}});
        break;
      case Json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        f.value_done = false;
        if (!f.keys.insert(f.key).second) throw JsonError(path(), "duplicate key");
        break;
      }
      case Json::parse_event_t::value:
        if (!frames_.empty()) {
          if (frames_.back().array) ++frames_.back().count;
          frames_.back().value_done = true;
        }
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!frames_.empty()) frames_.pop_back();
        if (!frames_.empty()) frames_.back().value_done = true;
        break;
    }
    return true;
  }
  /// Path of the value being parsed now.
  std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      if (f.array) {
        // An enclosing array counted its element when the element started; the
        // innermost one counts a plain value only once it has been read.
        const long idx = i + 1 < frames_.size() ? f.count - 1 : f.count;
        p += "[" + std::to_string(idx) + "]";
      } else if (!f.key.empty() && !(i + 1 == frames_.size() && f.value_done)) {
        // (Between two keys of the innermost object the object itself is meant.)
        if (!p.empty()) p += ".";
        p += f.key;
      }
    }
    return p;
  }

 private:
  struct Frame {
    bool array = false;
    bool value_done = false;  ///< the value of `key` has been read
    long count = 0;
    std::string key;
    std::set<std::string> keys;
  };
  std::vector<Frame> frames_;
};

inline std::string strip_json_exception_prefix(const std::string& what) {
  // "[json.exception.parse_error.101] parse error at ..." -> "parse error at ..."
  if (!what.empty() && what.front() == '[') {
    const std::size_t close = what.find("] ");
    if (close != std::string::npos) return what.substr(close + 2);
  }
  return what;
}
}  // namespace detail

/// Parses JSON text (comments allowed); throws JsonError naming where parsing failed.
inline Json parse_json_text(const std::string& text) {
  detail::ParsePathTracker tracker;
  try {
    return Json::parse(
        text,
        [&tracker](int, Json::parse_event_t e, Json& parsed) {
          return tracker.on_event(e, parsed);
        },
        /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const JsonError&) {
    throw;
  } catch (const Json::exception& e) {
    const std::string where = tracker.path();
    throw JsonError(where.empty() ? std::string("(document)") : where,
                    "malformed JSON: " + detail::strip_json_exception_prefix(e.what()));
  }
}

/// Reads and parses a JSON file; error messages start with the file name.
inline Json load_json_file(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw JsonError(file, "cannot open the file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw JsonError(file, "cannot read the file");
  return parse_json_text(ss.str());
}

inline std::string json_type_name(const Json& j) {
  if (j.is_string()) return "string " + j.dump();
  if (j.is_number()) return "number " + j.dump();
  return j.type_name();
}

/// Reads the keys of one JSON object; see the file comment.
class ObjectReader {
 public:
  ObjectReader(const Json& j, std::string path) : j_(&j), path_(std::move(path)) {
    if (!j.is_object())
      throw JsonError(path_.empty() ? "(document)" : path_,
                      "must be an object, got " + json_type_name(j));
  }

  const std::string& path() const noexcept { return path_; }
  std::string key_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  bool has(const std::string& key) const { return j_->contains(key); }
  /// The raw value (marks the key as read); nullptr when absent.
  const Json* raw(const std::string& key) {
    seen_.insert(key);
    const auto it = j_->find(key);
    return it == j_->end() ? nullptr : &*it;
  }

  double number(const std::string& key, double fallback, const Range& r) {
    const Json* v = raw(key);
    return v == nullptr ? fallback : as_number(*v, key_path(key), r);
  }
  double required_number(const std::string& key, const Range& r) {
    return as_number(required(key), key_path(key), r);
  }
  /// A limit: a number in r, or null for "no limit" (+infinity).
  double limit(const std::string& key, double fallback, const Range& r) {
    const Json* v = raw(key);
    if (v == nullptr) return fallback;
    if (v->is_null()) return std::numeric_limits<double>::infinity();
    return as_number(*v, key_path(key), r);
  }
  long long integer(const std::string& key, long long fallback, long long lo, long long hi) {
    const Json* v = raw(key);
    return v == nullptr ? fallback : as_integer(*v, key_path(key), lo, hi);
  }
  bool boolean(const std::string& key, bool fallback) {
    const Json* v = raw(key);
    if (v == nullptr) return fallback;
    if (!v->is_boolean())
      throw JsonError(key_path(key), "must be true or false, got " + json_type_name(*v));
    return v->get<bool>();
  }
  std::optional<bool> optional_boolean(const std::string& key) {
    if (!has(key)) {
      seen_.insert(key);
      return std::nullopt;
    }
    return boolean(key, false);
  }
  std::optional<double> optional_number(const std::string& key, const Range& r) {
    const Json* v = raw(key);
    if (v == nullptr) return std::nullopt;
    return as_number(*v, key_path(key), r);
  }
  std::string string(const std::string& key, const std::string& fallback) {
    const Json* v = raw(key);
    if (v == nullptr) return fallback;
    if (!v->is_string())
      throw JsonError(key_path(key), "must be a string, got " + json_type_name(*v));
    return v->get<std::string>();
  }
  std::string required_string(const std::string& key) {
    const Json& v = required(key);
    if (!v.is_string())
      throw JsonError(key_path(key), "must be a string, got " + json_type_name(v));
    return v.get<std::string>();
  }
  /// One of `choices`.
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& choices, bool is_required = false) {
    if (is_required) required(key);
    const std::string s = string(key, fallback);
    for (const std::string& c : choices)
      if (s == c) return s;
    throw JsonError(key_path(key), "must be one of " + join(choices) + ", got \"" + s + "\"");
  }
  /// An array of exactly n numbers, each in r.
  std::vector<double> numbers(const std::string& key, std::vector<double> fallback, std::size_t n,
                              const Range& r, bool is_required = false) {
    if (is_required) required(key);
    const Json* v = raw(key);
    if (v == nullptr) return fallback;
    const std::string p = key_path(key);
    if (!v->is_array() || v->size() != n)
      throw JsonError(
          p, "must be an array of " + std::to_string(n) + " numbers, got " + json_type_name(*v));
    std::vector<double> out;
    for (std::size_t i = 0; i < n; ++i)
      out.push_back(as_number((*v)[i], p + "[" + std::to_string(i) + "]", r));
    return out;
  }
  /// A nested object (absent: an empty object, so its defaults apply).
  ObjectReader object(const std::string& key) {
    const Json* v = raw(key);
    static const Json empty = Json::object();
    return ObjectReader(v == nullptr ? empty : *v, key_path(key));
  }
  /// A required array; returns it (elements are read by the caller).
  const Json& array(const std::string& key, bool is_required) {
    static const Json empty = Json::array();
    if (is_required) required(key);
    const Json* v = raw(key);
    if (v == nullptr) return empty;
    if (!v->is_array())
      throw JsonError(key_path(key), "must be an array, got " + json_type_name(*v));
    return *v;
  }

  /// Rejects keys that were never read.
  void finish() const {
    for (auto it = j_->begin(); it != j_->end(); ++it) {
      if (seen_.count(it.key()) == 0) {
        std::vector<std::string> known(seen_.begin(), seen_.end());
        throw JsonError(key_path(it.key()), "unknown key (accepted here: " + join(known) + ")");
      }
    }
  }

  static double as_number(const Json& v, const std::string& path, const Range& r) {
    if (!v.is_number())
      throw JsonError(path, "must be a number in " + r.describe() + ", got " + json_type_name(v));
    const double x = v.get<double>();
    if (!r.contains(x))
      throw JsonError(path, "must be a number in " + r.describe() + ", got " + v.dump());
    return x;
  }
  static long long as_integer(const Json& v, const std::string& path, long long lo, long long hi) {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (v.is_number_unsigned()) {
      const auto u = v.get<unsigned long long>();
      if (u > static_cast<unsigned long long>(hi) ||
          (lo > 0 && u < static_cast<unsigned long long>(lo)))
        throw JsonError(path, "must be an integer in " + range + ", got " + v.dump());
      return static_cast<long long>(u);
    }
    if (!v.is_number_integer())
      throw JsonError(path, "must be an integer in " + range + ", got " + json_type_name(v));
    const auto x = v.get<long long>();
    if (x < lo || x > hi)
      throw JsonError(path, "must be an integer in " + range + ", got " + v.dump());
    return x;
  }

 private:
  const Json& required(const std::string& key) {
    const Json* v = raw(key);
    if (v == nullptr) throw JsonError(key_path(key), "required key is missing");
    return *v;
  }
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
  }

  const Json* j_;
  std::string path_;
  std::set<std::string> seen_;
};

/// "<base>[i]"
inline std::string index_path(const std::string& base, std::size_t i) {
  return base + "[" + std::to_string(i) + "]";
}

}  // namespace inhand::examples
