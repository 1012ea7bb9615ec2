// ESF descriptors from the `esf` Python module: describe, describe_batch.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "bindings.hpp"
#include "esf/core/enum_names.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::python {

namespace {

/// Estimator pools by options, so that repeated describe() calls reuse their workspaces (their
/// set-up is about a quarter of a description). A pool is thread-safe; the map is locked, and a
/// caller keeps its pool alive while the map forgets it.
class PoolCache {
  public:
    std::shared_ptr<const EsfEstimatorPool> get(const EsfOptions& options) {
        const Key key{options.samples, options.grid_size, options.seed,
                      static_cast<int>(options.sampler)};
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = pools_.find(key);
        if (it != pools_.end()) return it->second;
        if (pools_.size() >= kMaxPools) pools_.clear();
        auto pool = std::make_shared<const EsfEstimatorPool>(options);
        pools_.emplace(key, pool);
        return pool;
    }

  private:
    using Key = std::tuple<int, int, std::uint64_t, int>;
    static constexpr std::size_t kMaxPools = 8;
    std::mutex mutex_;
    std::map<Key, std::shared_ptr<const EsfEstimatorPool>> pools_;
};

PoolCache& pool_cache() {
    static PoolCache cache;
    return cache;
}

EsfOptions esf_options(int samples, std::uint64_t seed, const std::string& sampler, int grid) {
    EsfOptions options;
    options.samples = samples;
    options.seed = seed;
    options.sampler = parse_enum<EsfSampler>(sampler);
    options.grid_size = grid;
    return options;
}

py::array_t<float> descriptor_array(const EsfDescriptor& d) {
    return py::array_t<float>(static_cast<py::ssize_t>(d.size()), d.data());
}

py::array_t<float> describe(const py::object& points, int samples, std::uint64_t seed,
                            const std::string& sampler, int grid) {
    const PointsArg arg = points_arg(points);
    const EsfOptions options = esf_options(samples, seed, sampler, grid);
    EsfResult result;
    {
        py::gil_scoped_release release;
        const std::shared_ptr<const EsfEstimatorPool> pool = pool_cache().get(options);
        result = pool->compute(arg.points);
    }
    return descriptor_array(result.descriptor);
}

py::array_t<float> describe_batch(const py::sequence& clouds, int samples, std::uint64_t seed,
                                  const std::string& sampler, int grid, int threads) {
    std::vector<PointsArg> args;
    args.reserve(clouds.size());
    for (std::size_t i = 0; i < clouds.size(); ++i)
        args.push_back(points_arg(clouds[i], "clouds[" + std::to_string(i) + "]"));
    const EsfOptions options = esf_options(samples, seed, sampler, grid);
    py::array_t<float> out({static_cast<py::ssize_t>(args.size()), py::ssize_t{kEsfSize}});
    float* data = out.mutable_data();
    std::vector<std::string> errors(args.size());
    {
        py::gil_scoped_release release;
        resolve_threads(threads);  // rejects negative counts
        const std::shared_ptr<const EsfEstimatorPool> pool = pool_cache().get(options);
        parallel_for(args.size(), threads, [&](std::size_t i) {
            try {
                const EsfResult r = pool->compute(args[i].points);
                std::copy(r.descriptor.begin(), r.descriptor.end(), data + i * kEsfSize);
            } catch (const std::invalid_argument& e) {
                errors[i] = e.what();
            }
        });
    }
    for (std::size_t i = 0; i < errors.size(); ++i)
        if (!errors[i].empty())
            throw std::invalid_argument("clouds[" + std::to_string(i) + "]: " + errors[i]);
    return out;
}

}  // namespace

void bind_descriptors(py::module_& m) {
    const EsfOptions defaults;
    m.def("describe", &describe, py::arg("points"), py::kw_only(),
          py::arg("samples") = defaults.samples, py::arg("seed") = defaults.seed,
          py::arg("sampler") = to_string(defaults.sampler), py::arg("grid") = defaults.grid_size,
          "The 640-bin ESF descriptor of a cloud (float32, L1-normalised): the same numbers as "
          "``esf describe`` for the same points, seed, samples and sampler ('fast' or 'pcl', "
          "bit-exact pcl::ESFEstimation). Non-finite points are dropped first. Raises ValueError "
          "for a cloud without descriptor (fewer than 3 finite points, all on one line). The "
          "GIL is released while computing.");
    m.def("describe_batch", &describe_batch, py::arg("clouds"), py::kw_only(),
          py::arg("samples") = defaults.samples, py::arg("seed") = defaults.seed,
          py::arg("sampler") = to_string(defaults.sampler), py::arg("grid") = defaults.grid_size,
          py::arg("threads") = 0,
          "Describes many clouds in parallel (``threads``, 0 = all cores): an (M, 640) float32 "
          "array, row i = describe(clouds[i], seed=seed). Raises ValueError naming the first "
          "cloud that has no descriptor.");
}

}  // namespace esf::python
