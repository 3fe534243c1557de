// Wall-clock seconds for progress lines and reported timings (not for benchmarks' own loops).
#pragma once

#include <chrono>

namespace vobb {

// Seconds elapsed since t0, on the monotonic clock.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace vobb
