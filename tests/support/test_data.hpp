#pragma once
// Locates the shared real data (../shared/data beside the repository, or $ESF_DATA).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace esf::test {

inline std::filesystem::path data_dir() {
    if (const char* env = std::getenv("ESF_DATA"); env && *env) return env;
    return ESF_DATA_DEFAULT;
}

inline std::filesystem::path data_file(const std::string& relative) {
    return data_dir() / relative;
}

}  // namespace esf::test

/// Skips the test, saying where the data was looked for, when a shared data file is missing.
#define ESF_REQUIRE_DATA(relative)                                                      \
    do {                                                                                \
        if (!std::filesystem::exists(::esf::test::data_file(relative)))                 \
            GTEST_SKIP() << "shared data missing: " << ::esf::test::data_file(relative) \
                         << " (set ESF_DATA to the folder holding meshes/ and real/)";  \
    } while (0)
