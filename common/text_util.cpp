#include "common/text_util.h"

#include <cctype>
#include <charconv>

namespace vobb {

std::string basename_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
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
