// Finds and opens the PCL baselines module (libesf_baselines.so) on first use; see
// baseline_descriptors.hpp for the search order.

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/installed_files.hpp"
#include "descriptors/pcl/baseline_descriptors.hpp"

#ifndef ESF_BASELINES_BUILD_PATH
#define ESF_BASELINES_BUILD_PATH ""
#endif
#ifndef ESF_BASELINES_INSTALL_PATH
#define ESF_BASELINES_INSTALL_PATH ""
#endif

namespace esf::detail {

namespace {

constexpr const char* kModuleFile = "libesf_baselines.so";

struct LoadedModule {
    const BaselineModule* module = nullptr;
    std::string failure;  ///< why none loaded: each place tried and what happened
};

LoadedModule load() {
    LoadedModule loaded;
    for (const std::string& path : installed_file_candidates(
             "ESF_BASELINES", kModuleFile, ESF_BASELINES_BUILD_PATH, ESF_BASELINES_INSTALL_PATH)) {
        std::error_code error;
        if (!std::filesystem::is_regular_file(path, error)) {
            loaded.failure += (loaded.failure.empty() ? "" : "; ") + path + ": not found";
            continue;
        }
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (handle == nullptr) {
            const char* why = dlerror();
            loaded.failure += (loaded.failure.empty() ? "" : "; ") + path + ": " +
                              (why != nullptr ? why : "cannot be opened");
            continue;
        }
        using Entry = const BaselineModule* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, "esf_baseline_module"));
        const BaselineModule* module = entry != nullptr ? entry() : nullptr;
        if (module == nullptr || module->abi != kBaselineModuleAbi || module->make == nullptr) {
            loaded.failure += (loaded.failure.empty() ? "" : "; ") + path +
                              ": not an esf baselines module of this version";
            dlclose(handle);
            continue;
        }
        loaded.module = module;  // kept open for the life of the process
        return loaded;
    }
    if (loaded.failure.empty()) loaded.failure = "no place to look";
    return loaded;
}

const LoadedModule& loaded_module() {
    static const LoadedModule loaded = load();  // once per process, thread-safe
    return loaded;
}

}  // namespace

const BaselineModule& baseline_module(const std::string& name) {
    const LoadedModule& loaded = loaded_module();
    if (loaded.module == nullptr)
        throw std::invalid_argument(
            name + " is a PCL baseline, and the baselines module " + kModuleFile +
            " cannot be loaded (" + loaded.failure +
            "); build esf with PCL (Debian: apt-get install libpcl-dev; cmake -DESF_WITH_PCL=ON) "
            "or set ESF_BASELINES to the module's path");
    return *loaded.module;
}

bool baseline_module_available() { return loaded_module().module != nullptr; }

}  // namespace esf::detail
