// PLY point clouds (src/io/ply_cloud_io.cpp): ascii, binary both byte orders, lists, errors.

#include "support/cloud_io_test_util.hpp"

namespace {

using namespace esf::test;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// ---------------------------------------------------------------------------------------------
// PLY

struct PlyVertex {
    double x;
    float y;
    std::int32_t z;
    std::uint8_t red;
    float nx;
    std::uint16_t label;
};

const std::vector<PlyVertex>& ply_vertices() {
    static const std::vector<PlyVertex> vertices = {
        {0.1, 2.5f, -3, 255, 0.0f, 7},
        {1e10, -0.25f, 4, 0, 1.0f, 0},
        {-1.5, kNaN, 0, 12, -1.0f, 65535},
    };
    return vertices;
}

/// An element with a list before the vertices, extra vertex properties, faces after them.
std::string ply_header(std::string_view format) {
    return "ply\nformat " + std::string(format) +
           " 1.0\n"
           "comment written by hand\n"
           "obj_info for the tests\n"
           "element material 2\n"
           "property list uchar int ids\n"
           "property float shininess\n"
           "element vertex 3\n"
           "property double x\n"
           "property float32 y\n"
           "property int z\n"
           "property uchar red\n"
           "property float nx\n"
           "property ushort label\n"
           "element face 2\n"
           "property list uchar int vertex_indices\n"
           "end_header\n";
}

std::string ply_binary(bool big_endian) {
    Bytes b(big_endian);
    b.text(ply_header(big_endian ? "binary_big_endian" : "binary_little_endian"));
    b.put<std::uint8_t>(2).put<std::int32_t>(5).put<std::int32_t>(6).put(0.5f);
    b.put<std::uint8_t>(0).put(1.5f);
    for (const auto& v : ply_vertices()) {
        b.put(v.x).put(v.y).put(v.z).put(v.red).put(v.nx).put(v.label);
    }
    b.put<std::uint8_t>(3).put<std::int32_t>(0).put<std::int32_t>(1).put<std::int32_t>(2);
    b.put<std::uint8_t>(4)
        .put<std::int32_t>(0)
        .put<std::int32_t>(1)
        .put<std::int32_t>(2)
        .put<std::int32_t>(0);
    return b.str();
}

std::string ply_ascii() {
    return ply_header("ascii") +
           "2 5 6 0.5\n"
           "0 1.5\n"
           "0.1 2.5 -3 255 0 7\n"
           "1e10 -0.25 4 0 1 0\n"
           "-1.5 nan 0 12 -1 65535\n"
           "3 0 1 2\n"
           "4 0 1 2 0\n";
}

void expect_ply_vertices(const esf::PointCloud& cloud) {
    const auto& vertices = ply_vertices();
    ASSERT_EQ(cloud.points.size(), vertices.size());
    EXPECT_EQ(cloud.width, 3u);
    EXPECT_EQ(cloud.height, 1u);
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        EXPECT_EQ(bits(cloud.points[i].x()), bits(static_cast<float>(vertices[i].x))) << i;
        if (std::isnan(vertices[i].y)) {
            EXPECT_TRUE(std::isnan(cloud.points[i].y()));
        } else {
            EXPECT_EQ(bits(cloud.points[i].y()), bits(vertices[i].y)) << i;
        }
        EXPECT_EQ(cloud.points[i].z(), static_cast<float>(vertices[i].z)) << i;
    }
    EXPECT_EQ(cloud.labels, (std::vector<std::uint32_t>{7, 0, 65535}));
}

TEST(PlyRead, Ascii) { expect_ply_vertices(ply_from(ply_ascii())); }
TEST(PlyRead, BinaryLittleEndian) { expect_ply_vertices(ply_from(ply_binary(false))); }
TEST(PlyRead, BinaryBigEndian) { expect_ply_vertices(ply_from(ply_binary(true))); }

TEST(PlyRead, AsciiWithCrLfAndNoLabel) {
    const esf::PointCloud cloud = ply_from(
        "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float x\r\n"
        "property float y\r\nproperty float z\r\nend_header\r\n1 2 3\r\n4 5 6\r\n");
    ASSERT_EQ(cloud.points.size(), 2u);
    EXPECT_EQ(cloud.points[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_TRUE(cloud.labels.empty());
}

TEST(PlyRead, ListPropertyInsideVertices) {
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
        "property list ushort float extra\nproperty float y\nproperty float z\nend_header\n";
    Bytes b;
    b.text(header);
    b.put(1.0f).put<std::uint16_t>(2).put(9.0f).put(9.0f).put(2.0f).put(3.0f);
    b.put(4.0f).put<std::uint16_t>(0).put(5.0f).put(6.0f);
    const esf::PointCloud binary = ply_from(b.str());
    ASSERT_EQ(binary.points.size(), 2u);
    EXPECT_EQ(binary.points[0], Eigen::Vector3f(1, 2, 3));
    EXPECT_EQ(binary.points[1], Eigen::Vector3f(4, 5, 6));

    std::string ascii = header;
    ascii.replace(ascii.find("binary_little_endian"), 20, "ascii");
    const esf::PointCloud text = ply_from(ascii + "1 2 9 9 2 3\n4 0 5 6\n");
    ASSERT_EQ(text.points.size(), 2u);
    EXPECT_EQ(text.points[0], Eigen::Vector3f(1, 2, 3));
    EXPECT_EQ(text.points[1], Eigen::Vector3f(4, 5, 6));
}

TEST(PlyErrors, Header) {
    auto error = [](const std::string& text) { return io_error([&] { ply_from(text); }); };
    EXPECT_EQ(error("plx\nformat ascii 1.0\nend_header\n"),
              "mem.ply:1: not a PLY file (no 'ply' line)");
    EXPECT_EQ(error("ply\nformat binary_middle_endian 1.0\nend_header\n"),
              "mem.ply:2: bad header: format: unknown format 'binary_middle_endian'");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n"),
              "mem.ply:4: bad header: property: unknown type 'float128'");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
              "mem.ply:3: bad header: property: comes before any element");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n"),
              "mem.ply:3: bad header: element: count is not a non-negative integer: '-1'");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
              "mem.ply:4: bad header: no end_header line");
    EXPECT_EQ(error("ply\nelement vertex 0\nend_header\n"),
              "mem.ply:3: bad header: end_header: no format line before end_header");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nelement face 0\nend_header\n"),
              "mem.ply: no element 'vertex'");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "end_header\n1 2\n"),
              "mem.ply:3: element 'vertex' has no property 'z'");
    EXPECT_EQ(error("ply\nformat ascii 1.0\nvertex 1\nend_header\n"),
              "mem.ply:3: bad header: unknown keyword 'vertex'");
    EXPECT_EQ(error(""), "mem.ply: empty file");
}

TEST(PlyErrors, TruncatedBinary) {
    const std::string full = ply_binary(false);
    // Cut inside the vertices: 2 materials (13 + 5 bytes) + 3 vertices of 23 bytes needed.
    const std::size_t header = ply_header("binary_little_endian").size();
    EXPECT_EQ(io_error([&] { ply_from(full.substr(0, header + 18 + 50)); }),
              "mem.ply: truncated: expected 87 bytes of binary data, got 68 (element 'vertex')");
    // Cut inside the list of the first material.
    EXPECT_EQ(io_error([&] { ply_from(full.substr(0, header + 5)); }),
              "mem.ply: truncated: expected 9 bytes of binary data, got 5 (element 'material' 0)");
}

TEST(PlyErrors, AbsurdVertexCount) {
    const std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n" +
        std::string(24, '\0');
    EXPECT_EQ(io_error([&] { ply_from(binary); }),
              "mem.ply: truncated: expected 48000000000 bytes of binary data, got 24 (element "
              "'vertex')");
    const std::string ascii =
        "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n1 2 3\n";
    EXPECT_THAT(io_error([&] { ply_from(ascii); }),
                StartsWith("mem.ply:3: truncated: expected 4000000000 vertices"));
    const std::string huge_list =
        "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint int idx\n"
        "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n" +
        Bytes().put<std::uint32_t>(4000000000u).str();
    EXPECT_THAT(io_error([&] { ply_from(huge_list); }),
                StartsWith("mem.ply: truncated: expected 16000000004 bytes of binary data"));
}

TEST(PlyErrors, NegativeListLength) {
    const std::string file =
        Bytes()
            .text(
                "ply\nformat binary_little_endian 1.0\nelement face 1\n"
                "property list char int idx\nelement vertex 0\nproperty float x\n"
                "property float y\nproperty float z\nend_header\n")
            .put<std::int8_t>(-1)
            .str();
    EXPECT_EQ(io_error([&] { ply_from(file); }),
              "mem.ply: corrupt data: element 'face' 0: property 'idx' has a negative list length");
}

TEST(PlyErrors, AsciiValues) {
    std::string bad = ply_ascii();
    bad.replace(bad.find("1e10"), 4, "oops");
    EXPECT_EQ(io_error([&] { ply_from(bad); }),
              "mem.ply:21: not a number: 'oops' (element 'vertex' 1, property 'x')");
    const std::string text = ply_ascii();
    const std::string cut = text.substr(0, text.find("-1.5 nan") + 8);
    EXPECT_EQ(io_error([&] { ply_from(cut); }),
              "mem.ply:22: truncated: unexpected end of file in element 'vertex' 2, property "
              "'z'");
}

TEST(PlyErrors, AsciiValuesBeyondTheFloatRange) {
    std::string big = ply_ascii();
    big.replace(big.find("1e10"), 4, "1e39");  // a double property: 1e39 is no float
    EXPECT_EQ(io_error([&] { ply_from(big); }),
              "mem.ply:21: out of float range: '1e39' (element 'vertex' 1, property 'x')");
    std::string tiny = ply_ascii();
    tiny.replace(tiny.find("-0.25"), 5, "1e-50");  // a float property: rounds to 0
    EXPECT_EQ(bits(ply_from(tiny).points[1].y()), bits(0.0f));
}

TEST(PlyRead, BinaryFloatXyzAtAnyOffset) {
    // x y z float32 one after another behind other properties: the one-copy-per-point path;
    // the same with z before y takes the column path. Both give the same points.
    for (const bool zyx : {false, true}) {
        SCOPED_TRACE(zyx ? "x z y" : "x y z");
        const std::string header =
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty uchar red\n"
            "property float x\n" +
            std::string(zyx ? "property float z\nproperty float y\n"
                            : "property float y\nproperty float z\n") +
            "property short s\nend_header\n";
        Bytes b;
        b.text(header);
        for (int i = 0; i < 3; ++i) {
            const float x = 0.5f * static_cast<float>(i), y = -1.0f - x, z = 1e-40f + x;
            b.put<std::uint8_t>(7).put(x);
            if (zyx) {
                b.put(z).put(y);
            } else {
                b.put(y).put(z);
            }
            b.put<std::int16_t>(-2);
        }
        const esf::PointCloud cloud = ply_from(b.str());
        ASSERT_EQ(cloud.points.size(), 3u);
        for (int i = 0; i < 3; ++i) {
            const float x = 0.5f * static_cast<float>(i);
            EXPECT_EQ(cloud.points[static_cast<std::size_t>(i)],
                      Eigen::Vector3f(x, -1.0f - x, 1e-40f + x));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Robustness: every prefix and random byte flips give a cloud or an IoError, nothing else.

TEST(Robustness, PrefixesAndByteFlips) {
    std::mt19937 gen(11);
    expect_prefixes_and_flips_read_or_fail(
        ply_binary(false), [](const std::string& b) { return ply_from(b); }, gen);
}

}  // namespace
