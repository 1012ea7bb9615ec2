#pragma once
// Triangle meshes: loading CAD files (Assimp, in a helper process: PLY, OBJ, OFF, STL, glTF/GLB,
// DAE, 3DS, ...) and writing PLY.

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace esf {

struct Mesh {
    std::vector<Eigen::Vector3f> vertices;
    std::vector<Eigen::Vector3i>
        triangles;  ///< vertex indices, counter-clockwise seen from outside

    /// Corners of the axis-aligned bounding box of the vertices; throw std::invalid_argument
    /// when the mesh has no vertex.
    Eigen::Vector3f min_corner() const;
    Eigen::Vector3f max_corner() const;
    /// Radius of the sphere around the bounding box's centre that holds every vertex (file
    /// units, accumulated in double); throws std::invalid_argument when the mesh has no vertex.
    double bounding_radius() const;
};

/// The mesh with every vertex times `factor` (computed in double), about the file's origin.
Mesh scaled_mesh(Mesh mesh, double factor);

/// Throws std::invalid_argument when the mesh has no triangle, a triangle index outside
/// [0, vertices.size()) or a non-finite vertex. `what` names the mesh in the message.
void check_mesh(const Mesh& mesh, const std::string& what = "mesh");

/// Default bounds on the helper process that imports a mesh (load_mesh): its address space and
/// its time.
inline constexpr std::size_t kMeshImportAddressSpaceMiB = 4096;
inline constexpr double kMeshImportSeconds = 120.0;

/// Bounds on one mesh import.
struct MeshImportLimits {
    std::size_t address_space_mib = kMeshImportAddressSpaceMiB;  ///< > 0
    double seconds = kMeshImportSeconds;                         ///< wall time (and CPU time), > 0
};

/// Loads every mesh of a file, merged into one (node transforms applied). Points and lines are
/// dropped, polygons triangulated, identical vertices joined, triangles with a repeated vertex
/// dropped and unused vertices removed; coordinates are kept in file units. Throws esf::IoError
/// naming the file when it cannot be read, holds no triangle or has a non-finite vertex.
/// The import (Assimp) runs in a helper process, esf_mesh_import (installed in lib/esf/; the
/// environment variable ESF_MESH_IMPORTER may name it), with the limits given: a crash, a time
/// or memory limit reached there is an esf::IoError naming the file and the reason, as is a
/// missing helper. Nothing is printed.
Mesh load_mesh(const std::string& path);
Mesh load_mesh(const std::string& path, const MeshImportLimits& limits);

/// Writes a binary little-endian PLY (vertex x y z float, face vertex_indices); atomic (temporary
/// file + rename). The data never starts with a line feed byte, which Assimp 5.2 reads as part of
/// the header: where the first vertex's x would start so, another vertex is written first (the
/// two indices swapped), or, where every x would, each vertex leads with a zero `uchar pad`. The
/// geometry reads back exactly. Throws std::invalid_argument when check_mesh() fails and
/// esf::IoError naming the file when it cannot be written.
void write_ply_mesh(const std::string& path, const Mesh& mesh);

}  // namespace esf
