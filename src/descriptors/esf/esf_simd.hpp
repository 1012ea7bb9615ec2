#pragma once
// Internal: which SIMD kernels the ESF descriptor runs (EsfKernels, the public choice) on this
// CPU (core/simd.hpp detects it).

#include "core/simd.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::detail {

/// kBest: AVX-512 where the CPU has it, else AVX2 where it has that; kAvx2: AVX2 where the CPU
/// has it; kPortable: none.
inline SimdLevel simd_level(EsfKernels kernels) {
    switch (kernels) {
        case EsfKernels::kBest:
            return best_simd_level();
        case EsfKernels::kAvx2:
            return avx2_available() ? SimdLevel::kAvx2 : SimdLevel::kPortable;
        case EsfKernels::kPortable:
            break;
    }
    return SimdLevel::kPortable;
}

}  // namespace esf::detail
