#include "common/text_util.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>

namespace vobb {

std::string basename_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

Status check_regular_file(const std::string& path, const std::string& display,
                          const std::string& what, uint64_t* size) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    return Status::error(display + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) return Status::error(display + ": is a directory, not a " + what);
  if (!S_ISREG(st.st_mode)) return Status::error(display + ": not a regular file");
  *size = static_cast<uint64_t>(st.st_size);
  return Status::ok();
}

bool path_absent(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) != 0 && (errno == ENOENT || errno == ENOTDIR);
}

Status read_regular_file(const std::string& path, const std::string& display,
                         const std::string& what, std::string* content, bool text) {
  uint64_t size = 0;
  const Status regular = check_regular_file(path, display, what, &size);
  if (!regular) return regular;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::error(display + ": cannot open: " + std::strerror(errno));
  auto read_to = [&](size_t from, size_t to) {
    content->resize(to);
    in.read(content->data() + from, static_cast<std::streamsize>(to - from));
    return static_cast<size_t>(in.gcount()) == to - from;
  };
  const size_t probe = text ? static_cast<size_t>(std::min<uint64_t>(size, kTextProbeBytes)) : 0;
  if (!read_to(0, probe)) return Status::error(display + ": read error");
  if (content->find('\0') != std::string::npos)
    return Status::error(display + ": binary data in a text format");
  if (!read_to(probe, static_cast<size_t>(size))) return Status::error(display + ": read error");
  return Status::ok();
}

std::string extension_of(const std::string& path) {
  const std::string base = basename_of(path);
  const size_t dot = base.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string e = base.substr(dot + 1);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

void append_double(std::string* s, double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  s->append(buf, res.ptr);
}

std::string format_double(double v) {
  std::string s;
  append_double(&s, v);
  return s;
}

void append_xyz(std::string* s, const Vec3& v) {
  append_double(s, v[0]);
  *s += ' ';
  append_double(s, v[1]);
  *s += ' ';
  append_double(s, v[2]);
}

}  // namespace vobb
