#pragma once
// Where the benchmarks find the shared real data: $ESF_DATA, else ../shared/data beside the
// repository (ESF_DATA_DEFAULT, set for every benchmark by bench/CMakeLists.txt).

#include <cstdlib>
#include <filesystem>

namespace esf::bench {

inline std::filesystem::path data_dir() {
    if (const char* env = std::getenv("ESF_DATA"); env && *env) return env;
    return ESF_DATA_DEFAULT;
}

}  // namespace esf::bench
