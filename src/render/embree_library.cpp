#include "render/embree_library.hpp"

#include <dlfcn.h>

#include <stdexcept>
#include <string>

#ifndef ESF_EMBREE_SONAME
#define ESF_EMBREE_SONAME "libembree3.so.3"
#endif
#ifndef ESF_EMBREE_PATH
#define ESF_EMBREE_PATH ""
#endif

namespace esf::detail {

namespace {

struct LoadedEmbree {
    EmbreeLibrary functions;
    std::string failure;  ///< why it could not be used; empty when it can
};

/// Looks up `name` in `handle` into `function`; notes the first missing one in `missing`.
template <typename F>
void look_up(void* handle, const char* name, F& function, std::string& missing) {
    function = reinterpret_cast<F>(dlsym(handle, name));
    if (function == nullptr && missing.empty()) missing = name;
}

LoadedEmbree load() {
    LoadedEmbree loaded;
    std::string tried;
    for (const char* path : {ESF_EMBREE_SONAME, ESF_EMBREE_PATH}) {
        if (*path == '\0') continue;
        void* handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (handle == nullptr) {
            const char* why = dlerror();
            tried += (tried.empty() ? "" : "; ") + std::string(path) + ": " +
                     (why != nullptr ? why : "cannot be opened");
            continue;
        }
        EmbreeLibrary& f = loaded.functions;
        std::string missing;
        look_up(handle, "rtcNewDevice", f.NewDevice, missing);
        look_up(handle, "rtcReleaseDevice", f.ReleaseDevice, missing);
        look_up(handle, "rtcGetDeviceError", f.GetDeviceError, missing);
        look_up(handle, "rtcSetDeviceErrorFunction", f.SetDeviceErrorFunction, missing);
        look_up(handle, "rtcGetDeviceProperty", f.GetDeviceProperty, missing);
        look_up(handle, "rtcNewScene", f.NewScene, missing);
        look_up(handle, "rtcReleaseScene", f.ReleaseScene, missing);
        look_up(handle, "rtcSetSceneFlags", f.SetSceneFlags, missing);
        look_up(handle, "rtcSetSceneBuildQuality", f.SetSceneBuildQuality, missing);
        look_up(handle, "rtcCommitScene", f.CommitScene, missing);
        look_up(handle, "rtcNewGeometry", f.NewGeometry, missing);
        look_up(handle, "rtcSetNewGeometryBuffer", f.SetNewGeometryBuffer, missing);
        look_up(handle, "rtcCommitGeometry", f.CommitGeometry, missing);
        look_up(handle, "rtcAttachGeometry", f.AttachGeometry, missing);
        look_up(handle, "rtcReleaseGeometry", f.ReleaseGeometry, missing);
        look_up(handle, "rtcIntersect4", f.Intersect4, missing);
        look_up(handle, "rtcIntersect8", f.Intersect8, missing);
        look_up(handle, "rtcIntersect16", f.Intersect16, missing);
        if (missing.empty()) return loaded;  // kept open for the life of the process
        tried += (tried.empty() ? "" : "; ") + std::string(path) + ": no function " + missing;
        loaded.functions = EmbreeLibrary{};
        dlclose(handle);
    }
    loaded.failure = "rendering needs Embree 3, which cannot be loaded (" + tried +
                     "); Debian: apt-get install libembree3-3";
    return loaded;
}

}  // namespace

const EmbreeLibrary& embree_library() {
    static const LoadedEmbree loaded = load();  // once per process, thread-safe
    if (!loaded.failure.empty()) throw std::runtime_error(loaded.failure);
    return loaded.functions;
}

}  // namespace esf::detail
