#pragma once
// The wall-clock seconds since `start`, for the bench programs' timings.
#include <chrono>

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
