// JSON read from files, parsed without letting a document nest deeper than its format can.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "common/sha256.h"

namespace vobb {

// The checksum our checkpoint files carry in "sha256": the SHA-256 of the document without that
// field, as nlohmann dumps it (keys sorted, doubles in digits that read back exactly), so that
// parsing a saved file and dumping it again gives the bytes that were hashed.
template <class Json>
std::string json_checksum(Json j) {
  j.erase("sha256");
  const std::string body = j.dump();
  return sha256_hex(body.data(), body.size());
}

// Whether `v` is an integer within [lo, hi], and then its value. nlohmann keeps an integer above
// INT64_MAX as unsigned, which get<int64_t> would wrap to a negative one (2^64 - 1 to -1).
template <class Json>
bool json_integer_in(const Json& v, int64_t lo, int64_t hi, int64_t* out) {
  if (!v.is_number_integer()) return false;
  int64_t x = 0;
  if (v.is_number_unsigned()) {
    const uint64_t u = v.template get<uint64_t>();
    if (u > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return false;
    x = static_cast<int64_t>(u);
  } else {
    x = v.template get<int64_t>();
  }
  if (x < lo || x > hi) return false;
  *out = x;
  return true;
}

// Parses `text` into *out. False, with *out reset, when it is not JSON, when arrays and
// objects nest deeper than `max_depth` (the top level is depth 0; *too_deep, when given, says
// so), or when an object holds a key twice (*twice, when given, gets the key): JSON leaves
// what such a document means to the reader, so it is refused rather than read one way. No file
// of ours nests deeper than a few levels, and a document nested some 10^5
// deep, though nlohmann parses and frees it without recursion, overflows the stack when
// copied or written out (a checksum over it, say). The depth is checked first by a SAX pass
// that stops at the first container too deep; both passes take time linear in the text
// (nlohmann's callback parser, the other way to cut depth, searches a container for
// discarded values after each object in it: quadratic in an array of objects).
template <class Json>
bool parse_json_within(const std::string& text, int max_depth, Json* out, bool* too_deep = nullptr,
                       std::string* twice = nullptr) {
  struct DepthCheck : nlohmann::json_sax<Json> {
    int max_depth = 0, depth = 0;
    bool deep = false;
    std::vector<std::set<std::string>> keys;  // of each object open, innermost last
    std::string repeated;
    bool open() {
      if (depth > max_depth) {
        deep = true;
        return false;  // stops the parse
      }
      ++depth;
      return true;
    }
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(typename Json::number_integer_t) override { return true; }
    bool number_unsigned(typename Json::number_unsigned_t) override { return true; }
    bool number_float(typename Json::number_float_t, const typename Json::string_t&) override {
      return true;
    }
    bool string(typename Json::string_t&) override { return true; }
    bool binary(typename Json::binary_t&) override { return true; }
    bool start_object(std::size_t) override { return keys.emplace_back(), open(); }
    bool key(typename Json::string_t& k) override {
      if (keys.back().insert(k).second) return true;
      repeated = k;
      return false;  // stops the parse
    }
    bool end_object() override { return keys.pop_back(), --depth, true; }
    bool start_array(std::size_t) override { return open(); }
    bool end_array() override { return --depth, true; }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
      return false;
    }
  } check;
  check.max_depth = max_depth;
  const bool parsed = Json::sax_parse(text, &check);
  if (too_deep) *too_deep = check.deep;
  if (twice) *twice = check.repeated;
  if (!parsed || check.deep) {
    *out = Json();
    return false;
  }
  *out = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  return !out->is_discarded();
}

// The one-line reason parse_json_within refused `kind` ("a tree file"), from what it said.
inline std::string json_refusal(bool too_deep, const std::string& twice, const std::string& kind) {
  if (too_deep) return "nested deeper than " + kind + " can be";
  if (twice.empty()) return "not valid JSON";
  // The key as JSON writes it in ASCII (quoted, escaped: one line), cut short if long.
  std::string quoted =
      nlohmann::json(twice).dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
  if (quoted.size() > 64) quoted = quoted.substr(0, 60) + "...\"";
  return "the key " + quoted + " twice in one object";
}

}  // namespace vobb
