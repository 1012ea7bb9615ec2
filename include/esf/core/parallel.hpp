#pragma once
// The one parallelism seam of esf: indexed parallel loops on TBB with a thread-count option.
// Work items write to their own slots, so results never depend on the number of threads.

#include <cstddef>
#include <functional>

namespace esf {

/// The most threads a `threads` option gets: 4 x the cores (tbb::info::default_concurrency()).
int max_threads();
/// max_threads() is never below this: counts up to it are taken as they are without asking TBB
/// for the core count (which starts TBB's runtime and loads further libraries, a cost that a
/// single-threaded process need not pay).
inline constexpr int kThreadsWithinAnyLimit = 4;
/// Number of threads a `threads` option means: 0 = all cores; above max_threads() it is
/// clamped to max_threads() without notice (a CLI warns); negative is rejected.
int resolve_threads(int threads);

/// Calls body(i) for i in [0, count) on `threads` threads (0 = all cores, 1 = the caller only).
/// The first exception thrown by a body is rethrown after the loop stops.
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body);

/// As parallel_for, and also passes the index in [0, resolve_threads(threads)) of the worker
/// running the call, so that each worker can use its own scratch object.
void parallel_for_slots(std::size_t count, int threads,
                        const std::function<void(std::size_t, int)>& body);

}  // namespace esf
