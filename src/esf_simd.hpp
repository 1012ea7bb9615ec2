#pragma once
// Internal: the one CPU feature set of the ESF descriptor's AVX-512 kernels (per-point passes,
// triangles, line tracing), checked once at run time. The library is built without -march
// flags; each kernel carries ESF_TARGET_AVX512 and runs only where esf_avx512_available().

#define ESF_TARGET_AVX512 \
    __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,avx2,fma,bmi,bmi2")))

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

}  // namespace esf::detail
