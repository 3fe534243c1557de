// Small text helpers shared by the readers and writers: file-name parts for one-line error
// messages, reading a whole input file, and the shortest round-trip form of a double.
#pragma once

#include <cstdint>
#include <string>

#include "common/mesh.h"
#include "common/status.h"

namespace vobb {

// "dir/dino.off" -> "dino.off": error messages name the file, not the whole path.
std::string basename_of(const std::string& path);
// Lower-cased extension without the dot; "" when there is none.
std::string extension_of(const std::string& path);
// Whether `path` is a regular file, and its size. A folder, a FIFO or a device (/dev/zero) is
// refused before it is opened, since reading it would fail late, block forever or never end.
// Failures are one line: "<display>: <reason>", where the reason is "cannot open:
// <strerror>", "is a directory, not a <what>" or "not a regular file".
Status check_regular_file(const std::string& path, const std::string& display,
                          const std::string& what, uint64_t* size);

// Whether nothing is at `path` (stat fails with ENOENT or ENOTDIR): a checkpoint not yet saved.
// Anything else there, or a path that cannot be checked, is not absent, so that reading it
// reports why.
bool path_absent(const std::string& path);

// Reads the whole of `path` into `content`, after check_regular_file; a short read is
// "<display>: read error". `text`: the file must be text, so its first kTextProbeBytes are read
// first, and a NUL byte among them refuses it ("<display>: binary data in a text format")
// before the rest is read: a large binary file is not read whole to be refused. `content`
// then holds those first bytes, for the caller to say what the file looks like.
inline constexpr size_t kTextProbeBytes = 1 << 16;
Status read_regular_file(const std::string& path, const std::string& display,
                         const std::string& what, std::string* content, bool text = false);

// Appends the shortest decimal form that reads back as the same double (std::to_chars).
void append_double(std::string* s, double v);
// The same form as a string.
std::string format_double(double v);
// Appends "x y z" with append_double, and no newline.
void append_xyz(std::string* s, const Vec3& v);

}  // namespace vobb
