// CLI11 validators the subcommands share: CLI::Range lets NaN through (every comparison with
// it is false), and an unsigned option takes "-1" as 2^64 - 1, so numbers are checked here.
#pragma once

#include <CLI/CLI.hpp>

#include <cctype>
#include <cmath>
#include <string>

namespace vobb::app {

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
      if (s.empty() || s.size() > 20) return "seed '" + s + "' is not an integer in [0, 2^64 - 1]";
      for (char c : s)
        if (!std::isdigit(static_cast<unsigned char>(c))) return "seed '" + s + "' is not an integer in [0, 2^64 - 1]";
      if (s.size() == 20 && s > "18446744073709551615") return "seed '" + s + "' is not an integer in [0, 2^64 - 1]";
      return "";
    },
    "SEED");

}  // namespace vobb::app
