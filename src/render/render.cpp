#include "esf/render/render.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "esf/core/parallel.hpp"
#include "esf/render/view_sphere.hpp"
#include "render/embree_library.hpp"

namespace esf {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// ---------------------------------------------------------------------------------------------
// Embree scene: an RAII device + scene holding triangle meshes (one geometry each), committed
// once; intersect calls are const and thread-safe.

class EmbreeScene {
  public:
    EmbreeScene()
        : rtc_(detail::embree_library()),
          device_(rtc_.NewDevice("verbose=0"), rtc_.ReleaseDevice),
          scene_(nullptr, rtc_.ReleaseScene) {
        if (device_ == nullptr)
            throw std::runtime_error(std::string("embree: cannot create a device: ") +
                                     error_name(rtc_.GetDeviceError(nullptr)));
        rtc_.SetDeviceErrorFunction(device_.get(), &EmbreeScene::on_error, this);
        scene_.reset(rtc_.NewScene(device_.get()));
        throw_if_error("creating the scene");
        // Robust traversal: no cracks between neighbouring triangles, whatever the ray.
        rtc_.SetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
        rtc_.SetSceneBuildQuality(scene_.get(), RTC_BUILD_QUALITY_HIGH);
        const bool ray16 =
            rtc_.GetDeviceProperty(device_.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED);
        const bool ray8 =
            rtc_.GetDeviceProperty(device_.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED);
        packet_ = ray16 ? 16 : ray8 ? 8 : 4;
        throw_if_error("creating the scene");
    }
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    /// Adds a mesh whose vertices are mapped by `transform` (computed in double) to the scene
    /// frame; returns its geometry id (0, 1, ... in order of addition).
    unsigned add(const Mesh& mesh, const Eigen::Affine3d& transform) {
        RTCGeometry geometry = rtc_.NewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
        if (geometry == nullptr) throw_if_error("creating a mesh");
        auto* vertices = static_cast<float*>(
            rtc_.SetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                      3 * sizeof(float), mesh.vertices.size()));
        auto* indices = static_cast<unsigned*>(
            rtc_.SetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                      3 * sizeof(unsigned), mesh.triangles.size()));
        if (vertices == nullptr || indices == nullptr) {
            rtc_.ReleaseGeometry(geometry);
            throw_if_error("allocating mesh buffers");
            throw std::runtime_error("embree: cannot allocate mesh buffers");
        }
        for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
            const Eigen::Vector3f p = (transform * mesh.vertices[i].cast<double>()).cast<float>();
            if (!p.allFinite()) {
                rtc_.ReleaseGeometry(geometry);
                throw std::invalid_argument("mesh vertex " + std::to_string(i) +
                                            " is out of float range once placed");
            }
            for (int k = 0; k < 3; ++k) vertices[3 * i + static_cast<std::size_t>(k)] = p[k];
        }
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
            for (int k = 0; k < 3; ++k)
                indices[3 * i + static_cast<std::size_t>(k)] =
                    static_cast<unsigned>(mesh.triangles[i][k]);
        }
        rtc_.CommitGeometry(geometry);
        const unsigned id = rtc_.AttachGeometry(scene_.get(), geometry);
        rtc_.ReleaseGeometry(geometry);
        throw_if_error("adding a mesh");
        return id;
    }

    void commit() {
        rtc_.CommitScene(scene_.get());
        throw_if_error("building the scene");
    }

    RTCScene scene() const { return scene_.get(); }
    int packet() const { return packet_; }

  private:
    static const char* error_name(RTCError error) {
        switch (error) {
            case RTC_ERROR_NONE:
                return "no error";
            case RTC_ERROR_INVALID_ARGUMENT:
                return "invalid argument";
            case RTC_ERROR_INVALID_OPERATION:
                return "invalid operation";
            case RTC_ERROR_OUT_OF_MEMORY:
                return "out of memory";
            case RTC_ERROR_UNSUPPORTED_CPU:
                return "unsupported CPU";
            case RTC_ERROR_CANCELLED:
                return "cancelled";
            default:
                return "unknown error";
        }
    }
    static void on_error(void* user, RTCError code, const char* message) {
        auto* self = static_cast<EmbreeScene*>(user);
        const std::lock_guard lock(self->mutex_);
        if (self->message_.empty())
            self->message_ =
                std::string(error_name(code)) + (message ? std::string(": ") + message : "");
    }
    void throw_if_error(const char* what) {
        const RTCError code = rtc_.GetDeviceError(device_.get());
        if (code == RTC_ERROR_NONE) return;
        std::string message;
        {
            const std::lock_guard lock(mutex_);
            message = message_.empty() ? error_name(code) : message_;
            message_.clear();
        }
        if (code == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
        throw std::runtime_error(std::string("embree: ") + what + ": " + message);
    }

    std::mutex mutex_;                  // guards message_, written by Embree's error callback
    std::string message_;               // (declared first: outlives the device)
    const detail::EmbreeLibrary& rtc_;  // (declared before the device and scene it creates)
    std::unique_ptr<RTCDeviceTy, decltype(&rtcReleaseDevice)> device_;
    std::unique_ptr<RTCSceneTy, decltype(&rtcReleaseScene)> scene_;
    int packet_ = 4;
};

// ---------------------------------------------------------------------------------------------
// Ray casting of a pixel rectangle, a band of rows at a time, in packets of N rays (TW x TH
// pixel tiles).

struct PixelRect {
    int u0 = 0, u1 = -1;  // inclusive
    int v0 = 0, v1 = -1;
    bool empty() const { return u1 < u0 || v1 < v0; }
    int width() const { return u1 - u0 + 1; }
};

/// One pixel's first hit along its ray: `t` is the camera depth z (rays have d_cam.z = 1),
/// `cos_incidence` = |cos| of the angle between ray and surface normal, `geometry` the hit
/// geometry id or RTC_INVALID_GEOMETRY_ID.
struct Hit {
    float t;
    float cos_incidence;
    unsigned geometry;
};

/// A sphere (camera frame) that holds everything the rays can hit: rays missing it are not cast.
struct SphereBound {
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    float radius = std::numeric_limits<float>::infinity();

    /// Whether the ray through normalised image point (x, y) can meet the sphere.
    bool may_hit(float x, float y) const {
        const float along = centre.x() * x + centre.y() * y + centre.z();  // c . d, d = (x, y, 1)
        const float excess = centre.squaredNorm() - radius * radius;       // < 0: camera inside
        return excess < 0.0f || (along > 0.0f && along * along >= excess * (x * x + y * y + 1.0f));
    }
};

/// The camera in the scene frame: origin and rotation camera -> scene.
struct RayFrame {
    Eigen::Vector3f origin;
    Eigen::Matrix3f rotation;
};

RayFrame ray_frame(const Eigen::Isometry3d& scene_to_camera) {
    const Eigen::Isometry3d camera_to_scene = scene_to_camera.inverse();
    return {camera_to_scene.translation().cast<float>(), camera_to_scene.linear().cast<float>()};
}

template <int N>
void intersect(const detail::EmbreeLibrary& rtc, const int* valid, RTCScene scene,
               RTCIntersectContext* context, RTCRayHitNt<N>& packet) {
    if constexpr (N == 16) {
        rtc.Intersect16(valid, scene, context, reinterpret_cast<RTCRayHit16*>(&packet));
    } else if constexpr (N == 8) {
        rtc.Intersect8(valid, scene, context, reinterpret_cast<RTCRayHit8*>(&packet));
    } else {
        static_assert(N == 4);
        rtc.Intersect4(valid, scene, context, reinterpret_cast<RTCRayHit4*>(&packet));
    }
}

/// Casts rows [v, v + TH) ∩ rect of `rect` and stores hits in band[row * rect.width() + column].
template <int N, int TW, int TH>
void cast_band(RTCScene scene, const CameraIntrinsics& camera, const RayFrame& frame,
               const SphereBound& bound, const PixelRect& rect, int v, std::vector<Hit>& band) {
    static_assert(TW * TH == N);
    const int width = rect.width();
    band.resize(static_cast<std::size_t>(TH * width));
    const detail::EmbreeLibrary& rtc = detail::embree_library();
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);  // inline in Embree's header
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHitNt<N> packet;
    alignas(64) int valid[N];
    // Embree leaves origins and directions as they are: only tfar and the hit are set per tile.
    for (int k = 0; k < N; ++k) {
        packet.ray.org_x[k] = frame.origin.x();
        packet.ray.org_y[k] = frame.origin.y();
        packet.ray.org_z[k] = frame.origin.z();
        packet.ray.tnear[k] = 0.0f;
        packet.ray.time[k] = 0.0f;
        packet.ray.mask[k] = 0xffffffffu;
        packet.ray.id[k] = static_cast<unsigned>(k);
        packet.ray.flags[k] = 0;
    }
    // Normalised image coordinates of the band's columns and rows.
    std::vector<float> xs(static_cast<std::size_t>(width + TW));
    for (std::size_t i = 0; i < xs.size(); ++i)
        xs[i] = static_cast<float>((rect.u0 + static_cast<double>(i) - camera.cx) / camera.fx);
    float ys[TH];
    for (int k = 0; k < TH; ++k) ys[k] = static_cast<float>((v + k - camera.cy) / camera.fy);
    const Eigen::Matrix3f& r = frame.rotation;
    for (int u = rect.u0; u <= rect.u1; u += TW) {
        bool any = false;
        for (int k = 0; k < N; ++k) {
            const int pu = u + k % TW;
            const int pv = v + k / TW;
            valid[k] = 0;
            if (pu > rect.u1 || pv > rect.v1) continue;
            const float xn = xs[static_cast<std::size_t>(pu - rect.u0)];
            const float yn = ys[k / TW];
            Hit& hit = band[static_cast<std::size_t>((k / TW) * width + pu - rect.u0)];
            hit.geometry = RTC_INVALID_GEOMETRY_ID;
            if (!bound.may_hit(xn, yn)) continue;
            valid[k] = -1;
            any = true;
            packet.ray.dir_x[k] = r(0, 0) * xn + r(0, 1) * yn + r(0, 2);
            packet.ray.dir_y[k] = r(1, 0) * xn + r(1, 1) * yn + r(1, 2);
            packet.ray.dir_z[k] = r(2, 0) * xn + r(2, 1) * yn + r(2, 2);
            packet.ray.tfar[k] = kInfinity;
            packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        if (!any) continue;
        intersect<N>(rtc, valid, scene, &context, packet);
        for (int k = 0; k < N; ++k) {
            if (valid[k] == 0 || packet.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
            Hit& hit = band[static_cast<std::size_t>((k / TW) * width + u + k % TW - rect.u0)];
            hit.geometry = packet.hit.geomID[k];
            hit.t = packet.ray.tfar[k];
            const Eigen::Vector3f n(packet.hit.Ng_x[k], packet.hit.Ng_y[k], packet.hit.Ng_z[k]);
            const Eigen::Vector3f d(packet.ray.dir_x[k], packet.ray.dir_y[k], packet.ray.dir_z[k]);
            const float norms = std::sqrt(n.squaredNorm() * d.squaredNorm());
            hit.cos_incidence = norms > 0.0f ? std::abs(n.dot(d)) / norms : 0.0f;
        }
    }
}

int band_height(int packet) { return packet == 16 ? 4 : 2; }

void cast_band(int packet, RTCScene scene, const CameraIntrinsics& camera, const RayFrame& frame,
               const SphereBound& bound, const PixelRect& rect, int v, std::vector<Hit>& band) {
    switch (packet) {
        case 16:
            cast_band<16, 4, 4>(scene, camera, frame, bound, rect, v, band);
            break;
        case 8:
            cast_band<8, 4, 2>(scene, camera, frame, bound, rect, v, band);
            break;
        default:
            cast_band<4, 2, 2>(scene, camera, frame, bound, rect, v, band);
            break;
    }
}

/// Range [lo, hi] of u = f * tan(angle) + c over the directions that can meet a disk of radius r
/// centred at (lateral, depth) in one coordinate plane of the camera; false when none can.
bool projected_range(double lateral, double depth, double r, double f, double c, int size, int& lo,
                     int& hi) {
    const double half_pi = std::numbers::pi / 2.0;
    const double distance = std::hypot(lateral, depth);
    double a_lo = -half_pi;
    double a_hi = half_pi;
    if (distance > r) {
        const double a = std::atan2(lateral, depth);
        const double half = std::asin(r / distance);
        a_lo = a - half;
        a_hi = a + half;
        if (a_lo >= half_pi || a_hi <= -half_pi) return false;
    }
    const double u_lo = a_lo <= -half_pi ? -1e30 : f * std::tan(a_lo) + c;
    const double u_hi = a_hi >= half_pi ? 1e30 : f * std::tan(a_hi) + c;
    // One pixel of margin against rounding; pixel centres are integers.
    lo = static_cast<int>(std::max(0.0, std::ceil(std::max(u_lo, -1e9) - 1.0)));
    hi = static_cast<int>(std::min(size - 1.0, std::floor(std::min(u_hi, 1e9) + 1.0)));
    return lo <= hi;
}

/// Pixels whose rays can meet the sphere (camera frame centre, radius).
PixelRect sphere_rect(const Eigen::Vector3d& centre, double radius,
                      const CameraIntrinsics& camera) {
    PixelRect rect;
    if (!projected_range(centre.x(), centre.z(), radius, camera.fx, camera.cx, camera.width,
                         rect.u0, rect.u1) ||
        !projected_range(centre.y(), centre.z(), radius, camera.fy, camera.cy, camera.height,
                         rect.v0, rect.v1))
        return PixelRect{};
    return rect;
}

/// Depth measured at a hit (NaN when the sensor model drops it).
float measure(const Hit& hit, SensorNoise noise, double fx, std::uint64_t seed, std::uint64_t key,
              std::uint64_t pixel) {
    if (noise == SensorNoise::kNone) return hit.t;
    PixelRandom random(seed, key, pixel);
    return static_cast<float>(kinect_measure(hit.t, hit.cos_incidence, fx, random));
}

// Embree asserts (and aborts) on rays whose origin or direction exceeds about 1.8e18, and float
// rays lose all precision long before: cameras stay within kMaxCameraDistance metres of the
// scene's origin and a pixel's ray direction (u - cx) / fx, (v - cy) / fy within kMaxRaySlope.
constexpr double kMaxCameraDistance = 1e6;
constexpr double kMaxRaySlope = 1e6;

void validate_rays(const CameraIntrinsics& camera, const char* what) {
    const double slope_x =
        std::max(std::abs(camera.cx), std::abs(camera.width - camera.cx)) / camera.fx;
    const double slope_y =
        std::max(std::abs(camera.cy), std::abs(camera.height - camera.cy)) / camera.fy;
    if (!(slope_x <= kMaxRaySlope && slope_y <= kMaxRaySlope))
        throw std::invalid_argument(
            std::string(what) +
            ": the camera's principal point lies too far outside the image for its focal "
            "lengths (a pixel's ray would be more than 1e6 times wider than deep)");
}

void validate_camera_distance(double distance, const char* what) {
    if (!(distance <= kMaxCameraDistance))
        throw std::invalid_argument(std::string(what) + " must be at most 1e6 m, got " +
                                    std::to_string(distance) + " m");
}

void validate_noise(SensorNoise noise) {
    if (noise != SensorNoise::kNone && noise != SensorNoise::kKinect)
        throw std::invalid_argument("unknown sensor noise value");
}

}  // namespace

// -------------------------------------------------------------------------------------------------

struct MeshRenderer::Impl {
    RenderOptions options;
    EmbreeScene embree;
    std::vector<Eigen::Vector3d> directions;  // the whole view sphere
    std::vector<int> kept;                    // view sphere indices of the cameras in use
    Eigen::Vector3d centre;                   // file units
    double scale = 1.0;
    double radius = 0.0;  // metres
    double distance = 0.0;

    // scene frame: (file coordinates - centre) * scale
    Points cast(const Eigen::Isometry3d& scene_to_camera, std::uint64_t key) const {
        const CameraIntrinsics& camera = options.camera;
        const PixelRect rect = sphere_rect(scene_to_camera.translation(), radius, camera);
        Points points;
        if (rect.empty()) return points;
        const RayFrame frame = ray_frame(scene_to_camera);
        const SphereBound bound{scene_to_camera.translation().cast<float>(),
                                static_cast<float>(radius)};
        const int packet = embree.packet();
        const int band_rows = band_height(packet);
        const int width = rect.width();
        points.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(width) / 2);
        std::vector<Hit> band;
        for (int v = rect.v0; v <= rect.v1; v += band_rows) {
            cast_band(packet, embree.scene(), camera, frame, bound, rect, v, band);
            const int rows = std::min(band_rows, rect.v1 - v + 1);
            for (int row = 0; row < rows; ++row) {
                const int pv = v + row;
                const float yn = static_cast<float>((pv - camera.cy) / camera.fy);
                for (int column = 0; column < width; ++column) {
                    const Hit& hit = band[static_cast<std::size_t>(row * width + column)];
                    if (hit.geometry == RTC_INVALID_GEOMETRY_ID) continue;
                    const int pu = rect.u0 + column;
                    const std::uint64_t pixel =
                        static_cast<std::uint64_t>(pv) * static_cast<std::uint64_t>(camera.width) +
                        static_cast<std::uint64_t>(pu);
                    const float z =
                        measure(hit, options.noise, camera.fx, options.seed, key, pixel);
                    if (!std::isfinite(z)) continue;
                    const float xn = static_cast<float>((pu - camera.cx) / camera.fx);
                    points.emplace_back(xn * z, yn * z, z);
                }
            }
        }
        return points;
    }
};

MeshRenderer::MeshRenderer(const Mesh& mesh, const RenderOptions& options)
    : impl_(std::make_unique<Impl>()) {
    check_mesh(mesh, "render");
    options.camera.validate();
    validate_noise(options.noise);
    impl_->directions = view_sphere(options.level);
    if (!(std::isfinite(options.min_elevation) && std::isfinite(options.max_elevation) &&
          -90.0 <= options.min_elevation && options.min_elevation <= options.max_elevation &&
          options.max_elevation <= 90.0))
        throw std::invalid_argument(
            "camera elevations must satisfy -90 <= min <= max <= 90 degrees, got [" +
            std::to_string(options.min_elevation) + ", " + std::to_string(options.max_elevation) +
            "]");
    for (std::size_t i = 0; i < impl_->directions.size(); ++i) {
        const double z = std::clamp(impl_->directions[i].z(), -1.0, 1.0);
        const double elevation = std::asin(z) * 180.0 / std::numbers::pi;
        if (elevation >= options.min_elevation && elevation <= options.max_elevation)
            impl_->kept.push_back(static_cast<int>(i));
    }
    if (impl_->kept.empty())
        throw std::invalid_argument("no camera of view sphere level " +
                                    std::to_string(options.level) + " has an elevation in [" +
                                    std::to_string(options.min_elevation) + ", " +
                                    std::to_string(options.max_elevation) + "] degrees");
    if (!(std::isfinite(options.fill_fraction) && options.fill_fraction > 0.0))
        throw std::invalid_argument("fill fraction must be positive and finite, got " +
                                    std::to_string(options.fill_fraction));
    if (!(std::isfinite(options.scale) && options.scale > 0.0))
        throw std::invalid_argument("model scale must be positive and finite, got " +
                                    std::to_string(options.scale));
    if (options.target_extent &&
        !(std::isfinite(*options.target_extent) && *options.target_extent > 0.0))
        throw std::invalid_argument("target extent must be positive and finite, got " +
                                    std::to_string(*options.target_extent));
    resolve_threads(options.threads);
    impl_->options = options;

    const Eigen::Vector3d lo = mesh.min_corner().cast<double>();
    const Eigen::Vector3d hi = mesh.max_corner().cast<double>();
    const double extent = (hi - lo).maxCoeff();
    if (!(extent > 0.0)) throw std::invalid_argument("mesh has zero extent (all vertices equal)");
    impl_->centre = (lo + hi) / 2.0;
    impl_->scale = options.target_extent ? *options.target_extent / extent : options.scale;
    // Slightly enlarged: the scene holds float vertices.
    impl_->radius = mesh.bounding_radius() * impl_->scale * (1.0 + 1e-5);

    const CameraIntrinsics& camera = options.camera;
    validate_rays(camera, "renderer");
    if (options.max_distance &&
        !(std::isfinite(*options.max_distance) && *options.max_distance > 0.0))
        throw std::invalid_argument("largest camera distance must be positive and finite, got " +
                                    std::to_string(*options.max_distance));
    if (options.max_distance)
        validate_camera_distance(*options.max_distance, "largest camera distance");
    if (options.distance) {
        if (!(std::isfinite(*options.distance) && *options.distance > impl_->radius))
            throw std::invalid_argument(
                "camera distance must be finite and exceed the model's bounding sphere radius (" +
                std::to_string(impl_->radius) + " m), got " + std::to_string(*options.distance));
        impl_->distance = *options.distance;
    } else {
        // The sphere seen from distance d spans 2 f r / sqrt(d^2 - r^2) pixels.
        const double side = camera.width <= camera.height ? camera.width : camera.height;
        const double f = camera.width <= camera.height ? camera.fx : camera.fy;
        const double ratio = 2.0 * f / (options.fill_fraction * side);
        impl_->distance = impl_->radius * std::sqrt(1.0 + ratio * ratio);
    }
    // Also where a huge model or focal length puts the camera (fx = 1e30: about 1e30 m).
    validate_camera_distance(impl_->distance, "camera distance");

    Eigen::Affine3d to_scene = Eigen::Affine3d::Identity();
    to_scene.linear() *= impl_->scale;
    to_scene.translation() = -impl_->scale * impl_->centre;
    impl_->embree.add(mesh, to_scene);
    impl_->embree.commit();
}

MeshRenderer::~MeshRenderer() = default;
MeshRenderer::MeshRenderer(MeshRenderer&&) noexcept = default;
MeshRenderer& MeshRenderer::operator=(MeshRenderer&&) noexcept = default;

std::size_t MeshRenderer::view_count() const { return impl_->kept.size(); }

int MeshRenderer::view_index(std::size_t index) const {
    if (index >= impl_->kept.size())
        throw std::invalid_argument("view index " + std::to_string(index) + " out of range (" +
                                    std::to_string(impl_->kept.size()) + " views)");
    return impl_->kept[index];
}

RenderedView MeshRenderer::render_view(std::size_t index) const {
    const auto sphere_index = static_cast<std::size_t>(view_index(index));
    double distance = impl_->distance;
    if (impl_->options.distance && impl_->options.max_distance &&
        *impl_->options.max_distance > impl_->distance) {
        // A draw of its own: the pixels' noise uses keys below width * height.
        PixelRandom random(impl_->options.seed, sphere_index, ~std::uint64_t{0});
        distance += random.uniform() * (*impl_->options.max_distance - impl_->distance);
    }
    const Eigen::Isometry3d scene_to_camera =
        look_at(distance * impl_->directions[sphere_index], Eigen::Vector3d::Zero());
    RenderedView view;
    view.index = static_cast<int>(sphere_index);
    view.points = impl_->cast(scene_to_camera, sphere_index);
    Eigen::Affine3d file_to_scene = Eigen::Affine3d::Identity();
    file_to_scene.linear() *= impl_->scale;
    file_to_scene.translation() = -impl_->scale * impl_->centre;
    view.pose = (scene_to_camera * file_to_scene).matrix().cast<float>();
    return view;
}

Points MeshRenderer::render_pose(const Eigen::Isometry3d& scaled_model_to_camera,
                                 std::uint64_t noise_key) const {
    if (!scaled_model_to_camera.matrix().allFinite())
        throw std::invalid_argument("render_pose: pose is not finite");
    // scene = scaled model - scale * centre
    Eigen::Isometry3d scene_to_scaled = Eigen::Isometry3d::Identity();
    scene_to_scaled.translation() = impl_->scale * impl_->centre;
    const Eigen::Isometry3d scene_to_camera = scaled_model_to_camera * scene_to_scaled;
    validate_camera_distance(scene_to_camera.translation().norm(),
                             "render_pose: the camera's distance from the model");
    return impl_->cast(scene_to_camera, noise_key);
}

double MeshRenderer::scale() const { return impl_->scale; }
Eigen::Vector3d MeshRenderer::centre() const { return impl_->centre; }
double MeshRenderer::radius() const { return impl_->radius; }
double MeshRenderer::camera_distance() const { return impl_->distance; }
const RenderOptions& MeshRenderer::options() const { return impl_->options; }

std::vector<RenderedView> render_views(const Mesh& mesh, const RenderOptions& options) {
    const MeshRenderer renderer(mesh, options);
    std::vector<RenderedView> views(renderer.view_count());
    parallel_for(views.size(), options.threads,
                 [&](std::size_t i) { views[i] = renderer.render_view(i); });
    return views;
}

// -------------------------------------------------------------------------------------------------

PointCloud render_scene(std::span<const SceneObject> objects,
                        const Eigen::Isometry3d& world_to_camera, const SceneOptions& options) {
    const CameraIntrinsics& camera = options.camera;
    camera.validate();
    validate_noise(options.noise);
    if (!world_to_camera.matrix().allFinite())
        throw std::invalid_argument("render_scene: camera pose is not finite");
    validate_rays(camera, "render_scene");
    validate_camera_distance(world_to_camera.translation().norm(),
                             "render_scene: the camera's distance from the world origin");
    if (!(options.table_half_size > 0.0))
        throw std::invalid_argument("render_scene: table half size must be positive");
    if (!(options.max_depth > 0.0))
        throw std::invalid_argument("render_scene: max depth must be positive");
    resolve_threads(options.threads);

    EmbreeScene embree;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const std::string name = "scene object " + std::to_string(i);
        if (objects[i].mesh == nullptr) throw std::invalid_argument(name + ": no mesh");
        if (!objects[i].model_to_world.matrix().allFinite())
            throw std::invalid_argument(name + ": pose is not finite");
        check_mesh(*objects[i].mesh, name);
        embree.add(*objects[i].mesh, Eigen::Affine3d(objects[i].model_to_world.matrix()));
    }
    embree.commit();

    const auto width = static_cast<std::size_t>(camera.width);
    const auto height = static_cast<std::size_t>(camera.height);
    PointCloud cloud;
    cloud.width = static_cast<std::uint32_t>(width);
    cloud.height = static_cast<std::uint32_t>(height);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cloud.points.assign(width * height, Eigen::Vector3f(nan, nan, nan));
    cloud.labels.assign(width * height, kSceneLabelNone);

    const RayFrame frame = ray_frame(world_to_camera);
    const Eigen::Vector3d origin = world_to_camera.inverse().translation();
    const Eigen::Matrix3d rotation = world_to_camera.linear().transpose();  // camera -> world
    const int packet = embree.packet();
    const int band_rows = band_height(packet);
    const PixelRect rect{0, camera.width - 1, 0, camera.height - 1};
    const std::size_t bands =
        (height + static_cast<std::size_t>(band_rows) - 1) / static_cast<std::size_t>(band_rows);
    parallel_for(bands, options.threads, [&](std::size_t b) {
        std::vector<Hit> band;
        const int v = static_cast<int>(b) * band_rows;
        if (!objects.empty()) {
            cast_band(packet, embree.scene(), camera, frame, SphereBound{}, rect, v, band);
        } else {
            band.assign(static_cast<std::size_t>(band_rows) * width,
                        Hit{kInfinity, 0.0f, RTC_INVALID_GEOMETRY_ID});
        }
        const int rows = std::min(band_rows, camera.height - v);
        for (int row = 0; row < rows; ++row) {
            const int pv = v + row;
            const double yn = (pv - camera.cy) / camera.fy;
            for (int pu = 0; pu < camera.width; ++pu) {
                Hit hit =
                    band[static_cast<std::size_t>(row) * width + static_cast<std::size_t>(pu)];
                if (hit.geometry == RTC_INVALID_GEOMETRY_ID) hit.t = kInfinity;
                const double xn = (pu - camera.cx) / camera.fx;
                std::uint32_t label = hit.geometry == RTC_INVALID_GEOMETRY_ID
                                          ? kSceneLabelNone
                                          : kSceneLabelFirstObject + hit.geometry;
                if (options.table_plane) {
                    const Eigen::Vector3d d = rotation * Eigen::Vector3d(xn, yn, 1.0);
                    if (d.z() != 0.0) {
                        const double t = -origin.z() / d.z();
                        const Eigen::Vector3d p = origin + t * d;
                        if (t > 0.0 && t < hit.t && std::abs(p.x()) <= options.table_half_size &&
                            std::abs(p.y()) <= options.table_half_size) {
                            hit.t = static_cast<float>(t);
                            hit.cos_incidence = static_cast<float>(std::abs(d.z()) / d.norm());
                            label = kSceneLabelTable;
                        }
                    }
                }
                if (label == kSceneLabelNone) continue;
                const std::size_t pixel =
                    static_cast<std::size_t>(pv) * width + static_cast<std::size_t>(pu);
                const float z = measure(hit, options.noise, camera.fx, options.seed, 0, pixel);
                if (!std::isfinite(z) || z > options.max_depth) continue;
                cloud.points[pixel] =
                    Eigen::Vector3f(static_cast<float>(xn) * z, static_cast<float>(yn) * z, z);
                cloud.labels[pixel] = label;
            }
        }
    });
    return cloud;
}

}  // namespace esf
