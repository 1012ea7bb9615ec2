#pragma once
// A model's surface as points: what verification aligns to an object (pose_verification.hpp),
// sampled from the mesh at training and stored with the database, so that recognition needs no
// meshes at hand.

#include <cstddef>
#include <cstdint>
#include <string>

#include "esf/core/point_cloud.hpp"
#include "esf/mesh/mesh.hpp"

namespace esf {

/// A model's surface, sampled evenly by area: points and outward normals in metres, model frame
/// (the mesh file's coordinates times `scale`).
struct ModelSurface {
    Points points;
    Points normals;
    double scale = 1.0;     ///< file units -> metres
    double diameter = 0.0;  ///< metres: twice the mesh's bounding radius

    bool operator==(const ModelSurface&) const = default;
};

/// The most samples a model surface may have (what a database stores and reads back).
inline constexpr std::size_t kMaxModelSurfacePoints = 1000000;

/// Samples `count` points (area-weighted triangles, uniform within each; seeded). Normals follow
/// the triangles' winding; when most of them point towards the bounding box centre (a mesh wound
/// clockwise), all are turned round. Throws std::invalid_argument for a bad mesh (check_mesh), a
/// mesh without area, count 0 or a scale that is not positive and finite.
ModelSurface sample_model_surface(const Mesh& mesh, double scale, std::size_t count,
                                  std::uint64_t seed);

/// Throws std::invalid_argument, starting with `what`, for a surface without points, normals that
/// are not one per point, a point or normal that is not finite, a normal that is not of unit
/// length (within 1e-3), or a scale or diameter that is not positive and finite.
void check_model_surface(const ModelSurface& surface, const std::string& what);

}  // namespace esf
