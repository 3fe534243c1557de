#include "common/io/mesh_io.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <string_view>
#include <unordered_map>

#include "common/atomic_file.h"
#include "common/text_util.h"

namespace vobb {

namespace {

// ---- small lexing helpers ----------------------------------------------------------------

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

void split_tokens(std::string_view line, std::vector<std::string_view>* out) {
  out->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    size_t j = i;
    while (j < line.size() && !is_space(line[j])) ++j;
    if (j > i) out->push_back(line.substr(i, j - i));
    i = j;
  }
}

bool parse_double(std::string_view tok, double* out) {
  if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
  const char* end = tok.data() + tok.size();
  auto res = std::from_chars(tok.data(), end, *out);
  if (res.ec == std::errc::result_out_of_range) {
    // from_chars says this for overflow and for underflow alike; strtod tells them apart and
    // rounds an underflowing literal correctly (to a subnormal or to zero), as a reader of
    // "1e-400" expects. Overflowing literals are infinite; the solidity check reports them.
    if (res.ptr != end) return false;
    *out = std::strtod(std::string(tok).c_str(), nullptr);
    return true;
  }
  return res.ec == std::errc() && res.ptr == end;
}

// The first of tokens[from..] that is not a number (tokens.size() if none): OFF lets numbers
// (normals, colours, texture coordinates) follow a vertex's coordinates and a face's indices.
size_t first_word(const std::vector<std::string_view>& tokens, size_t from) {
  for (size_t k = from; k < tokens.size(); ++k) {
    double ignored;
    if (!parse_double(tokens[k], &ignored)) return k;
  }
  return tokens.size();
}

bool parse_int(std::string_view tok, long long* out) {
  if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
  const char* end = tok.data() + tok.size();
  auto res = std::from_chars(tok.data(), end, *out);
  return res.ec == std::errc() && res.ptr == end;
}

// Line cursor over the file text; numbers lines from 1.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  // Next line, with '#' comments removed when `strip_comments`. False at end of file.
  bool next(std::string_view* line, bool strip_comments) {
    if (pos_ >= text_.size()) return false;
    size_t e = text_.find('\n', pos_);
    if (e == std::string_view::npos) e = text_.size();
    *line = text_.substr(pos_, e - pos_);
    pos_ = e + 1;
    ++number_;
    if (strip_comments) {
      const size_t h = line->find('#');
      if (h != std::string_view::npos) *line = line->substr(0, h);
    }
    return true;
  }
  // Next line holding at least one token.
  bool next_tokens(std::vector<std::string_view>* toks, bool strip_comments) {
    std::string_view line;
    while (next(&line, strip_comments)) {
      split_tokens(line, toks);
      if (!toks->empty()) return true;
    }
    return false;
  }
  size_t number() const { return number_; }
  size_t offset() const { return pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t number_ = 0;
};

class Reader {
 public:
  Reader(std::string display, std::string_view text) : display_(std::move(display)), text_(text) {}
  Status fail(const std::string& why) const { return Status::error(display_ + ": " + why); }
  Status fail_at(size_t line, const std::string& why) const {
    return Status::error(display_ + ":" + std::to_string(line) + ": " + why);
  }
  const std::string& display() const { return display_; }
  std::string_view text() const { return text_; }

  // Appends the polygon as a triangle fan, after range-checking its indices. Errors name
  // the line, or for binary data (line 0) the face record, and an index as the file counts
  // (`base`: 1 for OBJ's).
  Status add_polygon(const std::vector<long long>& idx, size_t line, size_t record, LoadedMesh* out,
                     int base = 0) const {
    auto err = [&](const std::string& why) {
      return line ? fail_at(line, why) : fail("face " + std::to_string(record) + ": " + why);
    };
    const long long nv = static_cast<long long>(out->mesh.vertices.size());
    for (long long i : idx)
      if (i < 0 || i >= nv)
        return err("vertex index " + std::to_string(i + base) + " out of range (" +
                   std::to_string(nv) + " vertices)");
    if (idx.size() < 3) return err("face with fewer than 3 vertices");
    if (idx.size() > 3) ++out->polygons_split;
    for (size_t k = 1; k + 1 < idx.size(); ++k)
      out->mesh.faces.push_back({static_cast<int32_t>(idx[0]), static_cast<int32_t>(idx[k]),
                                 static_cast<int32_t>(idx[k + 1])});
    return Status::ok();
  }

 private:
  std::string display_;
  std::string_view text_;
};

// A declared count must fit in the bytes that are there: this refuses absurd headers
// before any allocation. `min_bytes` is the least one record can take.
bool count_fits(long long count, size_t min_bytes, size_t available) {
  return count >= 0 && static_cast<unsigned long long>(count) <= available / min_bytes;
}

constexpr long long kMaxIndex = std::numeric_limits<int32_t>::max();

// ---- OFF --------------------------------------------------------------------------------

Status read_off(const Reader& r, LoadedMesh* out) {
  Lines lines(r.text());
  std::vector<std::string_view> t;
  if (!lines.next_tokens(&t, true)) return r.fail("empty file");
  std::string_view head = t[0];
  // Header keywords: [ST][C][N][4][n]OFF; vobb reads the 3D ones.
  if (head.size() < 3 || head.substr(head.size() - 3) != "OFF")
    return r.fail_at(lines.number(),
                     "not an OFF file (header '" + std::string(head.substr(0, 20)) + "')");
  const std::string_view prefix = head.substr(0, head.size() - 3);
  if (prefix.find('4') != std::string_view::npos || prefix.find('n') != std::string_view::npos)
    return r.fail_at(lines.number(),
                     "only 3D OFF is supported (header '" + std::string(head) + "')");
  size_t first = 1;
  if (t.size() > 1 && t[1] == "BINARY")
    return r.fail_at(lines.number(), "binary OFF is not supported");
  if (t.size() == first) {
    if (!lines.next_tokens(&t, true)) return r.fail("truncated: missing vertex and face counts");
    first = 0;
  }
  if (t.size() - first < 2) return r.fail_at(lines.number(), "expected vertex and face counts");
  // The counts' line holds the vertex, face and edge counts and nothing else: data after them
  // is a file written without its line breaks, which OFF needs (a face's colour is told from
  // its indices by where the line ends).
  if (t.size() - first > 3)
    return r.fail_at(lines.number(), "data after the vertex, face and edge counts (" +
                                         std::to_string(t.size() - first - 3) +
                                         " more values); OFF gives the counts, each vertex "
                                         "and each face a line");
  long long nv, nf, ne = 0;
  if (!parse_int(t[first], &nv) || !parse_int(t[first + 1], &nf) || nv < 0 || nf < 0)
    return r.fail_at(lines.number(), "bad vertex or face count");
  // The edge count, where given, is not used (writers often put 0), but it is a count.
  if (t.size() - first == 3 && (!parse_int(t[first + 2], &ne) || ne < 0))
    return r.fail_at(lines.number(), "bad edge count '" + std::string(t[first + 2]) + "'");
  const size_t left = r.text().size() - std::min(r.text().size(), lines.offset());
  if (!count_fits(nv, 6, left + 1) || nv > kMaxIndex)
    return r.fail_at(lines.number(), "truncated: header promises " + std::to_string(nv) +
                                         " vertices but only " + std::to_string(left) +
                                         " bytes follow");
  if (!count_fits(nf, 8, left + 1))
    return r.fail_at(lines.number(), "truncated: header promises " + std::to_string(nf) +
                                         " faces but only " + std::to_string(left) +
                                         " bytes follow");
  Mesh& m = out->mesh;
  m.vertices.reserve(nv);
  // Every vertex line has as many values as the first: a normal or colour is on all of them
  // or on none, and a line that differs holds two vertices, or the first line does, which
  // would shift every record after it.
  size_t values = 0, values_line = 0;
  for (long long i = 0; i < nv; ++i) {
    if (!lines.next_tokens(&t, true))
      return r.fail("truncated: " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    if (t.size() < 3) return r.fail_at(lines.number(), "vertex needs 3 coordinates");
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      if (!parse_double(t[k], &p[k]))
        return r.fail_at(lines.number(), "not a number: '" + std::string(t[k].substr(0, 32)) + "'");
    // Values after the coordinates are a normal, a colour or texture coordinates (the N, C
    // and ST headers; some writers add them under a plain OFF header too): numbers, ignored.
    // Anything else means the line is not what it seems.
    if (const size_t k = first_word(t, 3); k < t.size())
      return r.fail_at(lines.number(), "unexpected '" + std::string(t[k].substr(0, 32)) +
                                           "' after the vertex's coordinates");
    if (i == 0) {
      values = t.size();
      values_line = lines.number();
    } else if (t.size() != values) {
      return r.fail_at(lines.number(), "vertex line has " + std::to_string(t.size()) +
                                           " values, line " + std::to_string(values_line) +
                                           " has " + std::to_string(values) +
                                           "; every vertex line of an OFF file has as many");
    }
    m.vertices.push_back(p);
  }
  std::vector<long long> idx;
  for (long long i = 0; i < nf; ++i) {
    if (!lines.next_tokens(&t, true))
      return r.fail("truncated: " + std::to_string(i) + " of " + std::to_string(nf) + " faces");
    long long n;
    if (!parse_int(t[0], &n) || n < 0)
      return r.fail_at(lines.number(), "bad face size '" + std::string(t[0].substr(0, 32)) + "'");
    if (static_cast<long long>(t.size()) - 1 < n)
      return r.fail_at(lines.number(), "face lists " + std::to_string(t.size() - 1) + " of " +
                                           std::to_string(n) + " indices");
    idx.resize(n);
    for (long long k = 0; k < n; ++k)
      if (!parse_int(t[k + 1], &idx[k]))
        return r.fail_at(lines.number(),
                         "bad vertex index '" + std::string(t[k + 1].substr(0, 32)) + "'");
    // After the indices OFF allows a colour: a colormap index, RGB or RGBA, as integers or
    // floats. More values, or words, mean the face size and the line disagree.
    const size_t extra = t.size() - 1 - static_cast<size_t>(n);
    if (extra > 4)
      return r.fail_at(lines.number(), "face of " + std::to_string(n) + " indices is followed by " +
                                           std::to_string(extra) +
                                           " values (a colour has at most 4)");
    if (const size_t k = first_word(t, 1 + static_cast<size_t>(n)); k < t.size())
      return r.fail_at(lines.number(), "unexpected '" + std::string(t[k].substr(0, 32)) +
                                           "' after the face's indices");
    Status s = r.add_polygon(idx, lines.number(), static_cast<size_t>(i), out);
    if (!s) return s;
  }
  // More lines than the header declares would otherwise be dropped without a word, and a
  // header that undercounts its faces would show up as a hole in the mesh.
  if (lines.next_tokens(&t, true))
    return r.fail_at(lines.number(), "more data after the " + std::to_string(nf) +
                                         " faces the header declares: '" +
                                         std::string(t[0].substr(0, 32)) + "'");
  return Status::ok();
}

// ---- OBJ --------------------------------------------------------------------------------

Status read_obj(const Reader& r, LoadedMesh* out) {
  Lines lines(r.text());
  std::vector<std::string_view> t;
  std::vector<long long> idx;
  Mesh& m = out->mesh;
  // Faces may precede later vertices only through relative indices resolved at their line;
  // absolute indices are range-checked once all vertices are known.
  struct PendingFace {
    std::vector<long long> idx;
    size_t line;
  };
  std::vector<PendingFace> faces;
  while (lines.next_tokens(&t, true)) {
    if (t[0] == "v") {
      if (t.size() < 4) return r.fail_at(lines.number(), "vertex needs 3 coordinates");
      Vec3 p;
      for (int k = 0; k < 3; ++k)
        if (!parse_double(t[k + 1], &p[k]))
          return r.fail_at(lines.number(),
                           "not a number: '" + std::string(t[k + 1].substr(0, 32)) + "'");
      // After x y z: a weight w, or a colour r g b [a] (a common extension): at most 4
      // numbers. A word, or more numbers, means the line is not what it seems.
      if (const size_t k = first_word(t, 4); k < t.size())
        return r.fail_at(lines.number(), "unexpected '" + std::string(t[k].substr(0, 32)) +
                                             "' after the vertex's coordinates");
      if (t.size() > 8)
        return r.fail_at(lines.number(),
                         "vertex has " + std::to_string(t.size() - 4) +
                             " values after its coordinates (a weight or a colour has at most 4)");
      m.vertices.push_back(p);
    } else if (t[0] == "f") {
      idx.clear();
      for (size_t k = 1; k < t.size(); ++k) {
        std::string_view v = t[k].substr(0, t[k].find('/'));
        long long i;
        if (!parse_int(v, &i) || i == 0)
          return r.fail_at(lines.number(),
                           "bad vertex index '" + std::string(t[k].substr(0, 32)) + "'");
        // 1-based, negative counts back from the last vertex read so far.
        if (i < 0 && static_cast<long long>(m.vertices.size()) + i < 0)
          return r.fail_at(lines.number(), "relative vertex index " + std::to_string(i) +
                                               " reaches before the first vertex (" +
                                               std::to_string(m.vertices.size()) + " read so far)");
        idx.push_back(i > 0 ? i - 1 : static_cast<long long>(m.vertices.size()) + i);
      }
      faces.push_back({idx, lines.number()});
    } else if (t[0] == "l" || t[0] == "p") {
      return r.fail_at(lines.number(), "line and point elements are not part of a solid");
    }
    // vn, vt, g, o, s, usemtl, mtllib and the rest carry nothing vobb needs.
  }
  if (m.vertices.empty() && faces.empty()) return r.fail("empty file: no vertices or faces");
  for (const PendingFace& f : faces) {
    Status s = r.add_polygon(f.idx, f.line, 0, out, 1);
    if (!s) return s;
  }
  return Status::ok();
}

// ---- PLY --------------------------------------------------------------------------------

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64, kBad };

PlyType ply_type(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::kInt8;
  if (s == "uchar" || s == "uint8") return PlyType::kUint8;
  if (s == "short" || s == "int16") return PlyType::kInt16;
  if (s == "ushort" || s == "uint16") return PlyType::kUint16;
  if (s == "int" || s == "int32") return PlyType::kInt32;
  if (s == "uint" || s == "uint32") return PlyType::kUint32;
  if (s == "float" || s == "float32") return PlyType::kFloat32;
  if (s == "double" || s == "float64") return PlyType::kFloat64;
  return PlyType::kBad;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
    default:
      return 0;
  }
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::kBad, type = PlyType::kBad;
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> props;
};

// Binary cursor with bounds checks; values converted exactly to double.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view data, bool big_endian) : d_(data), big_(big_endian) {}
  bool read(PlyType t, double* out) {
    const size_t n = ply_size(t);
    if (pos_ + n > d_.size()) return false;
    unsigned char b[8];
    std::memcpy(b, d_.data() + pos_, n);
    pos_ += n;
    if (big_) std::reverse(b, b + n);
    switch (t) {
      case PlyType::kInt8: {
        int8_t v;
        std::memcpy(&v, b, 1);
        *out = v;
        break;
      }
      case PlyType::kUint8: {
        uint8_t v;
        std::memcpy(&v, b, 1);
        *out = v;
        break;
      }
      case PlyType::kInt16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        *out = v;
        break;
      }
      case PlyType::kUint16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        *out = v;
        break;
      }
      case PlyType::kInt32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        *out = v;
        break;
      }
      case PlyType::kUint32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        *out = v;
        break;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        *out = v;
        break;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        *out = v;
        break;
      }
      default:
        return false;
    }
    return true;
  }
  size_t remaining() const { return d_.size() - pos_; }

 private:
  std::string_view d_;
  bool big_;
  size_t pos_ = 0;
};

bool integral_value(double v, long long* out) {
  if (!(v == std::floor(v)) || std::abs(v) > 9e15) return false;
  *out = static_cast<long long>(v);
  return true;
}

// Parses the property line `t` (header line `line`) into `p`.
Status parse_ply_property(const Reader& r, size_t line, const std::vector<std::string_view>& t,
                          PlyProperty* p) {
  if (t.size() >= 5 && t[1] == "list") {
    p->is_list = true;
    p->count_type = ply_type(t[2]);
    p->type = ply_type(t[3]);
    p->name = std::string(t[4]);
    if (p->count_type == PlyType::kBad || p->type == PlyType::kBad ||
        p->count_type == PlyType::kFloat32 || p->count_type == PlyType::kFloat64)
      return r.fail_at(line, "bad list property types");
  } else if (t.size() >= 3) {
    p->type = ply_type(t[1]);
    p->name = std::string(t[2]);
    if (p->type == PlyType::kBad)
      return r.fail_at(line, "unknown property type '" + std::string(t[1].substr(0, 32)) + "'");
  } else {
    return r.fail_at(line, "bad property line");
  }
  return Status::ok();
}

// Reads the header through end_header: its format and its elements with their properties.
// `t` is the token buffer for `lines`.
Status read_ply_header(const Reader& r, Lines* lines, std::vector<std::string_view>* t,
                       std::string* format, std::vector<PlyElement>* elems) {
  if (!lines->next_tokens(t, false) || (*t)[0] != "ply")
    return r.fail("not a PLY file (no 'ply' magic)");
  bool ended = false;
  while (lines->next_tokens(t, false)) {
    const std::vector<std::string_view>& tok = *t;
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "format") {
      if (tok.size() < 2) return r.fail_at(lines->number(), "bad format line");
      *format = std::string(tok[1]);
      if (*format != "ascii" && *format != "binary_little_endian" && *format != "binary_big_endian")
        return r.fail_at(lines->number(), "unknown PLY format '" + format->substr(0, 32) + "'");
    } else if (tok[0] == "element") {
      long long n;
      if (tok.size() < 3 || !parse_int(tok[2], &n) || n < 0)
        return r.fail_at(lines->number(), "bad element line");
      elems->push_back({std::string(tok[1]), n, {}});
    } else if (tok[0] == "property") {
      if (elems->empty()) return r.fail_at(lines->number(), "property before any element");
      PlyProperty p;
      Status s = parse_ply_property(r, lines->number(), tok, &p);
      if (!s) return s;
      elems->back().props.push_back(p);
    } else if (tok[0] == "end_header") {
      ended = true;
      break;
    } else {
      return r.fail_at(lines->number(),
                       "unknown header line '" + std::string(tok[0].substr(0, 32)) + "'");
    }
  }
  if (!ended) return r.fail("truncated: no end_header");
  if (format->empty()) return r.fail("PLY header has no format line");
  return Status::ok();
}

// Which properties hold a vertex's x, y, z and a face's vertex indices (-1: none).
struct PlyLayout {
  int ix = -1, iy = -1, iz = -1, iface = -1;
};

// Finds the vertex coordinates and the face index list among the elements' properties.
PlyLayout ply_layout(const std::vector<PlyElement>& elems) {
  PlyLayout l;
  for (const PlyElement& e : elems) {
    if (e.name == "vertex")
      for (size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].is_list) continue;
        if (e.props[k].name == "x") l.ix = static_cast<int>(k);
        if (e.props[k].name == "y") l.iy = static_cast<int>(k);
        if (e.props[k].name == "z") l.iz = static_cast<int>(k);
      }
    if (e.name == "face")
      for (size_t k = 0; k < e.props.size(); ++k)
        if (e.props[k].is_list &&
            (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index"))
          l.iface = static_cast<int>(k);
  }
  return l;
}

// Reads every element's records, ASCII from `lines` (token buffer `tokens`) or binary from
// `bin`: the vertices into `mesh`, and each face's indices with its line (0 for binary) into
// `polys`.
Status read_ply_records(const Reader& r, const std::vector<PlyElement>& elems,
                        const PlyLayout& layout, bool ascii, Lines* lines,
                        std::vector<std::string_view>* tokens, BinaryCursor* bin,
                        std::vector<std::pair<std::vector<long long>, size_t>>* polys, Mesh* mesh) {
  const int ix = layout.ix, iy = layout.iy, iz = layout.iz, iface = layout.iface;
  const std::vector<std::string_view>& t = *tokens;
  Mesh& m = *mesh;
  std::vector<long long> idx;
  for (const PlyElement& e : elems) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    if (is_vertex) m.vertices.reserve(e.count);
    for (long long i = 0; i < e.count; ++i) {
      Vec3 p = Vec3::Zero();
      idx.clear();
      size_t tok = 0;
      if (ascii && !lines->next_tokens(tokens, false))
        return r.fail("truncated: " + std::to_string(i) + " of " + std::to_string(e.count) + " " +
                      e.name + " records");
      const size_t line = lines->number();
      // Binary data has no lines: its errors name the element's record instead.
      auto at_record = [&](const std::string& why) {
        return ascii ? r.fail_at(line, why)
                     : r.fail(e.name + " record " + std::to_string(i) + ": " + why);
      };
      for (size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& prop = e.props[k];
        auto next_value = [&](PlyType type, double* v) -> Status {
          if (ascii) {
            if (tok >= t.size()) return r.fail_at(line, "record has too few values");
            const std::string_view s = t[tok++];
            if (!parse_double(s, v))
              return r.fail_at(line, "not a number: '" + std::string(s.substr(0, 32)) + "'");
            return Status::ok();
          }
          if (!bin->read(type, v))
            return r.fail("truncated: binary data ends inside " + e.name + " record " +
                          std::to_string(i));
          return Status::ok();
        };
        double v;
        if (prop.is_list) {
          Status s = next_value(prop.count_type, &v);
          if (!s) return s;
          long long n;
          if (!integral_value(v, &n) || n < 0) return at_record("bad list length");
          if (!ascii && static_cast<unsigned long long>(n) * ply_size(prop.type) > bin->remaining())
            return r.fail("truncated: binary data ends inside " + e.name + " record " +
                          std::to_string(i));
          for (long long j = 0; j < n; ++j) {
            s = next_value(prop.type, &v);
            if (!s) return s;
            long long id;
            if (is_face && static_cast<int>(k) == iface) {
              if (!integral_value(v, &id)) return at_record("vertex index is not an integer");
              idx.push_back(id);
            }
          }
        } else {
          Status s = next_value(prop.type, &v);
          if (!s) return s;
          if (is_vertex && static_cast<int>(k) == ix) p[0] = v;
          if (is_vertex && static_cast<int>(k) == iy) p[1] = v;
          if (is_vertex && static_cast<int>(k) == iz) p[2] = v;
        }
      }
      // An ASCII record is one line: values beyond its properties (a damaged list length, a
      // stray word) mean the line and the header disagree.
      if (ascii && tok < t.size())
        return r.fail_at(line, "unexpected '" + std::string(t[tok].substr(0, 32)) + "' after the " +
                                   e.name + " record's " + std::to_string(tok) + " values");
      if (is_vertex) m.vertices.push_back(p);
      if (is_face) polys->emplace_back(idx, ascii ? line : 0);
    }
  }
  return Status::ok();
}

// Data beyond the records the header declares would otherwise be dropped without a word
// (a header that undercounts its faces shows up as a hole). ASCII: any further non-blank
// line. Binary: any further byte but a final line break, which some writers append.
Status check_ply_end(const Reader& r, bool ascii, Lines* lines, std::vector<std::string_view>* t,
                     const BinaryCursor& bin) {
  if (ascii) {
    if (lines->next_tokens(t, false))
      return r.fail_at(lines->number(), "more data after the records the header declares: '" +
                                            std::string((*t)[0].substr(0, 32)) + "'");
  } else {
    const std::string_view rest = r.text().substr(r.text().size() - bin.remaining());
    if (!rest.empty() && rest != "\n" && rest != "\r\n")
      return r.fail(std::to_string(rest.size()) +
                    " bytes of data after the records the header declares");
  }
  return Status::ok();
}

Status read_ply(const Reader& r, LoadedMesh* out) {
  Lines lines(r.text());
  std::vector<std::string_view> t;
  std::string format;
  std::vector<PlyElement> elems;
  Status s = read_ply_header(r, &lines, &t, &format, &elems);
  if (!s) return s;
  const size_t data_start = std::min(lines.offset(), r.text().size());
  const size_t available = r.text().size() - data_start;
  const PlyLayout layout = ply_layout(elems);
  if (layout.ix < 0 || layout.iy < 0 || layout.iz < 0)
    return r.fail("PLY has no vertex x, y, z properties");
  if (layout.iface < 0) return r.fail("PLY has no face vertex_indices list");
  for (const PlyElement& e : elems)
    if (!count_fits(e.count, 1, available + 1))
      return r.fail("truncated: header promises " + std::to_string(e.count) + " " + e.name +
                    " records but only " + std::to_string(available) + " bytes follow");

  std::vector<std::pair<std::vector<long long>, size_t>> polys;
  const bool ascii = format == "ascii";
  BinaryCursor bin(r.text().substr(data_start), format == "binary_big_endian");
  s = read_ply_records(r, elems, layout, ascii, &lines, &t, &bin, &polys, &out->mesh);
  if (!s) return s;
  s = check_ply_end(r, ascii, &lines, &t, bin);
  if (!s) return s;
  for (size_t fi = 0; fi < polys.size(); ++fi) {
    s = r.add_polygon(polys[fi].first, polys[fi].second, fi, out);
    if (!s) return s;
  }
  return Status::ok();
}

// ---- STL --------------------------------------------------------------------------------

// What is wrong with a binary STL of `size` bytes whose header declares `n` triangles ("" when
// its layout fits). Whole 50-byte records beyond the declared count would be dropped without a
// word (a count that undercounts shows up as a hole). Fewer bytes than one record cannot hold
// a triangle: some writers pad the file, and those bytes are ignored.
std::string stl_binary_layout_defect(uint64_t size, uint32_t n) {
  if (size < 84 + 50ull * n)
    return "truncated: binary STL promises " + std::to_string(n) + " triangles but holds " +
           std::to_string((size - 84) / 50);
  const uint64_t extra = (size - 84 - 50ull * n) / 50;
  if (extra > 0)
    return "binary STL holds " + std::to_string(extra) + " more triangle records after the " +
           std::to_string(n) + " its header declares";
  return "";
}

Status read_stl_binary(const Reader& r, LoadedMesh* out) {
  const std::string_view d = r.text();
  if (d.size() < 84) return r.fail("truncated: binary STL shorter than its 84-byte header");
  uint32_t n;
  std::memcpy(&n, d.data() + 80, 4);
  if (const std::string defect = stl_binary_layout_defect(d.size(), n); !defect.empty())
    return r.fail(defect);
  Mesh& m = out->mesh;
  m.vertices.reserve(3ull * n);
  for (uint32_t i = 0; i < n; ++i) {
    const char* rec = d.data() + 84 + 50ull * i + 12;  // skip the normal
    for (int k = 0; k < 3; ++k) {
      float v[3];
      std::memcpy(v, rec + 12 * k, 12);
      m.vertices.emplace_back(v[0], v[1], v[2]);  // float to double is exact
    }
    m.faces.push_back({static_cast<int32_t>(3 * i), static_cast<int32_t>(3 * i + 1),
                       static_cast<int32_t>(3 * i + 2)});
  }
  return Status::ok();
}

// ASCII STL's keywords are lower case in its grammar; some writers use upper case: taken either
// way, letter by letter.
bool stl_keyword(std::string_view word, std::string_view keyword) {
  if (word.size() != keyword.size()) return false;
  for (size_t i = 0; i < word.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(word[i])) != keyword[i]) return false;
  return true;
}

// Whether the text starts as an ASCII STL does: "solid" (in either case) after any blanks.
bool starts_ascii_stl(std::string_view d) {
  const size_t at = std::min(d.find_first_not_of(" \t\r\n"), d.size());
  const std::string_view word = d.substr(at, 5);
  return stl_keyword(word, "solid") &&
         (d.size() == at + 5 || std::isspace(static_cast<unsigned char>(d[at + 5])) != 0);
}

Status read_stl_ascii(const Reader& r, LoadedMesh* out) {
  Lines lines(r.text());
  std::vector<std::string_view> t;
  Mesh& m = out->mesh;
  if (!lines.next_tokens(&t, false) || !stl_keyword(t[0], "solid"))
    return r.fail("not an STL file");
  // The grammar, one keyword line each: facet normal nx ny nz / outer loop / vertex x y z
  // (three times) / endloop / endfacet. A line out of that order, or with other tokens, is
  // refused: read loosely it could drop or merge corners without a word.
  enum class At { kSolid, kFacet, kLoop, kLoopEnd };
  At at = At::kSolid;
  int corners = 0;
  bool ended = false;
  auto keyword_line = [&](const char* what, size_t tokens) -> Status {
    if (t.size() != tokens)
      return r.fail_at(lines.number(), "'" + std::string(what) + "' line with " +
                                           std::to_string(t.size()) + " words, expected " +
                                           std::to_string(tokens));
    return Status::ok();
  };
  while (lines.next_tokens(&t, false)) {
    const std::string_view k = t[0];
    Status s = Status::ok();
    if (ended) {  // some writers put several solids in one file: read them all
      // A DOS end-of-file mark (Ctrl-Z) or NUL padding after the last solid is not content.
      if (t.size() == 1 &&
          k.find_first_not_of(std::string_view("\x1a\0", 2)) == std::string_view::npos)
        continue;
      if (!stl_keyword(k, "solid"))
        return r.fail_at(lines.number(),
                         "unexpected '" + std::string(k.substr(0, 32)) + "' after endsolid");
      ended = false;
      continue;
    }
    if (stl_keyword(k, "facet")) {
      if (at != At::kSolid) return r.fail_at(lines.number(), "facet inside a facet");
      if (t.size() < 2 || !stl_keyword(t[1], "normal"))
        return r.fail_at(lines.number(), "'facet' without 'normal'");
      if (!(s = keyword_line("facet normal", 5))) return s;
      // The normal is ignored, but must be numbers: nan, inf and MSVC's 1.#IND / 1.#QNAN, which
      // some exporters write for degenerate facets, count as numbers here.
      for (int c = 2; c < 5; ++c) {
        double ignored;
        std::string_view w = t[c];
        if (!w.empty() && (w[0] == '-' || w[0] == '+')) w.remove_prefix(1);
        if (!parse_double(t[c], &ignored) && w.substr(0, 3) != "1.#")
          return r.fail_at(lines.number(),
                           "not a number: '" + std::string(t[c].substr(0, 32)) + "'");
      }
      at = At::kFacet;
    } else if (stl_keyword(k, "outer")) {
      if (at != At::kFacet)
        return r.fail_at(lines.number(), "'outer loop' outside a facet, or twice");
      if (t.size() < 2 || !stl_keyword(t[1], "loop"))
        return r.fail_at(lines.number(), "'outer' without 'loop'");
      if (!(s = keyword_line("outer loop", 2))) return s;
      at = At::kLoop;
      corners = 0;
    } else if (stl_keyword(k, "vertex")) {
      if (at != At::kLoop) return r.fail_at(lines.number(), "vertex outside an outer loop");
      if (corners == 3) return r.fail_at(lines.number(), "facet with more than 3 vertices");
      if (t.size() < 4) return r.fail_at(lines.number(), "vertex needs 3 coordinates");
      Vec3 p;
      for (int c = 0; c < 3; ++c)
        if (!parse_double(t[c + 1], &p[c]))
          return r.fail_at(lines.number(),
                           "not a number: '" + std::string(t[c + 1].substr(0, 32)) + "'");
      if (t.size() > 4)
        return r.fail_at(lines.number(), "unexpected '" + std::string(t[4].substr(0, 32)) +
                                             "' after the vertex's coordinates");
      m.vertices.push_back(p);
      ++corners;
    } else if (stl_keyword(k, "endloop")) {
      if (at != At::kLoop) return r.fail_at(lines.number(), "'endloop' outside an outer loop");
      if (corners != 3) return r.fail_at(lines.number(), "facet without exactly 3 vertices");
      if (!(s = keyword_line("endloop", 1))) return s;
      at = At::kLoopEnd;
    } else if (stl_keyword(k, "endfacet")) {
      if (at == At::kLoop) return r.fail_at(lines.number(), "'endfacet' before 'endloop'");
      if (at != At::kLoopEnd)
        return r.fail_at(lines.number(), "'endfacet' without a facet and its outer loop");
      if (!(s = keyword_line("endfacet", 1))) return s;
      const int32_t b = static_cast<int32_t>(m.vertices.size()) - 3;
      m.faces.push_back({b, b + 1, b + 2});
      at = At::kSolid;
    } else if (stl_keyword(k, "endsolid")) {
      if (at != At::kSolid) return r.fail_at(lines.number(), "'endsolid' inside a facet");
      ended = true;
    } else {
      return r.fail_at(lines.number(), "unexpected '" + std::string(k.substr(0, 32)) + "'");
    }
  }
  if (!ended) return r.fail("truncated: no endsolid");
  return Status::ok();
}

Status read_stl(const Reader& r, LoadedMesh* out) {
  const std::string_view d = r.text();
  // "solid" starts ASCII files, but some binary headers start with it too: a size that
  // matches the binary layout exactly decides for binary.
  if (d.size() >= 84) {
    uint32_t n;
    std::memcpy(&n, d.data() + 80, 4);
    if (d.size() == 84 + 50ull * n) return read_stl_binary(r, out);
  }
  if (starts_ascii_stl(d)) {
    // A binary file whose header starts with "solid" and that carries trailing bytes: if the
    // ASCII parse fails but the binary layout fits, read it as binary.
    Status s = read_stl_ascii(r, out);
    if (s || d.size() < 84) return s;
    uint32_t n;
    std::memcpy(&n, d.data() + 80, 4);
    if (d.size() < 84 + 50ull * n) return s;
    *out = LoadedMesh();
    out->format = "stl";
    return read_stl_binary(r, out);
  }
  return read_stl_binary(r, out);
}

}  // namespace

void weld_vertices(Mesh* mesh, size_t* welded, size_t* unreferenced) {
  struct Key {
    uint64_t b[3];
    bool operator==(const Key& o) const {
      return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2];
    }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      uint64_t h = 1469598103934665603ull;
      for (uint64_t v : k.b) h = (h ^ v) * 1099511628211ull ^ (v >> 29);
      return static_cast<size_t>(h);
    }
  };
  const size_t n = mesh->vertices.size();
  std::vector<char> used(n, 0);
  for (const Face& f : mesh->faces)
    for (int32_t i : f) used[i] = 1;
  std::unordered_map<Key, int32_t, KeyHash> first;
  first.reserve(n);
  std::vector<int32_t> remap(n, -1);
  std::vector<Vec3> kept;
  kept.reserve(n);
  *welded = *unreferenced = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!used[i]) {
      ++*unreferenced;
      continue;
    }
    Key k;
    for (int c = 0; c < 3; ++c) {
      const double v = mesh->vertices[i][c] == 0.0 ? 0.0 : mesh->vertices[i][c];  // -0 == +0
      std::memcpy(&k.b[c], &v, 8);
    }
    auto [it, inserted] = first.emplace(k, static_cast<int32_t>(kept.size()));
    if (inserted)
      kept.push_back(mesh->vertices[i]);
    else
      ++*welded;
    remap[i] = it->second;
  }
  for (Face& f : mesh->faces)
    for (int32_t& i : f) i = remap[i];
  mesh->vertices = std::move(kept);
}

namespace {

// The native format a file's first bytes announce: "off" ([ST][C][N]OFF), "ply" (its magic
// line), "stl" (ASCII "solid"), "obj" (a first line starting with "v", "vn", "f", "o", "g" or
// "mtllib"), or "" when none does. Binary STL has no magic, so it is never named.
std::string looks_like(std::string_view text) {
  Lines lines(text);
  std::vector<std::string_view> t;
  if (!lines.next_tokens(&t, true)) return "";
  const std::string_view head = t[0];
  if (head.size() >= 3 && head.size() <= 6 && head.substr(head.size() - 3) == "OFF") return "off";
  if (head == "ply") return "ply";
  if (stl_keyword(head, "solid")) return "stl";
  for (const char* k : {"v", "vn", "vt", "f", "o", "g", "mtllib", "usemtl"})
    if (head == k) return "obj";
  return "";
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

namespace {
std::atomic<ForeignMeshReader> foreign_reader{nullptr};
}  // namespace

void set_foreign_mesh_reader(ForeignMeshReader reader) { foreign_reader = reader; }

Status load_mesh(const std::string& path, LoadedMesh* out) {
  *out = LoadedMesh();
  const std::string display = basename_of(path);
  const std::string ext = extension_of(path);
  const bool native = ext == "off" || ext == "obj" || ext == "ply" || ext == "stl";
  if (!native) {
    uint64_t size = 0;
    const Status regular = check_regular_file(path, display, "mesh file", &size);
    if (!regular) return regular;
    // vobb's own files are JSON: one given as a mesh is most likely an argument out of place.
    if (ext == "json")
      return Status::error(display +
                           ": a JSON file, not a mesh (vobb's tree, box and query files are JSON)");
    const ForeignMeshReader reader = foreign_reader;
    if (reader == nullptr)
      return Status::error(display + ": unknown mesh format '" + ext +
                           "' (this build reads OFF, OBJ, PLY, STL)");
    Status s = reader(path, display, size, out);
    if (!s) return s;
  } else {
    std::string content;
    // A file saved under another format's extension fails in that format's terms ("binary
    // STL promises 808263735 triangles"); the message also says what it looks like.
    auto hinted = [&](const Status& failed) {
      const std::string looks = looks_like(content);
      if (looks.empty() || looks == ext) return failed;
      return Status::error(failed.message() + " (the file looks like " + upper(looks) + ", not " +
                           upper(ext) + "; is the extension right?)");
    };
    // A binary STL that is no ASCII one is refused by its size and declared count before it
    // is read whole, as a text format with binary bytes in its first kTextProbeBytes is.
    if (ext == "stl") {
      uint64_t size = 0;
      if (Status st = check_regular_file(path, display, "mesh file", &size); !st) return st;
      std::ifstream in(path, std::ios::binary);
      content.resize(static_cast<size_t>(std::min<uint64_t>(size, kTextProbeBytes)));
      in.read(content.data(), static_cast<std::streamsize>(content.size()));
      // An ASCII STL starts with "solid", as a binary one's 80-byte header may; a NUL among
      // the first 84 bytes (the header and the count) is no ASCII one's (some pad their end).
      if (size >= 84 && static_cast<size_t>(in.gcount()) == content.size() &&
          (!starts_ascii_stl(content) || content.find('\0') < 84)) {
        uint32_t n;
        std::memcpy(&n, content.data() + 80, 4);
        if (const std::string defect = stl_binary_layout_defect(size, n); !defect.empty())
          return hinted(Status::error(display + ": " + defect));
      }
    }
    const bool text_format = ext != "ply" && ext != "stl";
    Status s = read_regular_file(path, display, "mesh file", &content, text_format);
    if (!s) return content.find('\0') == std::string::npos ? s : hinted(s);  // binary at the start
    if (content.empty()) return Status::error(display + ": empty file");
    if (content.find('\0') != std::string::npos && text_format)
      return hinted(Status::error(display + ": binary data in a text format"));
    // Lines that end in CR alone (classic Mac OS) would read as one long line.
    if (ext != "stl" && content.find('\n') == std::string::npos &&
        content.find('\r') != std::string::npos)
      return Status::error(display +
                           ": lines end in CR alone (classic Mac OS); convert them to LF or CR LF");
    // A UTF-8 byte-order mark, which some Windows editors put first, is no part of the text
    // (OBJ's first "v" line was dropped with it, and PLY's magic missed). Not for STL: a
    // binary STL's 80-byte header may begin with any bytes.
    std::string_view text = content;
    if (ext != "stl" && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
    Reader r(display, text);
    out->format = ext;
    if (ext == "off")
      s = read_off(r, out);
    else if (ext == "obj")
      s = read_obj(r, out);
    else if (ext == "ply")
      s = read_ply(r, out);
    else
      s = read_stl(r, out);
    if (!s) return hinted(s);
  }
  if (out->mesh.vertices.size() > static_cast<size_t>(kMaxIndex))
    return Status::error(display + ": too many vertices");
  out->file_vertices = out->mesh.vertices.size();
  bool finite = true;
  for (const Vec3& v : out->mesh.vertices) finite = finite && v.allFinite();
  // Welding compares bit patterns: with NaN around, leave the mesh as read and let the
  // solidity check name the defect.
  if (finite) weld_vertices(&out->mesh, &out->welded_vertices, &out->unreferenced_vertices);
  return Status::ok();
}

// ---- writers ----------------------------------------------------------------------------

namespace {

template <typename T>
void put_bin(std::string* s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  s->append(b, sizeof(T));
}

}  // namespace

Status save_mesh(const Mesh& m, const std::string& path, MeshFormat format) {
  std::string s;
  auto vertex_line = [&](const char* prefix, const Vec3& v) {
    s += prefix;
    append_xyz(&s, v);
    s += '\n';
  };
  switch (format) {
    case MeshFormat::kOff:
      s = "OFF\n" + std::to_string(m.vertices.size()) + " " + std::to_string(m.faces.size()) +
          " 0\n";
      for (const Vec3& v : m.vertices) vertex_line("", v);
      for (const Face& f : m.faces)
        s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             "\n";
      break;
    case MeshFormat::kObj:
      for (const Vec3& v : m.vertices) vertex_line("v ", v);
      for (const Face& f : m.faces)
        s += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
             std::to_string(f[2] + 1) + "\n";
      break;
    case MeshFormat::kPlyAscii:
    case MeshFormat::kPlyBinary: {
      const bool bin = format == MeshFormat::kPlyBinary;
      s = std::string("ply\nformat ") + (bin ? "binary_little_endian" : "ascii") + " 1.0\n";
      s += "element vertex " + std::to_string(m.vertices.size()) + "\n";
      s += "property double x\nproperty double y\nproperty double z\n";
      s += "element face " + std::to_string(m.faces.size()) + "\n";
      s += "property list uchar int vertex_indices\nend_header\n";
      for (const Vec3& v : m.vertices) {
        if (bin)
          for (int k = 0; k < 3; ++k) put_bin(&s, v[k]);
        else
          vertex_line("", v);
      }
      for (const Face& f : m.faces) {
        if (bin) {
          put_bin<uint8_t>(&s, 3);
          for (int32_t i : f) put_bin(&s, i);
        } else {
          s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " +
               std::to_string(f[2]) + "\n";
        }
      }
      break;
    }
    case MeshFormat::kStlAscii:
      s = "solid vobb\n";
      for (const Face& f : m.faces) {
        s += "facet normal 0 0 0\nouter loop\n";
        for (int32_t i : f) vertex_line("vertex ", m.vertices[i]);
        s += "endloop\nendfacet\n";
      }
      s += "endsolid vobb\n";
      break;
    case MeshFormat::kStlBinary: {
      s.assign(80, ' ');
      put_bin<uint32_t>(&s, static_cast<uint32_t>(m.faces.size()));
      for (const Face& f : m.faces) {
        for (int k = 0; k < 3; ++k) put_bin<float>(&s, 0.0f);
        for (int32_t i : f)
          for (int k = 0; k < 3; ++k) put_bin<float>(&s, static_cast<float>(m.vertices[i][k]));
        put_bin<uint16_t>(&s, 0);
      }
      break;
    }
  }
  return write_file_atomic(path, s);
}

}  // namespace vobb
