#include "esf/mesh/mesh.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/core/error.hpp"
#include "support/error_of.hpp"
#include "support/recursive_collada.hpp"
#include "support/test_data.hpp"

namespace {

namespace fs = std::filesystem;
using Triangle = std::array<std::array<float, 3>, 3>;

class MeshTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_mesh_test_" +
                std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string write(const std::string& name, const std::string& text) const {
        const std::string path = (dir_ / name).string();
        std::ofstream(path, std::ios::binary) << text;
        return path;
    }

    fs::path dir_;
};

// Each triangle as its three corner positions, rotated so the smallest corner comes first
// (the winding is kept), so meshes compare whatever their vertex numbering.
std::multiset<Triangle> triangle_set(const esf::Mesh& mesh) {
    std::multiset<Triangle> out;
    for (const auto& t : mesh.triangles) {
        Triangle tri;
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3f& v = mesh.vertices[static_cast<std::size_t>(t[k])];
            tri[static_cast<std::size_t>(k)] = {v.x(), v.y(), v.z()};
        }
        const auto first = std::min_element(tri.begin(), tri.end());
        std::rotate(tri.begin(), first, tri.end());
        out.insert(tri);
    }
    return out;
}

std::multiset<Triangle> triangles_of(std::initializer_list<Triangle> list) {
    std::multiset<Triangle> out;
    for (Triangle tri : list) {
        const auto first = std::min_element(tri.begin(), tri.end());
        std::rotate(tri.begin(), first, tri.end());
        out.insert(tri);
    }
    return out;
}

using esf::test::error_of;

TEST_F(MeshTest, ObjQuadIsTriangulatedAndObjectsAreMerged) {
    // A unit quad (one polygon, two triangles after triangulation) and a separate triangle in a
    // second object: 3 triangles, 4 + 3 vertices.
    const std::string path = write("two.obj",
                                   "o quad\n"
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                   "f 1 2 3 4\n"
                                   "o tri\n"
                                   "v 0 0 5\nv 2 0 5\nv 0 3 5\n"
                                   "f 5 6 7\n");
    const esf::Mesh mesh = esf::load_mesh(path);
    EXPECT_EQ(mesh.triangles.size(), 3u);
    EXPECT_EQ(mesh.vertices.size(), 7u);
    EXPECT_EQ(mesh.min_corner(), Eigen::Vector3f(0, 0, 0));
    EXPECT_EQ(mesh.max_corner(), Eigen::Vector3f(2, 3, 5));
    EXPECT_EQ(triangle_set(mesh), triangles_of({{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}},
                                                {{{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                                                {{{0, 0, 5}, {2, 0, 5}, {0, 3, 5}}}}));
}

TEST_F(MeshTest, OffTetrahedron) {
    const std::string path = write("tet.off",
                                   "OFF\n4 4 6\n"
                                   "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                   "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const esf::Mesh mesh = esf::load_mesh(path);
    EXPECT_EQ(mesh.vertices.size(), 4u);
    EXPECT_EQ(triangle_set(mesh), triangles_of({{{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}},
                                                {{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}},
                                                {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}},
                                                {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}}));
}

TEST_F(MeshTest, StlCornersAreJoined) {
    // STL stores three corners per facet: 12 corners of a tetrahedron become 4 vertices.
    std::string stl = "solid tet\n";
    const std::array<std::array<const char*, 3>, 4> facets = {{{"0 0 0", "0 1 0", "1 0 0"},
                                                               {"0 0 0", "1 0 0", "0 0 1"},
                                                               {"0 0 0", "0 0 1", "0 1 0"},
                                                               {"1 0 0", "0 1 0", "0 0 1"}}};
    for (const auto& f : facets) {
        stl += "facet normal 0 0 0\nouter loop\n";
        for (const char* v : f) stl += std::string("vertex ") + v + "\n";
        stl += "endloop\nendfacet\n";
    }
    stl += "endsolid tet\n";
    const esf::Mesh mesh = esf::load_mesh(write("tet.stl", stl));
    EXPECT_EQ(mesh.triangles.size(), 4u);
    EXPECT_EQ(mesh.vertices.size(), 4u);
}

std::string base64(const std::vector<std::uint8_t>& bytes) {
    static const char* kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        std::uint32_t n = static_cast<std::uint32_t>(bytes[i]) << 16;
        if (i + 1 < bytes.size()) n |= static_cast<std::uint32_t>(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size()) n |= bytes[i + 2];
        out += kAlphabet[(n >> 18) & 63];
        out += kAlphabet[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
    }
    return out;
}

TEST_F(MeshTest, GltfNodeTransformsAreApplied) {
    // One triangle (0,0,0) (1,0,0) (0,1,0), used by a parent node translated by (10, 0, 0) and by
    // its child scaled by 2: the child's copy is translate(10,0,0) * scale(2) applied.
    std::vector<std::uint8_t> buffer(44, 0);
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint16_t indices[3] = {0, 1, 2};
    std::memcpy(buffer.data(), positions, sizeof(positions));
    std::memcpy(buffer.data() + 36, indices, sizeof(indices));
    const std::string gltf = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0, "translation": [10, 0, 0], "children": [1]},
            {"mesh": 0, "scale": [2, 2, 2]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" +
                             base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
})";
    const esf::Mesh mesh = esf::load_mesh(write("nodes.gltf", gltf));
    EXPECT_EQ(triangle_set(mesh), triangles_of({{{{10, 0, 0}, {11, 0, 0}, {10, 1, 0}}},
                                                {{{10, 0, 0}, {12, 0, 0}, {10, 2, 0}}}}));
}

TEST_F(MeshTest, DegenerateTrianglesAndUnusedVerticesAreDropped) {
    // Vertex 5 is unused; face 1 1 2 repeats a vertex.
    const std::string path = write("messy.obj",
                                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 7 7 7\nv 0 0 1\n"
                                   "f 1 2 3\nf 1 2 5\nf 2 2 3\n");
    const esf::Mesh mesh = esf::load_mesh(path);
    EXPECT_EQ(mesh.triangles.size(), 2u);
    EXPECT_EQ(mesh.vertices.size(), 4u);
    EXPECT_EQ(mesh.max_corner(), Eigen::Vector3f(1, 1, 1));
}

TEST_F(MeshTest, PlyRoundTripIsExact) {
    esf::Mesh mesh;
    mesh.vertices = {
        {0.1f, -0.2f, 0.3f}, {1e-7f, 2.5f, -3.25f}, {-4.f, 5.f, 6.125f}, {0.f, 0.f, 1.f}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 1, 0}};
    const std::string path = (dir_ / "out.ply").string();
    esf::write_ply_mesh(path, mesh);

    std::ifstream in(path, std::ios::binary);
    std::string header;
    for (std::string line; std::getline(in, line) && line != "end_header";) header += line + "\n";
    EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
    EXPECT_NE(header.find("element vertex 4"), std::string::npos);
    EXPECT_NE(header.find("element face 3"), std::string::npos);
    EXPECT_EQ(fs::file_size(path), header.size() + 11 + 4 * 12 + 3 * 13);

    const esf::Mesh back = esf::load_mesh(path);
    EXPECT_EQ(triangle_set(back), triangle_set(mesh));
    // No temporary file is left beside it.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// Assimp's PLY reader takes a line feed right after end_header for part of the header, so binary
// data may not start with 0x0A: x of the first vertex, whose lowest byte it is.
float with_low_byte(float x, unsigned char byte) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &x, sizeof bits);
    bits = (bits & ~std::uint32_t{0xff}) | byte;
    std::memcpy(&x, &bits, sizeof x);
    return x;
}

std::string first_data_bytes(const std::string& path, std::size_t n) {
    std::ifstream in(path, std::ios::binary);
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t end = all.find("end_header\n");
    return end == std::string::npos ? std::string() : all.substr(end + 11, n);
}

TEST_F(MeshTest, PlyRoundTripWhereTheFirstValueStartsWithALineFeed) {
    esf::Mesh mesh;
    mesh.vertices = {{with_low_byte(0.1f, '\n'), -0.2f, 0.3f},
                     {1e-7f, 2.5f, -3.25f},
                     {-4.f, 5.f, 6.125f},
                     {with_low_byte(0.5f, '\n'), 0.f, 1.f}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 1, 0}};
    const std::string path = (dir_ / "line_feed.ply").string();
    esf::write_ply_mesh(path, mesh);
    EXPECT_NE(first_data_bytes(path, 1), "\n");
    const esf::Mesh back = esf::load_mesh(path);
    ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
    EXPECT_EQ(triangle_set(back), triangle_set(mesh));

    // Every x starting so: each vertex leads with a zero byte, still exact.
    for (Eigen::Vector3f& v : mesh.vertices) v.x() = with_low_byte(v.x(), '\n');
    esf::write_ply_mesh(path, mesh);
    EXPECT_EQ(first_data_bytes(path, 1), std::string(1, '\0'));
    EXPECT_EQ(triangle_set(esf::load_mesh(path)), triangle_set(mesh));
}

TEST_F(MeshTest, BinaryPlyWhoseDataStartsWithALineFeedIsRefused) {
    // The same bytes as esf wrote them before it avoided this: the importer would read them one
    // byte late.
    esf::Mesh mesh;
    mesh.vertices = {{with_low_byte(0.1f, '\n'), 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}};
    mesh.triangles = {{0, 1, 2}};
    std::string bytes =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n";
    for (const Eigen::Vector3f& v : mesh.vertices)
        bytes.append(reinterpret_cast<const char*>(v.data()), 3 * sizeof(float));
    bytes.push_back(3);
    for (const int i : {0, 1, 2}) bytes.append(reinterpret_cast<const char*>(&i), sizeof i);
    ASSERT_EQ(bytes[bytes.find("end_header\n") + 11], '\n');
    const std::string path = write("line_feed.ply", bytes);
    EXPECT_CONTAINS(error_of([&] { esf::load_mesh(path); }), "line feed");
    EXPECT_THROW(esf::load_mesh(path), esf::IoError);
}

TEST_F(MeshTest, MinMaxCornerOfEmptyMeshThrows) {
    const esf::Mesh empty;
    EXPECT_THROW((void)empty.min_corner(), std::invalid_argument);
    EXPECT_THROW((void)empty.max_corner(), std::invalid_argument);
    EXPECT_THROW((void)empty.bounding_radius(), std::invalid_argument);
}

TEST_F(MeshTest, BoundingRadiusIsAroundTheBoxCentre) {
    esf::Mesh mesh;
    // Box [0, 2] x [0, 4] x [0, 1]: centre (1, 2, 0.5). The corner (2, 4, 1) is
    // sqrt(1 + 4 + 0.25) away; (1, 0, 0.5) is only 2 away.
    mesh.vertices = {{0, 0, 0}, {2, 4, 1}, {1, 0, 0.5f}};
    mesh.triangles = {{0, 1, 2}};
    EXPECT_DOUBLE_EQ(mesh.bounding_radius(), std::sqrt(5.25));
}

TEST_F(MeshTest, LoadErrorsNameTheFile) {
    const std::string missing = (dir_ / "missing.obj").string();
    EXPECT_THROW(esf::load_mesh(missing), esf::IoError);
    EXPECT_EQ(error_of([&] { esf::load_mesh(missing); }), missing + ": no such file");

    const std::string empty = write("empty.ply", "");
    EXPECT_EQ(error_of([&] { esf::load_mesh(empty); }), empty + ": empty file");

    EXPECT_EQ(error_of([&] { esf::load_mesh(dir_.string()); }),
              dir_.string() + ": is a directory, not a mesh file");

    // Assimp alone would loop forever on this header.
    const std::string no_end = write("no_end.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(no_end); }),
              no_end + ": PLY header has no end_header line");

    // 3 vertices (36 bytes) and one face (13 bytes) announced, 20 bytes present.
    const std::string truncated = write("truncated.ply",
                                        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                                        "property float x\nproperty float y\nproperty float z\n"
                                        "element face 1\nproperty list uchar int vertex_indices\n"
                                        "end_header\n" +
                                            std::string(20, '\0'));
    EXPECT_EQ(error_of([&] { esf::load_mesh(truncated); }),
              truncated +
                  ": truncated PLY: the header announces 3 vertex elements, needing at least 36 "
                  "bytes with those before them, but 20 bytes follow the header");

    const std::string garbage = write("garbage.ply", "PLY\x01\x02 not a header at all");
    const std::string garbage_error = error_of([&] { esf::load_mesh(garbage); });
    EXPECT_EQ(garbage_error.rfind(garbage + ": cannot read mesh: ", 0), 0u) << garbage_error;
    EXPECT_THROW(esf::load_mesh(garbage), esf::IoError);

    const std::string nan = write("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(nan); }), nan + ": has a non-finite vertex");

    const std::string bad_index = write("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    EXPECT_EQ(
        error_of([&] { esf::load_mesh(bad_index); }).rfind(bad_index + ": cannot read mesh", 0),
        0u);

    const std::string unknown = write("cloud.xyz123", "0 0 0\n1 1 1\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(unknown); }).rfind(unknown + ": ", 0), 0u);

    const std::string points = write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    const std::string points_error = error_of([&] { esf::load_mesh(points); });
    EXPECT_EQ(points_error.rfind(points + ": ", 0), 0u) << points_error;
    EXPECT_THROW(esf::load_mesh(points), esf::IoError);

    const std::string lines = write("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(lines); }), lines + ": holds no triangle");

    const std::string degenerate = write("degenerate.obj", "v 0 0 0\nv 1 0 0\nf 1 2 2\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(degenerate); }).rfind(degenerate + ": ", 0), 0u);
}

TEST_F(MeshTest, OffCountsAndIndicesAreCheckedBeforeAssimp) {
    // Assimp clamps an out-of-range index to the last vertex; it is an error.
    const std::string bad_index = write("bad_index.off",
                                        "OFF\n# a comment\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                        "3 0 1 2\n3 0 1 4\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(bad_index); }),
              bad_index + ":9: OFF face 1 has vertex index 4 outside [0, 4)");
    const std::string negative =
        write("negative.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(negative); }),
              negative + ":5: OFF face 0 has vertex index -1 outside [0, 3)");

    // A 50-byte file announcing 9e8 faces: refused before anything is allocated.
    const std::string huge =
        write("huge.off", "OFF\n3 900000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(huge); }),
              huge +
                  ":2: truncated OFF: the header announces 3 vertices and 9e+08 faces, needing "
                  "at least 1.8e+09 bytes, but the file has " +
                  std::to_string(fs::file_size(huge)));

    // Fewer vertices or faces than announced, and short faces.
    const std::string short_faces =
        write("short.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(short_faces); }),
              short_faces + ": truncated OFF: 2 of the 3 faces the header announces");
    const std::string short_face =
        write("short_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n                \n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(short_face); }),
              short_face + ":6: OFF face 0 lists fewer than 3 vertex indices");
    const std::string bad_counts = write("bad_counts.off", "OFF\n3 -1 0\n0 0 0\n1 0 0\n0 1 0\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(bad_counts); }),
              bad_counts + ":2: OFF vertex and face counts are not two whole numbers >= 0");

    // A valid file still loads.
    const std::string valid = write("valid.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(esf::load_mesh(valid).triangles.size(), 1u);
}

TEST_F(MeshTest, PlyListLengthsAreCheckedBeforeAssimp) {
    // A 100-byte file whose one face lists 9e8 vertices (Assimp would allocate 3.6 GB).
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::string ascii = write("list.ply", header + "0 0 0\n1 0 0\n0 1 0\n900000000 0 1 2\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(ascii); }),
              ascii + ": PLY face element 0: a list of 9e+08 items on a line of 15 characters");
    const std::string short_list =
        write("short_list.ply", header + "0 0 0\n1 0 0\n0 1 0\n4 0 1 2        \n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(short_list); }),
              short_list + ": PLY face element 0: a list shorter than its count");
    const std::string short_vertex =
        write("short_vertex.ply", header + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(short_vertex); }),
              short_vertex + ": PLY vertex element 1: fewer values than the element's properties");

    // Binary, an int count of 1e9 in a file of a hundred bytes.
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list int int vertex_indices\nend_header\n";
    for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
        binary.append(reinterpret_cast<const char*>(&v), 4);
    const std::int32_t counts[4] = {1000000000, 0, 1, 2};
    binary.append(reinterpret_cast<const char*>(counts), sizeof counts);
    const std::string huge = write("huge_list.ply", binary);
    EXPECT_EQ(error_of([&] { esf::load_mesh(huge); }),
              huge +
                  ": PLY face element 0: a list of 1000000000 items, more than the 12 bytes left "
                  "in the file hold");
    // The same with the right count loads.
    binary.replace(binary.size() - sizeof counts, 4, std::string("\x03\0\0\0", 4));
    EXPECT_EQ(esf::load_mesh(write("good_list.ply", binary)).triangles.size(), 1u);
    EXPECT_EQ(esf::load_mesh(write("good.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
                  .triangles.size(),
              1u);
}

TEST_F(MeshTest, APlyElementWithoutPropertiesCountsAsAByte) {
    // 1e18 elements of nothing in a binary file: the list check looped over every one of them,
    // and Assimp keeps a record of each.
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement nothing 1000000000000000000\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::size_t header = binary.size();
    for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
        binary.append(reinterpret_cast<const char*>(&v), 4);
    binary += std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13);
    const std::string path = write("nothing.ply", binary);
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path +
                  ": truncated PLY: the header announces 1e+18 nothing elements, needing at least "
                  "1e+18 bytes with those before them, but " +
                  std::to_string(binary.size() - header) + " bytes follow the header");
}

// A binary STL: an 80-byte header, a little-endian triangle count, 50 bytes a triangle (normal,
// three corners, a 16-bit attribute).
std::string binary_stl(const std::string& header, std::uint32_t count,
                       const std::vector<Triangle>& triangles) {
    std::string out = header;
    out.resize(80, '\0');
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<char>((count >> (8 * b)) & 0xffu));
    for (const Triangle& t : triangles) {
        const float normal[3] = {0, 0, 1};
        out.append(reinterpret_cast<const char*>(normal), sizeof normal);
        for (const auto& corner : t)
            out.append(reinterpret_cast<const char*>(corner.data()), 3 * sizeof(float));
        out.append(2, '\0');
    }
    return out;
}

TEST_F(MeshTest, BinaryStlTriangleCountIsCheckedAgainstTheFileSize) {
    const std::vector<Triangle> one = {{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
    const esf::Mesh mesh = esf::load_mesh(write("one.stl", binary_stl("esf test", 1, one)));
    EXPECT_EQ(mesh.triangles.size(), 1u);
    EXPECT_EQ(mesh.vertices.size(), 3u);

    // 2^31 + 1 triangles: 84 + 50 x count is the file's 134 bytes in 32 bits, which Assimp 5.2
    // takes for a binary STL (only its own later check stops it allocating 6e9 corners). The
    // header may start with "solid" too: Assimp tries binary first.
    for (const char* header : {"esf test", "solid esf"}) {
        const std::string wraps = write("wraps.stl", binary_stl(header, (1u << 31) + 1u, one));
        EXPECT_EQ(error_of([&] { esf::load_mesh(wraps); }),
                  wraps +
                      ": truncated binary STL: the header announces 2147483649 triangles, "
                      "needing 107374182534 bytes, but the file has 134");
    }
    // Named anything else, with "STL" in its header: Assimp still reads it as STL.
    const std::string named_bin =
        write("wraps.bin", binary_stl("STL by esf", (1u << 31) + 1u, one));
    EXPECT_THROW(esf::load_mesh(named_bin), esf::IoError);

    const std::string short_file = write("short.stl", binary_stl("esf test", 1000, one));
    EXPECT_EQ(error_of([&] { esf::load_mesh(short_file); }),
              short_file +
                  ": truncated binary STL: the header announces 1000 triangles, needing 50084 "
                  "bytes, but the file has 134");
}

TEST_F(MeshTest, APlyMeshCutShortIsAnErrorWhereverItIsCut) {
    // A 6 x 6 vertex grid, 50 triangles, binary (written by esf) and ASCII. Cut at 30 % to 99 %
    // of its length, Assimp aborted (30-60 %) or returned a part of the mesh (75-99 %).
    esf::Mesh grid;
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 6; ++x)
            grid.vertices.emplace_back(static_cast<float>(x), static_cast<float>(y), 0.0f);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) {
            const int i = 6 * y + x;
            grid.triangles.emplace_back(i, i + 1, i + 7);
            grid.triangles.emplace_back(i, i + 7, i + 6);
        }
    const std::string binary_path = (dir_ / "grid.ply").string();
    esf::write_ply_mesh(binary_path, grid);
    std::ifstream in(binary_path, std::ios::binary);
    const std::string binary((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
    std::string ascii =
        "ply\nformat ascii 1.0\nelement vertex 36\nproperty float x\nproperty float y\n"
        "property float z\nelement face 50\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& v : grid.vertices)
        ascii += std::to_string(v.x()) + " " + std::to_string(v.y()) + " 0\n";
    for (const auto& t : grid.triangles)
        ascii += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " +
                 std::to_string(t[2]) + "\n";
    EXPECT_EQ(esf::load_mesh(write("whole_ascii.ply", ascii)).triangles.size(), 50u);
    EXPECT_EQ(esf::load_mesh(binary_path).triangles.size(), 50u);
    for (const double fraction : {0.3, 0.45, 0.6, 0.75, 0.9, 0.99}) {
        const auto cut = [fraction](const std::string& text) {
            return text.substr(
                0, static_cast<std::size_t>(fraction * static_cast<double>(text.size())));
        };
        const std::string b = write("cut.ply", cut(binary));
        EXPECT_THROW(esf::load_mesh(b), esf::IoError) << fraction;
        // ASCII cut inside the last line it keeps: that line may still read as whole, the
        // lines after it are missing.
        const std::string a = write("cut_ascii.ply", cut(ascii));
        EXPECT_THROW(esf::load_mesh(a), esf::IoError) << fraction;
    }
}

TEST_F(MeshTest, APlyHeaderCutBeforeItsLastNewlineIsAnError) {
    // Found by the mesh fuzz target: nothing after the header, not even its newline (the bytes
    // left after the header came out as -1).
    for (const std::string header :
         {"ply\nformat ascii 1.0\nend_header", "ply\nformat ascii 1.0\nelement x 0\nend_header",
          "ply\nformat binary_little_endian 1.0\nend_header"})
        EXPECT_THROW(esf::load_mesh(write("header_only.ply", header)), std::exception) << header;
}

TEST_F(MeshTest, NoFileOutsideTheModelsFolderIsOpened) {
    // A glTF whose buffer lies beside the model loads; the same buffer one folder up does not
    // exist for the importer (as /etc/passwd would not).
    std::vector<std::uint8_t> buffer(44, 0);
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint16_t indices[3] = {0, 1, 2};
    std::memcpy(buffer.data(), positions, sizeof(positions));
    std::memcpy(buffer.data() + 36, indices, sizeof(indices));
    const auto gltf = [](const std::string& uri) {
        return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 44, "uri": ")" +
               uri + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
    };
    fs::create_directories(dir_ / "model");
    const std::string bytes(buffer.begin(), buffer.end());
    write("model/inside.bin", bytes);
    write("outside.bin", bytes);
    EXPECT_EQ(esf::load_mesh(write("model/inside.gltf", gltf("inside.bin"))).triangles.size(), 1u);
    const std::string outside = write("model/outside.gltf", gltf("../outside.bin"));
    EXPECT_THROW(esf::load_mesh(outside), esf::IoError);
    const std::string absolute =
        write("model/absolute.gltf", gltf((dir_ / "outside.bin").string()));
    EXPECT_THROW(esf::load_mesh(absolute), esf::IoError);
    // A link beside the model to a file outside its folder is outside too.
    fs::create_symlink(dir_ / "outside.bin", dir_ / "model" / "link.bin");
    EXPECT_THROW(esf::load_mesh(write("model/link.gltf", gltf("link.bin"))), esf::IoError);

    // Material libraries that are FIFOs (inside or outside the folder) are never opened: an
    // open would wait forever for a writer. The mesh itself loads.
    ASSERT_EQ(::mkfifo((dir_ / "model" / "pipe.mtl").c_str(), 0600), 0);
    ASSERT_EQ(::mkfifo((dir_ / "secret.mtl").c_str(), 0600), 0);
    const std::string obj =
        write("model/quad.obj",
              "mtllib pipe.mtl\nmtllib ../secret.mtl\nmtllib ../../../etc/shadow\n"
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(esf::load_mesh(obj).triangles.size(), 1u);
    // A mesh that is itself a FIFO: one line, no wait.
    ASSERT_EQ(::mkfifo((dir_ / "model" / "fifo.obj").c_str(), 0600), 0);
    EXPECT_CONTAINS(error_of([&] { esf::load_mesh((dir_ / "model" / "fifo.obj").string()); }),
                    "fifo.obj: ");
}

TEST_F(MeshTest, WriteErrors) {
    esf::Mesh mesh;
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    const std::string bad_dir = (dir_ / "no" / "such" / "dir" / "m.ply").string();
    EXPECT_THROW(esf::write_ply_mesh(bad_dir, mesh), esf::IoError);
    EXPECT_EQ(error_of([&] { esf::write_ply_mesh(bad_dir, mesh); }),
              bad_dir + ": cannot create temporary file: No such file or directory");

    const std::string path = (dir_ / "m.ply").string();
    esf::Mesh bad_index = mesh;
    bad_index.triangles = {{0, 1, 3}};
    EXPECT_EQ(error_of([&] { esf::write_ply_mesh(path, bad_index); }),
              path + ": triangle 0 has a vertex index outside [0, 3)");
    esf::Mesh nan = mesh;
    nan.vertices[1].y() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(error_of([&] { esf::write_ply_mesh(path, nan); }), path + ": vertex 1 is not finite");
    EXPECT_EQ(error_of([&] { esf::write_ply_mesh(path, esf::Mesh{}); }),
              path + ": mesh has no triangle");
    EXPECT_FALSE(fs::exists(path));
}

// ---- the importer helper ---------------------------------------------------------------------

TEST_F(MeshTest, AnImporterCrashIsAnErrorOfThatFileOnly) {
    const std::string path = write("recursive.dae", esf::test::recursive_collada());
    EXPECT_THROW(esf::load_mesh(path), esf::IoError);
    // The helper's stack overflows (SIGSEGV; under AddressSanitizer, its report and exit status).
    const std::string error = error_of([&] { esf::load_mesh(path); });
    EXPECT_EQ(error.rfind(path + ": the mesh importer ", 0), 0u) << error;
    // This process goes on loading meshes.
    EXPECT_EQ(
        esf::load_mesh(write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).triangles.size(),
        1u);
}

TEST_F(MeshTest, ImportLimitsAreReported) {
    const std::string path = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    esf::MeshImportLimits limits;
    EXPECT_EQ(limits.address_space_mib, esf::kMeshImportAddressSpaceMiB);
    EXPECT_EQ(limits.seconds, esf::kMeshImportSeconds);
    EXPECT_EQ(esf::load_mesh(path, limits).triangles.size(), 1u);
    // A microsecond is over before the helper has started.
    limits.seconds = 1e-6;
    EXPECT_EQ(error_of([&] { esf::load_mesh(path, limits); }),
              path + ": the mesh importer took longer than 1e-06 s");
    limits.seconds = 0.0;
    EXPECT_THROW(esf::load_mesh(path, limits), std::invalid_argument);
}

#if defined(__SANITIZE_ADDRESS__)
#define ESF_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ESF_TEST_ASAN 1
#endif
#endif

TEST_F(MeshTest, TheImportersAddressSpaceIsLimited) {
#if defined(ESF_TEST_ASAN)
    GTEST_SKIP() << "the helper sets no address-space limit under AddressSanitizer";
#else
    // The helper's own code and libraries take more than 1 MiB: its first allocation fails.
    const std::string path = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    esf::MeshImportLimits limits;
    limits.address_space_mib = 1;
    EXPECT_EQ(error_of([&] { esf::load_mesh(path, limits); }),
              path + ": the mesh importer needed more than 1 MiB");
#endif
}

class MeshHelperTest : public MeshTest {
  protected:
    // A stand-in for the helper: a shell script, named by ESF_MESH_IMPORTER for this test only.
    void use_helper(const std::string& script) {
        helper_ = write("helper.sh", "#!/bin/sh\n" + script);
        fs::permissions(helper_, fs::perms::owner_all);
        ::setenv("ESF_MESH_IMPORTER", helper_.c_str(), 1);
    }
    void TearDown() override {
        ::unsetenv("ESF_MESH_IMPORTER");
        MeshTest::TearDown();
    }
    std::string helper_;
};

TEST_F(MeshHelperTest, AMissingHelperIsNamed) {
    const std::string path = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string missing = (dir_ / "no" / "esf_mesh_import").string();
    ::setenv("ESF_MESH_IMPORTER", missing.c_str(), 1);
    EXPECT_THROW(esf::load_mesh(path), esf::IoError);
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": cannot import meshes: its helper esf_mesh_import is missing (looked in " +
                  missing + ")");
    // Files that are no mesh are refused before the helper is looked for.
    EXPECT_EQ(error_of([&] { esf::load_mesh((dir_ / "none.obj").string()); }),
              (dir_ / "none.obj").string() + ": no such file");
}

TEST_F(MeshHelperTest, CrashesHangsAndBadRepliesOfTheHelperAreErrors) {
    const std::string path = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    use_helper("kill -SEGV $$\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer crashed (signal 11)");
    use_helper("kill -ABRT $$\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer crashed (signal 6)");
    use_helper("exit 4\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer needed more than 4096 MiB");
    use_helper("exit 7\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer failed (exit status 7)");
    use_helper("exec /bin/sleep 30\n");
    esf::MeshImportLimits limits;
    limits.seconds = 0.3;
    EXPECT_EQ(error_of([&] { esf::load_mesh(path, limits); }),
              path + ": the mesh importer took longer than 0.3 s");
    use_helper("printf 'short'\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer's reply is malformed (5 bytes)");
    // A header announcing 2^40 vertices in no bytes: refused before anything is allocated.
    std::string lie(24, '\0');
    lie[8 + 5] = 1;
    write("lie.bin", lie);
    use_helper("exec /bin/cat " + (dir_ / "lie.bin").string() + "\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path +
                  ": the mesh importer's reply is malformed (1099511627776 vertices and 0 "
                  "triangles in 0 bytes)");
    // A triangle naming a vertex that is not there.
    std::string bad(24 + 12, '\0');
    bad[16] = 1;  // 0 vertices, 1 triangle
    write("bad.bin", bad);
    use_helper("exec /bin/cat " + (dir_ / "bad.bin").string() + "\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer's reply is malformed (triangle 0 names vertex 0)");
    // A helper that exits without reading or writing anything.
    use_helper("exit 0\n");
    EXPECT_EQ(error_of([&] { esf::load_mesh(path); }),
              path + ": the mesh importer's reply is malformed (0 bytes)");
}

TEST(MeshRealData, YcbPlyAndKitObj) {
    ESF_REQUIRE_DATA("meshes/apple/ycb_013_apple.ply");
    ESF_REQUIRE_DATA("meshes/bottle/kit_BathDetergent.obj");
    // YCB 16k scan in metres: 16384 faces; texture seams are joined, extent about 7.5 cm.
    const esf::Mesh apple =
        esf::load_mesh(esf::test::data_file("meshes/apple/ycb_013_apple.ply").string());
    EXPECT_EQ(apple.triangles.size(), 16384u);
    EXPECT_LE(apple.vertices.size(), 8194u);
    const Eigen::Vector3f apple_size = apple.max_corner() - apple.min_corner();
    EXPECT_GT(apple_size.maxCoeff(), 0.06f);
    EXPECT_LT(apple_size.maxCoeff(), 0.09f);
    // KIT (Dex-Net) OBJ, 800 faces, middle bounding-box side 45 (mm units).
    const esf::Mesh kit =
        esf::load_mesh(esf::test::data_file("meshes/bottle/kit_BathDetergent.obj").string());
    EXPECT_EQ(kit.triangles.size(), 800u);
    Eigen::Vector3f kit_size = kit.max_corner() - kit.min_corner();
    std::sort(kit_size.data(), kit_size.data() + 3);
    EXPECT_NEAR(kit_size[1], 0.045f, 0.01f);
}

TEST(MeshRealData, TheLargestMeshesLoadWithinTheDefaultLimits) {
    ESF_REQUIRE_DATA("meshes/cup/ycb_065-d_cups.ply");
    const esf::Mesh cup =
        esf::load_mesh(esf::test::data_file("meshes/cup/ycb_065-d_cups.ply").string());
    EXPECT_GT(cup.triangles.size(), 10000u);
}

}  // namespace
