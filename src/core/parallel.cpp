#include "esf/core/parallel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace esf {

int max_threads() { return 4 * tbb::info::default_concurrency(); }

int resolve_threads(int threads) {
    if (threads < 0)
        throw std::invalid_argument("thread count must be >= 0 (0 = all cores), got " +
                                    std::to_string(threads));
    if (threads >= 1 && threads <= kThreadsWithinAnyLimit) return threads;
    // Tens of thousands of TBB workers exhaust the allocator: never more than max_threads().
    return threads == 0 ? tbb::info::default_concurrency() : std::min(threads, max_threads());
}

void parallel_for_slots(std::size_t count, int threads,
                        const std::function<void(std::size_t, int)>& body) {
    const int slots = resolve_threads(threads);
    if (slots == 1 || count <= 1) {
        for (std::size_t i = 0; i < count; ++i) body(i, 0);
        return;
    }
    tbb::task_arena arena(slots);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              const int slot = tbb::this_task_arena::current_thread_index();
                              for (std::size_t i = range.begin(); i != range.end(); ++i)
                                  body(i, slot);
                          });
    });
}

void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body) {
    parallel_for_slots(count, threads, [&](std::size_t i, int) { body(i); });
}

}  // namespace esf
