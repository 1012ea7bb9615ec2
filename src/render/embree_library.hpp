#pragma once
// Internal: Embree 3, opened on the first rendering call instead of linked, so that programs
// that never render (describing, searching, segmenting; `esf --version`) do not load it and its
// start-up cost. The functions the renderer calls are looked up once per process.

#include <embree3/rtcore.h>

namespace esf::detail {

/// Embree's functions, as the renderer calls them (rtcFoo as Foo).
struct EmbreeLibrary {
    decltype(&rtcNewDevice) NewDevice = nullptr;
    decltype(&rtcReleaseDevice) ReleaseDevice = nullptr;
    decltype(&rtcGetDeviceError) GetDeviceError = nullptr;
    decltype(&rtcSetDeviceErrorFunction) SetDeviceErrorFunction = nullptr;
    decltype(&rtcGetDeviceProperty) GetDeviceProperty = nullptr;
    decltype(&rtcNewScene) NewScene = nullptr;
    decltype(&rtcReleaseScene) ReleaseScene = nullptr;
    decltype(&rtcSetSceneFlags) SetSceneFlags = nullptr;
    decltype(&rtcSetSceneBuildQuality) SetSceneBuildQuality = nullptr;
    decltype(&rtcCommitScene) CommitScene = nullptr;
    decltype(&rtcNewGeometry) NewGeometry = nullptr;
    decltype(&rtcSetNewGeometryBuffer) SetNewGeometryBuffer = nullptr;
    decltype(&rtcCommitGeometry) CommitGeometry = nullptr;
    decltype(&rtcAttachGeometry) AttachGeometry = nullptr;
    decltype(&rtcReleaseGeometry) ReleaseGeometry = nullptr;
    decltype(&rtcIntersect4) Intersect4 = nullptr;
    decltype(&rtcIntersect8) Intersect8 = nullptr;
    decltype(&rtcIntersect16) Intersect16 = nullptr;
};

/// Opens Embree on the first call (by its soname, as the system loader finds it, then by the
/// path it was built against) and returns its functions; thread-safe. Throws
/// std::runtime_error naming the library and every place tried when it cannot be opened or
/// lacks one of the functions.
const EmbreeLibrary& embree_library();

}  // namespace esf::detail
