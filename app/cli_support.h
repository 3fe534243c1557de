// What the subcommands share: exit codes, the one-line error, and CLI11 validators.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/status.h"

namespace vobb::app {

// 3: the run could not finish for a reason that is not the input: out of memory, standard
// output not writable (a full disk), or a library's internal check. One line on stderr; files
// are written atomically, so none is left half-written.
constexpr int kExitOk = 0, kExitCheckFailed = 1, kExitBadInput = 2, kExitCouldNotFinish = 3;

// A message as one printable line: control characters (a newline in a file name, bytes of a
// binary file quoted in a parse error) become \xNN.
inline std::string one_line(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (unsigned char c : s) {
    if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

// A JSON report as printed: indented by 2, with bytes that are not UTF-8 (a file name may
// hold any) replaced by U+FFFD instead of throwing.
template <class Json>
std::string report_json(const Json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

// Bad input: one line on stderr, exit code 2.
inline int refuse(const Status& s) {
  std::fprintf(stderr, "vobb: %s\n", one_line(s.message()).c_str());
  return kExitBadInput;
}

// An output that names one of the run's input files (the same file by any path: "./x", a
// link) would replace it: `build dino.off -o dino.off` turned the mesh into a tree. Refused
// before anything runs. An output that does not exist yet cannot be an input.
inline Status check_output_is_not_input(const std::string& option, const std::string& output,
                                        const std::vector<std::string>& inputs) {
  if (output.empty()) return Status::ok();
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (std::filesystem::equivalent(output, in, ec) && !ec)
      return Status::error(option + " " + output + ": is the input file " + in + "; choose another output");
  }
  return Status::ok();
}

// CLI::Range lets NaN through (every comparison with it is false), and an unsigned option
// takes "-1" as 2^64 - 1, so numbers are checked here.

// A finite number (no nan, inf, or text).
inline const CLI::Validator kFinite(
    [](std::string& s) -> std::string {
      char* end = nullptr;
      const double v = std::strtod(s.c_str(), &end);
      if (s.empty() || end == nullptr || *end != '\0') return "'" + s + "' is not a number";
      if (!std::isfinite(v)) return "'" + s + "' is not a finite number";
      return "";
    },
    "FINITE");

// A seed: decimal digits only, at most 2^64 - 1.
inline const CLI::Validator kSeed(
    [](std::string& s) -> std::string {
      const bool digits = !s.empty() && s.size() <= 20 &&
                          std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
      if (!digits || (s.size() == 20 && s > "18446744073709551615"))
        return "seed '" + s + "' is not an integer in [0, 2^64 - 1]";
      return "";
    },
    "SEED");

}  // namespace vobb::app
