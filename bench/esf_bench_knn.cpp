// esf_bench_knn [--views N] [--queries Q] [--k K] [--seed S]: exact L1 k-NN over ESF-like
// descriptors with FLANN's exact linear index (flann::Index<flann::L1<float>> with
// LinearIndexParams, as PCL's recognition pipeline uses it) and with esf::KnnIndex, on the same
// data and queries in one process. Checks that the results agree, prints per-query times and
// batched throughput, and ends with "ratio: X" = FLANN time / esf time per query, one query at
// a time on one thread (the two run in turns, query by query, so that both meet the same load).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <flann/flann.hpp>
#include <string>
#include <vector>

#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/recognition/knn_index.hpp"
#include "recognition/knn_synthetic.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// CPU time of the calling thread.
double thread_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Args {
    std::size_t views = 300000;
    std::size_t queries = 100;
    std::size_t k = 10;
    unsigned long long seed = 1;
};

/// Reads the options; prints the usage and returns false for --help (`help` set) or bad input.
bool parse(int argc, char** argv, Args& args, bool& help) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const bool has_value = i + 1 < argc;
        if (arg == "--views" && has_value) {
            args.views = std::strtoull(argv[++i], nullptr, 10);
        } else if (arg == "--queries" && has_value) {
            args.queries = std::strtoull(argv[++i], nullptr, 10);
        } else if (arg == "--k" && has_value) {
            args.k = std::strtoull(argv[++i], nullptr, 10);
        } else if (arg == "--seed" && has_value) {
            args.seed = std::strtoull(argv[++i], nullptr, 10);
        } else {
            std::printf(
                "usage: esf_bench_knn [--views N] [--queries Q] [--k K] [--seed S]\n"
                "Exact L1 k-NN over N random ESF-like descriptors (640 bins, sum 1; default\n"
                "300000 views, 100 queries, k 10, seed 1): FLANN's linear L1 index and\n"
                "esf::KnnIndex side by side. Ends with 'ratio: FLANN time / esf time' per\n"
                "query, single thread.\n");
            help = arg == "-h" || arg == "--help";
            return false;
        }
    }
    if (args.views > 0 && args.queries > 0 && args.k > 0) return true;
    std::printf("esf_bench_knn: --views, --queries and --k must be > 0\n");
    return false;
}

}  // namespace

int main(int argc, char** argv) {
    Args args;
    bool help = false;
    if (!parse(argc, argv, args, help)) return help ? 0 : 1;
    const std::size_t dim = esf::kEsfSize;
    const int cores = esf::resolve_threads(0);

    auto start = Clock::now();
    std::vector<float> data = esf::detail::esf_like_rows(args.views, dim, args.seed);
    std::vector<float> queries = esf::detail::esf_like_rows(args.queries, dim, args.seed + 1);
    std::printf("esf_bench_knn: %zu views x %zu bins, %zu queries, k = %zu, %d cores\n", args.views,
                dim, args.queries, args.k, cores);
    std::printf("data: random ESF-like descriptors (seed %llu), generated in %.2f s\n", args.seed,
                seconds_since(start));

    // FLANN, as in PCL's recognition pipeline: exact linear search with L1 over floats.
    flann::Matrix<float> flann_data(data.data(), args.views, dim);
    flann::Index<flann::L1<float>> flann_index(flann_data, flann::LinearIndexParams());
    flann_index.buildIndex();

    start = Clock::now();
    const esf::KnnIndex index(data, dim);
    const double build = seconds_since(start);
    const double per_view =
        static_cast<double>(index.memory_bytes()) / static_cast<double>(index.views());
    std::printf(
        "esf KnnIndex: built in %.2f s (%d threads), kernel %s, %.0f bytes per view "
        "(%zu float row + %zu sketch + 8 error), %.1f MB in all\n",
        build, cores, esf::to_string(index.kernels()), per_view, dim * sizeof(float),
        index.sketch_bytes(), static_cast<double>(index.memory_bytes()) / 1e6);

    // One query at a time on this thread, FLANN and esf in turns, so that both meet the same
    // machine load; wall and CPU time of this thread.
    std::vector<std::size_t> flann_ids(args.queries * args.k);
    std::vector<float> flann_dists(args.queries * args.k);
    std::vector<esf::KnnResult> single(args.queries);
    index.search({queries.data(), dim}, args.k);  // warm up
    double flann_wall = 0, flann_cpu = 0, ours_wall = 0, ours_cpu = 0;
    for (std::size_t q = 0; q < args.queries; ++q) {
        flann::Matrix<float> query(queries.data() + q * dim, 1, dim);
        flann::Matrix<std::size_t> ids(flann_ids.data() + q * args.k, 1, args.k);
        flann::Matrix<float> dists(flann_dists.data() + q * args.k, 1, args.k);
        auto cpu = thread_seconds();
        start = Clock::now();
        flann_index.knnSearch(query, ids, dists, args.k, flann::SearchParams());
        flann_wall += seconds_since(start);
        flann_cpu += thread_seconds() - cpu;

        cpu = thread_seconds();
        start = Clock::now();
        single[q] = index.search({queries.data() + q * dim, dim}, args.k);
        ours_wall += seconds_since(start);
        ours_cpu += thread_seconds() - cpu;
    }
    const double n = static_cast<double>(args.queries);
    double exact_mean = 0.0;
    for (const auto& r : single) exact_mean += static_cast<double>(r.exact_distances);
    exact_mean /= n;
    std::printf("flann LinearIndex L1<float>: %8.3f ms per query (1 thread; %.3f ms CPU)\n",
                flann_wall / n * 1e3, flann_cpu / n * 1e3);
    std::printf(
        "esf KnnIndex:                %8.3f ms per query (1 thread; %.3f ms CPU; "
        "%.0f of %zu rows refined on average)\n",
        ours_wall / n * 1e3, ours_cpu / n * 1e3, exact_mean, args.views);

    start = Clock::now();
    const auto batch_one = index.search_batch(queries, args.k, 1);
    const double batch_one_time = seconds_since(start);
    start = Clock::now();
    const auto batch_all = index.search_batch(queries, args.k, 0);
    const double batch_all_time = seconds_since(start);
    std::printf(
        "esf KnnIndex batch:          %8.3f ms per query (1 thread), %.0f queries/s; "
        "%.0f queries/s on %d threads\n",
        batch_one_time / static_cast<double>(args.queries) * 1e3,
        static_cast<double>(args.queries) / batch_one_time,
        static_cast<double>(args.queries) / batch_all_time, cores);

    // Agreement: the same views in the same order; FLANN sums in float, so a swap of two
    // neighbours whose float distances differ by less than 1e-5 is a near tie, not an error.
    std::size_t identical = 0, near_ties = 0, disagreements = 0;
    double max_difference = 0.0;
    for (std::size_t q = 0; q < args.queries; ++q) {
        const auto& ours = single[q].neighbours;
        bool same = ours.size() == args.k;
        bool tie_only = same;
        for (std::size_t i = 0; i < ours.size() && i < args.k; ++i) {
            const double flann_d = flann_dists[q * args.k + i];
            max_difference = std::max(max_difference, std::fabs(flann_d - ours[i].distance));
            if (ours[i].view != flann_ids[q * args.k + i]) {
                same = false;
                tie_only = tie_only && std::fabs(flann_d - ours[i].distance) <= 1e-5;
            }
            if (batch_one[q].neighbours[i].view != ours[i].view ||
                batch_all[q].neighbours[i].view != ours[i].view ||
                batch_all[q].neighbours[i].distance != ours[i].distance)
                tie_only = same = false;
        }
        if (same)
            ++identical;
        else if (tie_only)
            ++near_ties;
        else
            ++disagreements;
    }
    std::printf(
        "agreement: %zu of %zu queries identical to flann (views and order), %zu differ "
        "by near ties only, %zu disagree; max |distance difference| %.2g\n",
        identical, args.queries, near_ties, disagreements, max_difference);
    std::printf("flann / esf CPU time per query: %.1f\n", flann_cpu / ours_cpu);
    std::printf("ratio: %.1f\n", flann_wall / ours_wall);
    return disagreements == 0 ? 0 : 1;
}
