#pragma once
// Triangle meshes: loading CAD files (Assimp: PLY, OBJ, OFF, STL, glTF/GLB, DAE, 3DS, ...) and
// writing PLY.

#include <Eigen/Core>
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

/// Throws std::invalid_argument when the mesh has no triangle, a triangle index outside
/// [0, vertices.size()) or a non-finite vertex. `what` names the mesh in the message.
void check_mesh(const Mesh& mesh, const std::string& what = "mesh");

/// Loads every mesh of a file, merged into one (node transforms applied). Points and lines are
/// dropped, polygons triangulated, identical vertices joined, triangles with a repeated vertex
/// dropped and unused vertices removed; coordinates are kept in file units. Throws esf::IoError
/// naming the file when it cannot be read, holds no triangle or has a non-finite vertex.
/// Assimp never prints: its default logger is left unset.
Mesh load_mesh(const std::string& path);

/// Writes a binary little-endian PLY (vertex x y z float, face vertex_indices); atomic (temporary
/// file + rename). Throws std::invalid_argument when check_mesh() fails and esf::IoError naming
/// the file when it cannot be written.
void write_ply_mesh(const std::string& path, const Mesh& mesh);

}  // namespace esf
