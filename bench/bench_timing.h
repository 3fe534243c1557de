// Timing for the benchmark programs: wall-clock seconds of one call, on the monotonic clock.
#pragma once

#include <chrono>

namespace vobb::bench {

template <typename F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace vobb::bench
