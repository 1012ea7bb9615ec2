#pragma once
// Internal: the one CPU detection of the project. The library is built without -march flags;
// each SIMD kernel carries ESF_TARGET_AVX512, ESF_TARGET_AVX512_VPOPCNTDQ or ESF_TARGET_AVX2
// and runs only where avx512_available(), avx512_vpopcntdq_available() or avx2_available()
// says so. Every kernel set gives the same output bit for bit as the portable code. The public
// choice of kernels is esf::Kernels (esf/core/kernels.hpp).

#include "esf/core/kernels.hpp"

#define ESF_TARGET_AVX512 \
    __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,avx2,fma,bmi,bmi2")))
#define ESF_TARGET_AVX512_VPOPCNTDQ                                               \
    __attribute__((                                                               \
        target("avx512f,avx512bw,avx512vl,avx512dq,avx512vpopcntdq,avx2,fma,bmi," \
               "bmi2")))
#define ESF_TARGET_AVX2 __attribute__((target("avx2,fma,bmi,bmi2")))

namespace esf::detail {

/// True when this CPU runs ESF_TARGET_AVX512 code.
inline bool avx512_available() {
    static const bool available = [] {  // CPU features do not change while running
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
               __builtin_cpu_supports("bmi2");
    }();
    return available;
}

/// True when this CPU runs ESF_TARGET_AVX512_VPOPCNTDQ code (Ice Lake, Zen 4 and later).
inline bool avx512_vpopcntdq_available() {
    static const bool available = [] {
        __builtin_cpu_init();
        return avx512_available() && __builtin_cpu_supports("avx512vpopcntdq");
    }();
    return available;
}

/// True when this CPU runs ESF_TARGET_AVX2 code.
inline bool avx2_available() {
    static const bool available = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    }();
    return available;
}

/// The widest kernels a pass may run: each gives the same output bit for bit.
enum class SimdLevel { kPortable, kAvx2, kAvx512 };

/// The widest level this CPU runs.
inline SimdLevel best_simd_level() {
    if (avx512_available()) return SimdLevel::kAvx512;
    return avx2_available() ? SimdLevel::kAvx2 : SimdLevel::kPortable;
}

/// The level `kernels` asks for on this CPU: at most the widest it runs (kBest: that one).
inline SimdLevel simd_level(Kernels kernels) {
    const SimdLevel best = best_simd_level();
    switch (kernels) {
        case Kernels::kBest:
            return best;
        case Kernels::kAvx512:
            return best;  // nothing wider than AVX-512
        case Kernels::kAvx2:
            return avx2_available() ? SimdLevel::kAvx2 : SimdLevel::kPortable;
        case Kernels::kPortable:
            break;
    }
    return SimdLevel::kPortable;
}

}  // namespace esf::detail
