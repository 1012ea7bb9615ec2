// Where files installed beside esf's libraries lie (installed_files.hpp).

#include "core/installed_files.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace esf::detail {
namespace {

/// The directory of the binary (program or shared object) this code is linked into.
std::filesystem::path own_directory() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&installed_file_candidates), &info) == 0 ||
        info.dli_fname == nullptr)
        return {};
    std::error_code error;
    std::filesystem::path path = std::filesystem::canonical(info.dli_fname, error);
    if (error) path = std::filesystem::canonical("/proc/self/exe", error);
    return error ? std::filesystem::path{} : path.parent_path();
}

}  // namespace

std::vector<std::string> installed_file_candidates(const char* env, const std::string& file,
                                                   const char* build_path,
                                                   const char* install_path) {
    std::vector<std::string> out;
    if (const char* chosen = std::getenv(env); chosen != nullptr && *chosen != '\0') {
        out.emplace_back(chosen);
        return out;
    }
    if (const std::filesystem::path dir = own_directory(); !dir.empty()) {
        out.push_back((dir.parent_path() / "lib" / "esf" / file).string());
        out.push_back((dir / file).string());
    }
    for (const char* fixed : {build_path, install_path})
        if (fixed != nullptr && *fixed != '\0') out.emplace_back(fixed);
    return out;
}

}  // namespace esf::detail
