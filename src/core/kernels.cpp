#include "esf/core/kernels.hpp"

#include "core/simd.hpp"

namespace esf {

bool kernels_supported(Kernels kernels) {
    switch (kernels) {
        case Kernels::kAvx512:
            return detail::avx512_available();
        case Kernels::kAvx2:
            return detail::avx2_available();
        case Kernels::kBest:
        case Kernels::kPortable:
            break;
    }
    return true;
}

Kernels best_kernels() {
    switch (detail::best_simd_level()) {
        case detail::SimdLevel::kAvx512:
            return Kernels::kAvx512;
        case detail::SimdLevel::kAvx2:
            return Kernels::kAvx2;
        case detail::SimdLevel::kPortable:
            break;
    }
    return Kernels::kPortable;
}

}  // namespace esf
