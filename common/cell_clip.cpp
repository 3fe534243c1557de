#include "common/cell_clip.h"

namespace vobb::cell_clip {

std::vector<int> cap_cycle(const std::vector<int>& next, size_t edges) {
  std::vector<int> cap;
  int start = 0;
  while (next[start] < 0) ++start;
  int at = start;
  do {
    cap.push_back(at);
    if (static_cast<size_t>(at) >= next.size() || next[at] < 0)
      throw InconsistentSides{};  // an open cycle
    at = next[at];
    if (cap.size() > edges) throw InconsistentSides{};
  } while (at != start);
  if (cap.size() != edges) throw InconsistentSides{};  // more than one cycle
  return cap;
}

std::vector<int> compact_faces(std::vector<std::vector<int>>* faces, size_t n_ids) {
  std::vector<int> remap(n_ids, -1), old_of;
  for (std::vector<int>& f : *faces)
    for (int& id : f) {
      if (remap[id] < 0) {
        remap[id] = static_cast<int>(old_of.size());
        old_of.push_back(id);
      }
      id = remap[id];
    }
  return old_of;
}

std::pair<double, double> NumberBounds<Rational>::of(const Rational& x) {
  std::pair<double, double> b;
  enclose(x, &b.first, &b.second);
  return b;
}

}  // namespace vobb::cell_clip
