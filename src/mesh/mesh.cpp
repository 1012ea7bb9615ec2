// Mesh: its bounding box, its checks and PLY output. Loading is mesh_load.cpp (the helper
// process that imports) and mesh_import.cpp (the import itself).

#include "esf/mesh/mesh.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.hpp"
#include "esf/core/error.hpp"

namespace esf {

Eigen::Vector3f Mesh::min_corner() const {
    if (vertices.empty()) throw std::invalid_argument("min_corner: mesh has no vertex");
    Eigen::Vector3f m = vertices.front();
    for (const auto& v : vertices) m = m.cwiseMin(v);
    return m;
}

Eigen::Vector3f Mesh::max_corner() const {
    if (vertices.empty()) throw std::invalid_argument("max_corner: mesh has no vertex");
    Eigen::Vector3f m = vertices.front();
    for (const auto& v : vertices) m = m.cwiseMax(v);
    return m;
}

double Mesh::bounding_radius() const {
    const Eigen::Vector3d centre =
        (min_corner().cast<double>() + max_corner().cast<double>()) / 2.0;
    double radius = 0.0;
    for (const auto& v : vertices) radius = std::max(radius, (v.cast<double>() - centre).norm());
    return radius;
}

Mesh scaled_mesh(Mesh mesh, double factor) {
    for (Eigen::Vector3f& v : mesh.vertices) v = (v.cast<double>() * factor).cast<float>();
    return mesh;
}

void check_mesh(const Mesh& mesh, const std::string& what) {
    if (mesh.triangles.empty()) throw std::invalid_argument(what + ": mesh has no triangle");
    if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw std::invalid_argument(what + ": too many vertices");
    const int n = static_cast<int>(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const Eigen::Vector3i& t = mesh.triangles[i];
        if (t.minCoeff() < 0 || t.maxCoeff() >= n)
            throw std::invalid_argument(what + ": triangle " + std::to_string(i) +
                                        " has a vertex index outside [0, " + std::to_string(n) +
                                        ")");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        if (!mesh.vertices[i].allFinite())
            throw std::invalid_argument(what + ": vertex " + std::to_string(i) + " is not finite");
    }
}

namespace {

// The first byte a binary little-endian PLY holds of x: its least significant byte.
unsigned char first_byte(float x) {
    return static_cast<unsigned char>(std::bit_cast<std::uint32_t>(x));
}

}  // namespace

void write_ply_mesh(const std::string& path, const Mesh& mesh) {
    check_mesh(mesh, path);
    // Assimp's PLY reader (5.2) takes a line feed right after end_header for the end of the
    // header and reads every value one byte late: binary data must not start with 0x0A. That is
    // x of the first vertex; another vertex goes first instead (its index swapped with 0), or,
    // where every x would start so, each vertex leads with a zero byte (`uchar pad`, which
    // readers leave alone).
    std::size_t first = 0;
    while (first < mesh.vertices.size() && first_byte(mesh.vertices[first].x()) == '\n') ++first;
    const bool pad = first == mesh.vertices.size() && first > 0;
    if (pad) first = 0;
    const auto written = [first](std::size_t i) { return i == 0 ? first : i == first ? 0 : i; };
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by esf\n";
    header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
    if (pad) header += "property uchar pad\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    header += "element face " + std::to_string(mesh.triangles.size()) + "\n";
    header += "property list uchar int vertex_indices\nend_header\n";

    std::string bytes = std::move(header);
    bytes.reserve(bytes.size() + mesh.vertices.size() * 12 + mesh.triangles.size() * 13);
    const auto put = [&bytes](const void* data, std::size_t size) {
        const char* from = static_cast<const char*>(data);
        if constexpr (std::endian::native == std::endian::little) {
            bytes.append(from, size);
        } else {
            for (std::size_t i = size; i-- > 0;) bytes.push_back(from[i]);
        }
    };
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3f& v = mesh.vertices[written(i)];
        if (pad) bytes.push_back('\0');
        for (int k = 0; k < 3; ++k) put(&v[k], sizeof(float));
    }
    for (const auto& t : mesh.triangles) {
        bytes.push_back(static_cast<char>(3));
        for (int k = 0; k < 3; ++k) {
            const auto index = static_cast<std::int32_t>(written(static_cast<std::size_t>(t[k])));
            put(&index, sizeof(index));
        }
    }
    detail::write_file_atomically(path, bytes);
}

}  // namespace esf
