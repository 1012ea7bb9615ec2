#include "recognition/knn_kernels.hpp"

#include <cstdlib>

#include "core/simd.hpp"

namespace esf::detail {

namespace {

double exact_scalar(const float* a, const float* b, const float* w, std::size_t n, double limit) {
    double lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    std::size_t i = 0;
    for (; i + kExactCheck < n; i += kExactCheck) {
        exact_tail(a, b, w, i, i + kExactCheck, lane);
        if (const double partial = combine_lanes(lane); partial > limit) return partial;
    }
    exact_tail(a, b, w, i, n, lane);
    return combine_lanes(lane);
}

std::size_t sketch_scalar(const std::uint8_t* rows, std::size_t count, std::size_t stride,
                          const std::uint8_t* query, const std::uint32_t* weight, double unit,
                          const double* row_error, double query_error, double limit,
                          std::uint32_t first_row, double* bound, std::uint32_t* row) {
    const std::size_t lanes = stride / 8;
    std::size_t kept = 0;
    for (std::size_t r = 0; r < count; ++r) {
        const std::uint8_t* codes = rows + r * stride;
        std::uint64_t sum = 0;
        for (std::size_t l = 0; l < lanes; ++l) {
            std::uint32_t sad = 0;
            for (std::size_t j = 8 * l; j < 8 * l + 8; ++j)
                sad += static_cast<std::uint32_t>(
                    std::abs(static_cast<int>(codes[j]) - static_cast<int>(query[j])));
            sum += std::uint64_t{weight[l]} * sad;
        }
        const double row_bound = (unit * static_cast<double>(sum) - row_error[r]) - query_error;
        if (row_bound <= limit)
            kept = keep_rows(&row_bound, 1u, first_row + static_cast<std::uint32_t>(r), kept, bound,
                             row);
    }
    return kept;
}

}  // namespace

KnnKernels knn_kernels(Kernels kernels) {
    if (kernels == Kernels::kBest) kernels = best_kernels();
    if (kernels == Kernels::kAvx512) return {exact_avx512, sketch_avx512};
    if (kernels == Kernels::kAvx2) return {exact_avx2, sketch_avx2};
    return {exact_scalar, sketch_scalar};
}

}  // namespace esf::detail
