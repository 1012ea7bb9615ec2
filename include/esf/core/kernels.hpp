#pragma once
// Which SIMD kernels a computation runs: the one choice shared by the ESF descriptor
// (EsfOptions::kernels) and the k-NN index (KnnIndexOptions::kernels). The library is built
// without -march flags; the kernels are picked at run time from the CPU's feature flags, and
// every kernel set gives the same output bit for bit: only the speed depends on the choice.

#include <array>

#include "esf/core/enum_names.hpp"

namespace esf {

enum class Kernels {
    /// The widest kernels the CPU runs (the default): AVX-512 where it has it (the ESF line
    /// tracer counting cells with VPOPCNTDQ where present, and timing its versions to keep the
    /// fastest), else AVX2, else portable code.
    kBest,
    /// AVX-512 (F, BW, VL, DQ) kernels, without VPOPCNTDQ: what a CPU like Skylake-SP runs.
    kAvx512,
    /// AVX2 (with FMA, BMI, BMI2) kernels: what a CPU without AVX-512 runs.
    kAvx2,
    /// No SIMD kernels.
    kPortable,
};

/// "best", "avx512", "avx2", "portable" (to_string, parse_enum<Kernels>).
template <>
struct EnumNames<Kernels> {
    static constexpr const char* what = "kernels";
    static constexpr std::array<EnumName<Kernels>, 4> table{{{Kernels::kBest, "best"},
                                                             {Kernels::kAvx512, "avx512"},
                                                             {Kernels::kAvx2, "avx2"},
                                                             {Kernels::kPortable, "portable"}}};
};

/// Whether this CPU runs `kernels` (kBest and kPortable: always).
bool kernels_supported(Kernels kernels);

/// The widest kernels this CPU runs: kAvx512, kAvx2 or kPortable (never kBest).
Kernels best_kernels();

}  // namespace esf
