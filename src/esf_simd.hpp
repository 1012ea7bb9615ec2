#pragma once
// Internal: the CPU feature sets of the ESF descriptor's SIMD kernels (per-point passes,
// triangles, line tracing), checked once at run time. The library is built without -march
// flags; each kernel carries ESF_TARGET_AVX512 or ESF_TARGET_AVX2 and runs only where
// esf_avx512_available() or esf_avx2_available().

#include "esf/esf_descriptor.hpp"

#define ESF_TARGET_AVX512 \
    __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,avx2,fma,bmi,bmi2")))
#define ESF_TARGET_AVX2 __attribute__((target("avx2,fma,bmi,bmi2")))

namespace esf::detail {

/// True when this CPU runs ESF_TARGET_AVX512 code.
inline bool esf_avx512_available() {
    static const bool available = [] {  // CPU features do not change while running
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
               __builtin_cpu_supports("bmi2");
    }();
    return available;
}

/// True when this CPU runs ESF_TARGET_AVX2 code.
inline bool esf_avx2_available() {
    static const bool available = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    }();
    return available;
}

/// The widest kernels a pass may run: each gives the same output bit for bit.
enum class SimdLevel { kPortable, kAvx2, kAvx512 };

/// kBest: AVX-512 where the CPU has it, else AVX2 where it has that; kAvx2: AVX2 where the CPU
/// has it; kPortable: none.
inline SimdLevel simd_level(EsfKernels kernels) {
    switch (kernels) {
        case EsfKernels::kBest:
            if (esf_avx512_available()) return SimdLevel::kAvx512;
            return esf_avx2_available() ? SimdLevel::kAvx2 : SimdLevel::kPortable;
        case EsfKernels::kAvx2:
            return esf_avx2_available() ? SimdLevel::kAvx2 : SimdLevel::kPortable;
        case EsfKernels::kPortable:
            break;
    }
    return SimdLevel::kPortable;
}

}  // namespace esf::detail
