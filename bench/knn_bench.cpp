// Google Benchmark of the exact L1 k-NN index over random ESF-like descriptors: single searches
// per kernel and database size, batches on one and on all threads, the build, and the two
// distance kernels on their own. The side-by-side run against FLANN is esf_bench_knn.

#include <benchmark/benchmark.h>

#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/recognition/knn_index.hpp"
#include "recognition/knn_kernels.hpp"
#include "recognition/knn_synthetic.hpp"

namespace {

using esf::Kernels;
using esf::KnnIndex;

constexpr std::size_t kDim = esf::kEsfSize;
constexpr std::size_t kQueries = 64;

const std::vector<float>& database(std::size_t views) {
    static std::map<std::size_t, std::vector<float>> cache;
    auto it = cache.find(views);
    if (it == cache.end())
        it = cache.emplace(views, esf::detail::esf_like_rows(views, kDim, 1)).first;
    return it->second;
}

const std::vector<float>& queries() {
    static const std::vector<float> rows = esf::detail::esf_like_rows(kQueries, kDim, 2);
    return rows;
}

const KnnIndex& index(std::size_t views, Kernels kernel) {
    static std::map<std::pair<std::size_t, Kernels>, std::unique_ptr<KnnIndex>> cache;
    auto& slot = cache[{views, kernel}];
    if (!slot) {
        esf::KnnIndexOptions options;
        options.kernels = kernel;
        slot = std::make_unique<KnnIndex>(database(views), kDim, options);
    }
    return *slot;
}

Kernels kernel_arg(const benchmark::State& state, int i) {
    return static_cast<Kernels>(state.range(i));
}

void BM_Search(benchmark::State& state) {
    const auto views = static_cast<std::size_t>(state.range(0));
    const auto k = static_cast<std::size_t>(state.range(1));
    const Kernels kernel = kernel_arg(state, 2);
    if (!esf::kernels_supported(kernel)) {
        state.SkipWithError("kernel not supported by this CPU");
        return;
    }
    const KnnIndex& idx = index(views, kernel);
    const std::vector<float>& q = queries();
    std::size_t i = 0, exact = 0;
    for (auto _ : state) {
        const esf::KnnResult r = idx.search({q.data() + (i % kQueries) * kDim, kDim}, k);
        exact += r.exact_distances;
        benchmark::DoNotOptimize(r.neighbours.data());
        ++i;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(i));
    state.SetLabel(esf::to_string(kernel));
    state.counters["exact_per_query"] =
        static_cast<double>(exact) / static_cast<double>(std::max<std::size_t>(i, 1));
}
BENCHMARK(BM_Search)
    ->ArgNames({"views", "k", "kernel"})
    ->ArgsProduct({{10000, 100000},
                   {10},
                   {static_cast<int>(Kernels::kPortable), static_cast<int>(Kernels::kAvx2),
                    static_cast<int>(Kernels::kAvx512)}})
    ->Args({100000, 1, static_cast<int>(Kernels::kBest)})
    ->Args({100000, 50, static_cast<int>(Kernels::kBest)})
    ->Args({300000, 10, static_cast<int>(Kernels::kBest)})
    ->Unit(benchmark::kMicrosecond);

void BM_SearchBatch(benchmark::State& state) {
    const auto views = static_cast<std::size_t>(state.range(0));
    const int threads = static_cast<int>(state.range(1));
    const KnnIndex& idx = index(views, Kernels::kBest);
    for (auto _ : state) {
        const auto r = idx.search_batch(queries(), 10, threads);
        benchmark::DoNotOptimize(r.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kQueries));
}
BENCHMARK(BM_SearchBatch)
    ->ArgNames({"views", "threads"})
    ->ArgsProduct({{100000, 300000}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Build(benchmark::State& state) {
    const auto views = static_cast<std::size_t>(state.range(0));
    const std::vector<float>& rows = database(views);
    for (auto _ : state) {
        const KnnIndex idx(rows, kDim);
        benchmark::DoNotOptimize(idx.memory_bytes());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * views));
}
BENCHMARK(BM_Build)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ExactDistance(benchmark::State& state) {
    const Kernels kernel = kernel_arg(state, 0);
    if (!esf::kernels_supported(kernel)) {
        state.SkipWithError("kernel not supported by this CPU");
        return;
    }
    const auto exact = esf::detail::knn_kernels(kernel).exact;
    const std::vector<float>& rows = database(10000);
    const std::vector<float> weights(kDim, 1.0f);
    std::size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(exact(queries().data(), rows.data() + (i % 64) * kDim,
                                       weights.data(), kDim,
                                       std::numeric_limits<double>::infinity()));
        ++i;
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(i));
    state.SetBytesProcessed(static_cast<std::int64_t>(i * kDim * sizeof(float)));
    state.SetLabel(esf::to_string(kernel));
}
BENCHMARK(BM_ExactDistance)
    ->ArgName("kernel")
    ->DenseRange(static_cast<int>(Kernels::kAvx512), static_cast<int>(Kernels::kPortable));

void BM_SketchBounds(benchmark::State& state) {
    const Kernels kernel = kernel_arg(state, 0);
    if (!esf::kernels_supported(kernel)) {
        state.SkipWithError("kernel not supported by this CPU");
        return;
    }
    // 4096 rows of a 64-byte sketch (ESF's), from cache.
    constexpr std::size_t kRows = 4096, kStride = 64;
    std::vector<std::uint8_t> rows(kRows * kStride), query(kStride, 100);
    for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<std::uint8_t>(i * 37);
    const std::vector<std::uint32_t> weight(kStride / 8, 1000);
    const std::vector<double> row_error(kRows, 1e-3);
    std::vector<double> bound(kRows);
    std::vector<std::uint32_t> row(kRows);
    const auto sketch = esf::detail::knn_kernels(kernel).sketch;
    // A limit of 0 keeps none of these rows, as a search's cut keeps a few in a thousand.
    for (auto _ : state) {
        benchmark::DoNotOptimize(sketch(rows.data(), kRows, kStride, query.data(), weight.data(),
                                        1e-7, row_error.data(), 1e-3, 0.0, 0, bound.data(),
                                        row.data()));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kRows));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * kRows * kStride));
    state.SetLabel(esf::to_string(kernel));
}
BENCHMARK(BM_SketchBounds)
    ->ArgName("kernel")
    ->DenseRange(static_cast<int>(Kernels::kAvx512), static_cast<int>(Kernels::kPortable));

}  // namespace

BENCHMARK_MAIN();
