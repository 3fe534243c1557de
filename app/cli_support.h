// What the subcommands share: exit codes, the one-line error, and CLI11 validators.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "common/io/mesh_io.h"
#include "common/io/mesh_report.h"
#include "common/status.h"
#include "common/text_util.h"

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
// link) would replace it (`build dino.off -o dino.off` would turn the mesh into a tree), so it
// is refused before anything runs. An output that does not exist yet cannot be an input.
inline Status check_output_is_not_input(const std::string& option, const std::string& output,
                                        const std::vector<std::string>& inputs) {
  if (output.empty()) return Status::ok();
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (std::filesystem::equivalent(output, in, ec) && !ec)
      return Status::error(option + " " + output + ": is the input file " + in +
                           "; choose another output");
  }
  return Status::ok();
}

// An output that names one of the run's own checkpoint files (`names`, relative to `folder`),
// existing yet or not, would be written over it at the end of the run and refuse every resume;
// one that names the checkpoint folder, a folder of those files, or a folder above them would
// be made a folder by the run and fail at its end. Both are compared as absolute paths with
// links and dot parts resolved as far as they exist.
inline Status check_output_is_not_checkpoint(const std::string& option, const std::string& output,
                                             const std::string& folder,
                                             const std::vector<std::string>& names) {
  namespace fs = std::filesystem;
  if (output.empty() || folder.empty()) return Status::ok();
  std::string followed;
  if (!output_target(output, &followed)) return Status::ok();  // check_output_is_writable says why
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(followed, ec), ec);
  if (ec) return Status::ok();
  for (const std::string& name : names) {
    const fs::path own = fs::weakly_canonical(fs::absolute(fs::path(folder) / name, ec), ec);
    if (ec) continue;
    if (own == out)
      return Status::error(option + " " + output + ": is this run's checkpoint file " +
                           (fs::path(folder) / name).string() + "; choose another output");
    for (fs::path above = own.parent_path(); !above.empty(); above = above.parent_path()) {
      if (above == out)
        return Status::error(option + " " + output + ": is a folder of this run's checkpoint " +
                             folder + "; choose another output");
      if (above == above.parent_path()) break;
    }
  }
  return Status::ok();
}

// Two outputs of one run that name the same file, existing yet or not (links followed, paths
// made absolute), would have the second written over the first.
inline Status check_outputs_differ(const std::string& option, const std::string& output,
                                   const std::string& other_option, const std::string& other) {
  namespace fs = std::filesystem;
  if (output.empty() || other.empty()) return Status::ok();
  std::string a, b;
  if (!output_target(output, &a) || !output_target(other, &b))
    return Status::ok();  // check_output_is_writable says why
  std::error_code ec1, ec2;
  const fs::path pa = fs::weakly_canonical(fs::absolute(a, ec1), ec1);
  const fs::path pb = fs::weakly_canonical(fs::absolute(b, ec2), ec2);
  if (!ec1 && !ec2 && pa == pb)
    return Status::error(option + " " + output + ": is also the file of " + other_option +
                         "; choose another output");
  return Status::ok();
}

// An output that cannot be written is refused before the run, not after hours of it. Paths
// are resolved as write_file_atomic resolves them (common/atomic_file.h): a folder is no
// output; a device or pipe, also through a link (/dev/stdout), is written in place and passes.
// A named pipe is not opened here, since its reader would take the probe's close for the end
// of the stream; one that no process opens for reading within a few seconds of the write, like
// a full disk, shows only when writing, and the run then ends with could_not_finish. Otherwise,
// following a link, the folder that will hold the file must exist and take a new file (a
// probe is made there and removed), and the file's name must fit the folder's file system.
inline Status check_output_is_writable(const std::string& option, const std::string& output) {
  namespace fs = std::filesystem;
  if (output.empty()) return Status::ok();
  std::error_code ec;
  const fs::file_status st = fs::status(output, ec);
  if (fs::is_directory(st))
    return Status::error(option + " " + output + ": is a folder; name a file");
  if (fs::exists(st) && !fs::is_regular_file(st)) return Status::ok();
  std::string followed;
  if (Status s = output_target(output, &followed); !s)
    return Status::error(option + " " + s.message());
  const fs::path target(followed);
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir, ec))
    return Status::error(option + " " + output + ": " + vobb::not_a_folder(dir.string()));
  const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  if (name_max > 0 && target.filename().string().size() > static_cast<size_t>(name_max))
    return Status::error(option + " " + output + ": file name longer than the " +
                         std::to_string(name_max) + " bytes its folder takes");
  return vobb::check_folder_takes_files(option + " " + output, dir.string());
}

// The run could not finish for a reason that is not its input (its output could be written
// when it started, and then could not: a full disk): one line on stderr, exit code 3.
inline int could_not_finish(const Status& s) {
  std::fprintf(stderr, "vobb: %s\n", one_line(s.message()).c_str());
  return kExitCouldNotFinish;
}

// Every command that reads a mesh says on stderr when it was read in single precision
// (through assimp: float32 coordinates, DESIGN §3), since its results are then those of the
// rounded mesh, not of the numbers in the file. The line is said when the run ends with its
// results (exit 0 or 1, say_pending_notes), not at once: a run that then refuses its input
// (a tree of another mesh, a bad option) says that in its one line and nothing else.
inline std::string& pending_precision_note() {
  static std::string note;
  return note;
}
inline void note_precision(const std::string& path, const LoadedMesh& mesh) {
  if (!mesh.single_precision) return;
  pending_precision_note() = "vobb: " + one_line(basename_of(path)) +
                             ": read in single precision through assimp (" + one_line(mesh.format) +
                             "): the results are for its coordinates rounded to float32; OFF, "
                             "OBJ, PLY and STL files are read as written\n";
}
// A command's mesh: read as a solid (load_solid), its single-precision read noted.
inline Status load_input_solid(const std::string& path, LoadedMesh* mesh) {
  const Status s = load_solid(path, mesh);
  if (s) note_precision(path, *mesh);
  return s;
}
inline void say_pending_notes() {
  std::string& note = pending_precision_note();
  if (note.empty()) return;
  std::fputs(note.c_str(), stderr);
  note.clear();
}

// CLI::Range lets NaN through (every comparison with it is false), and an unsigned option
// takes "-1" as 2^64 - 1, so numbers are checked here.

// Whether `s` is a number in decimal notation: an optional sign, digits with at most one point
// (a digit on one side of it at least), an optional exponent. strtod alone would also take
// hexadecimal ("0x10"), leading blanks, "inf" and "nan".
inline bool is_decimal_number(const std::string& s) {
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t from = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) != 0) ++i;
    return i - from;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == s.size();
}

// A finite number in decimal notation (no nan, inf, hexadecimal, blanks or text).
inline const CLI::Validator kFinite(
    [](std::string& s) -> std::string {
      if (!is_decimal_number(s)) return "'" + s + "' is not a number in decimal notation";
      char* end = nullptr;
      const double v = std::strtod(s.c_str(), &end);
      if (end == nullptr || *end != '\0') return "'" + s + "' is not a number";
      if (!std::isfinite(v)) return "'" + s + "' is not a finite number";
      return "";
    },
    "FINITE");

// A file or folder name given to an option: not empty ('-o ""' names nothing; refused before
// the run, not when its output is written).
inline const CLI::Validator kPath(
    [](std::string& s) -> std::string { return s.empty() ? "an empty name" : ""; }, "PATH");

// A count: decimal digits only (CLI11 would read "0x10" as 16, and "08" as a failed octal),
// leading zeros dropped; a range check follows it.
inline const CLI::Validator kCount(
    [](std::string& s) -> std::string {
      const bool digits = !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) {
        return std::isdigit(c) != 0;
      });
      if (!digits) return "'" + s + "' is not a whole number in decimal digits";
      s.erase(0, std::min(s.find_first_not_of('0'), s.size() - 1));
      return s.size() <= 10 ? "" : "'" + s + "' is out of range";
    },
    "COUNT");

// A comma-separated list of counts in [lo, hi], each in decimal digits; no element may be
// empty ("8,,16" names no resolution between 8 and 16). CLI11's own delimiter drops empty
// elements silently, so the list is taken whole: count_list checks it, split_counts reads it.
inline std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::size_t begin = 0;
  for (std::size_t end; (end = s.find(',', begin)) != std::string::npos; begin = end + 1)
    out.push_back(s.substr(begin, end - begin));
  out.push_back(s.substr(begin));
  return out;
}

inline std::vector<int> split_counts(const std::string& s) {
  std::vector<int> out;
  for (const std::string& item : split_commas(s)) out.push_back(std::stoi(item));
  return out;
}

inline CLI::Validator count_list(int lo, int hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        std::vector<int> seen;
        for (std::string item : split_commas(s)) {
          if (item.empty()) return "'" + s + "' has an empty element";
          if (const std::string bad = kCount(item); !bad.empty()) return bad;
          if (item.size() > 9 || std::stoi(item) < lo || std::stoi(item) > hi)
            return "'" + item + "' is not in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                   "]";
          // A count given twice would be computed twice.
          if (std::find(seen.begin(), seen.end(), std::stoi(item)) != seen.end())
            return "'" + s + "' lists " + std::to_string(std::stoi(item)) + " twice";
          seen.push_back(std::stoi(item));
        }
        return "";
      },
      "COUNT,...");
}

// A seed: decimal digits only, at most 2^64 - 1.
inline const CLI::Validator kSeed(
    [](std::string& s) -> std::string {
      const bool digits =
          !s.empty() && s.size() <= 20 &&
          std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
      if (!digits || (s.size() == 20 && s > "18446744073709551615"))
        return "seed '" + s + "' is not an integer in [0, 2^64 - 1]";
      return "";
    },
    "SEED");

}  // namespace vobb::app
