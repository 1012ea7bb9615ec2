#pragma once
// Wall-clock time of a step, in seconds, on the steady clock (never set back).

#include <chrono>

namespace esf::detail {

/// Seconds from `start` until now.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Milliseconds from `start` until now.
inline double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

}  // namespace esf::detail
