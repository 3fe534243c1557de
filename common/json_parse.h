// JSON read from files, parsed without letting a document nest deeper than its format can.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace vobb {

// Parses `text` into *out. False when it is not JSON, or when arrays and objects nest deeper
// than `max_depth` (the top level is depth 0): no file of ours nests deeper than a few levels,
// and a document nested some 10^5 deep, though parsed and freed without recursion, overflows
// the stack when copied or written out (a checksum over it, say). Its nested values are left
// out of *out as they are parsed, so *out itself never gets deep.
template <class Json>
bool parse_json_within(const std::string& text, int max_depth, Json* out) {
  bool too_deep = false;
  *out = Json::parse(
      text,
      [&](int depth, typename Json::parse_event_t event, Json&) {
        if ((event == Json::parse_event_t::object_start || event == Json::parse_event_t::array_start) &&
            depth > max_depth) {
          too_deep = true;
          return false;  // keep none of it
        }
        return true;
      },
      /*allow_exceptions=*/false);
  return !too_deep && !out->is_discarded();
}

}  // namespace vobb
