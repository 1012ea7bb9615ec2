#include "esf/core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {

TEST(Parallel, SmallThreadCountsAreWithinEveryLimit) {
    // resolve_threads() takes counts up to kThreadsWithinAnyLimit without asking TBB: that is
    // only right while the cap can never be lower.
    EXPECT_GE(esf::max_threads(), esf::kThreadsWithinAnyLimit);
    for (int threads = 1; threads <= esf::kThreadsWithinAnyLimit; ++threads)
        EXPECT_EQ(esf::resolve_threads(threads), threads);
}

TEST(Parallel, ZeroMeansAllCoresAndHugeCountsAreCapped) {
    const int all = esf::resolve_threads(0);
    EXPECT_GE(all, 1);
    EXPECT_EQ(esf::max_threads(), 4 * all);
    EXPECT_EQ(esf::resolve_threads(std::numeric_limits<int>::max()), esf::max_threads());
    EXPECT_EQ(esf::resolve_threads(esf::max_threads()), esf::max_threads());
    EXPECT_THROW(esf::resolve_threads(-1), std::invalid_argument);
}

TEST(Parallel, EveryIndexRunsOnceOnASlotInRange) {
    for (int threads : {1, 2, 3, 0}) {
        const std::size_t count = 1000;
        std::vector<std::atomic<int>> runs(count);
        const int slots = esf::resolve_threads(threads);
        std::atomic<bool> slot_in_range{true};
        esf::parallel_for_slots(count, threads, [&](std::size_t i, int slot) {
            runs[i].fetch_add(1);
            if (slot < 0 || slot >= slots) slot_in_range = false;
        });
        for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(runs[i].load(), 1) << "index " << i;
        EXPECT_TRUE(slot_in_range.load()) << threads << " threads";
    }
}

TEST(Parallel, ABodysExceptionReachesTheCaller) {
    for (int threads : {1, 2}) {
        EXPECT_THROW(esf::parallel_for(100, threads,
                                       [](std::size_t i) {
                                           if (i == 37) throw std::runtime_error("index 37");
                                       }),
                     std::runtime_error);
    }
}

}  // namespace
