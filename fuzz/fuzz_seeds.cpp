// Writes the seed corpora of the fuzz targets: small valid inputs of every reader, made with the
// library's own writers where it has them. Usage: esf_fuzz_seeds OUT_DIR (creates
// OUT_DIR/<target>/).
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "esf/io/cloud_io.hpp"
#include "esf/io/depth_image.hpp"
#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/training/database.hpp"
#include "io/lzf.hpp"

namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& path, const std::string& bytes) {
    fs::create_directories(path.parent_path());
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

esf::PointCloud small_cloud(bool organised, bool labels) {
    esf::PointCloud cloud;
    for (int i = 0; i < 6; ++i)
        cloud.points.emplace_back(0.1f * static_cast<float>(i), 0.2f,
                                  0.5f + 0.01f * static_cast<float>(i));
    cloud.width = organised ? 3 : 6;
    cloud.height = organised ? 2 : 1;
    if (labels) cloud.labels = {0, 0, 10, 10, 20, 0};
    return cloud;
}

void pcd_seeds(const fs::path& dir) {
    int n = 0;
    for (const auto encoding :
         {esf::PcdEncoding::kAscii, esf::PcdEncoding::kBinary, esf::PcdEncoding::kBinaryCompressed})
        for (const bool organised : {false, true}) {
            std::ostringstream out;
            esf::write_pcd(out, small_cloud(organised, organised), encoding);
            write_file(dir / ("seed" + std::to_string(n++) + ".pcd"), out.str());
        }
}

/// lzf_fuzz inputs: the output size, the flag for 8,224 bytes of literal runs first, and blocks
/// compressed by lzf_compress: float columns with runs and repeats (references near and far,
/// short and long, and literal runs), as a scene's x, y, z blocks hold.
void lzf_seeds(const fs::path& dir) {
    for (const std::size_t points : {16u, 700u, 3000u}) {
        std::vector<unsigned char> raw;
        for (std::size_t i = 0; i < points; ++i) {
            const float v = i % 50 < 20 ? 0.0f : 0.5f + 0.001f * static_cast<float>(i % 97);
            const auto* bytes = reinterpret_cast<const unsigned char*>(&v);
            raw.insert(raw.end(), bytes, bytes + sizeof v);
        }
        std::vector<unsigned char> packed(esf::detail::lzf_compress_bound(raw.size()));
        packed.resize(esf::detail::lzf_compress(raw, packed));
        for (const int flag : {0, 1}) {
            const auto size = static_cast<std::uint32_t>(raw.size());
            std::string seed(reinterpret_cast<const char*>(&size), sizeof size);
            seed.push_back(static_cast<char>(flag));
            seed.append(reinterpret_cast<const char*>(packed.data()), packed.size());
            write_file(dir / ("seed" + std::to_string(points) + "_" + std::to_string(flag)), seed);
        }
    }
}

void ply_seeds(const fs::path& dir) {
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n";
    write_file(dir / "ascii.ply", header + "0 0 1\n0.5 0 1\n0 0.5 1.25\n");
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
        "property float y\nproperty float z\nproperty uchar red\nend_header\n";
    for (const float v : {0.f, 0.f, 1.f}) binary.append(reinterpret_cast<const char*>(&v), 4);
    binary.push_back('\x7f');
    for (const float v : {0.5f, 0.f, 1.f}) binary.append(reinterpret_cast<const char*>(&v), 4);
    binary.push_back('\x01');
    write_file(dir / "binary.ply", binary);
    std::string big =
        "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty double x\n"
        "property double y\nproperty double z\nend_header\n";
    for (const double v : {0.25, -0.5, 1.5}) {
        char b[8];
        std::memcpy(b, &v, 8);
        for (int i = 7; i >= 0; --i) big.push_back(b[i]);
    }
    write_file(dir / "big_endian.ply", big);
}

void xyz_seeds(const fs::path& dir) {
    write_file(dir / "spaces.xyz", "# x y z\n0 0 1\n0.5 0 1\n0 0.5 1.25 7\n");
    write_file(dir / "commas.xyz", "1e-3,2.5,-3\r\n4,5,6\r\n");
}

void depth_png_seeds(const fs::path& dir) {
    const double intrinsics[4] = {525.0, 525.0, 1.5, 1.0};
    std::string head(sizeof intrinsics, '\0');
    std::memcpy(head.data(), intrinsics, sizeof intrinsics);
    esf::DepthImage image;
    image.width = 4;
    image.height = 3;
    image.depth = {0, 800, 801, 0, 900, 901, 902, 903, 0, 0, 1200, 65535};
    std::ostringstream out;
    esf::write_depth_png(out, image, "seed.png");
    write_file(dir / "seed.bin", head + out.str());
}

void csv_seeds(const fs::path& root) {
    write_file(root / "test_set" / "plain.csv", "file,class\na.pcd,mug\nsub/b.pcd,bottle\n");
    write_file(root / "test_set" / "quoted.csv",
               "\xEF\xBB\xBF\"Class\", notes ,FILE\r\n\"mug\",\"a, \"\"b\"\"\",\"x\ny.pcd\"\r\n");
    write_file(root / "catalog" / "catalog.csv",
               "file,category,source,model,group,extent,metric\n"
               "mug/a.ply,mug,3dnet,a,g1,0.12,yes\nmug/b.off,mug,3dnet,b,g1,3.5,no\n"
               "bottle/c.obj,bottle,,c,,0,yes\n");
    write_file(
        root / "scene_set" / "scenes.csv",
        "scene_file,object_id,class,scene_type\ns1.pcd,1,mug,stacked\ns1.pcd,2,bowl,stacked\n"
        "s2.pcd,1,mug,occluded\n");
    write_file(root / "scene_set" / "short.csv", "class,object_id,scene_file\nbox,3,\"s 3.pcd\"\n");
}

void database_seeds(const fs::path& dir) {
    fs::create_directories(dir);
    const fs::path path = dir / "tmp.sqlite";
    fs::remove(path);
    {
        esf::Database db(path.string(), esf::OpenMode::kWrite);
        db.set_settings({{"seed", std::int64_t{1}}, {"distance", 0.75}, {"noise", "kinect"}});
        db.add_descriptor_kind({"tiny", 1, 4});
        for (const char* category : {"mug", "bowl"}) {
            esf::ModelEntry model;
            model.category = category;
            model.name = std::string(category) + "_1";
            model.file = model.category + "/" + model.name + ".ply";
            for (int v = 0; v < 2; ++v) {
                esf::ViewEntry view;
                view.index = v;
                view.points = 100;
                view.descriptors = {0.25f, 0.25f, 0.25f, 0.25f};
                model.views.push_back(view);
            }
            esf::ViewEntry skipped;
            skipped.index = 2;
            skipped.skip_reason = "too few points";
            model.views.push_back(skipped);
            db.write_model(model, "tiny");
        }
        db.set_weights(std::vector<float>{1.f, 2.f}, "tiny");
    }
    write_file(dir / "seed.sqlite", read_file(path));
    fs::remove(path);
}

// mesh_fuzz: the first byte names the file (0 .ply, 1 .off, 2 .stl, 3 .obj), the rest is the file.
void mesh_seeds(const fs::path& dir) {
    esf::Mesh tet;
    tet.vertices = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}};
    tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    fs::create_directories(dir);
    const fs::path ply = dir / "tmp.ply";
    esf::write_ply_mesh(ply.string(), tet);
    write_file(dir / "binary.ply.seed", std::string(1, '\0') + read_file(ply));
    fs::remove(ply);
    write_file(dir / "ascii.ply.seed",
               std::string(1, '\0') +
                   "ply\nformat ascii 1.0\ncomment esf\nelement vertex 4\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 2\n"
                   "property list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n4 0 1 3 2\n");
    write_file(dir / "tet.off.seed", std::string(1, '\1') +
                                         "OFF\n# a tetrahedron\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n"
                                         "0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    std::string stl(1, '\2');
    stl += "binary STL written by esf_fuzz_seeds";
    stl.resize(81, '\0');
    const std::uint32_t count = 2;
    for (int b = 0; b < 4; ++b) stl.push_back(static_cast<char>((count >> (8 * b)) & 0xffu));
    for (std::size_t t = 0; t < count; ++t) {
        float facet[12] = {0, 0, 1};  // the normal, then three corners
        for (int k = 0; k < 3; ++k) facet[3 + 3 * k + k] = 1.0f + static_cast<float>(t);
        stl.append(reinterpret_cast<const char*>(facet), sizeof facet);
        stl.append(2, '\0');  // the attribute
    }
    write_file(dir / "binary.stl.seed", stl);
    write_file(dir / "ascii.stl.seed",
               std::string(1, '\2') +
                   "solid tri\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                   "vertex 0 1 0\nendloop\nendfacet\nendsolid tri\n");
    write_file(dir / "quad.obj.seed",
               std::string(1, '\3') + "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
}

// kinect_recording_fuzz: the first byte picks the reader (0 depth .pgm, 1 colour .ppm, 2
// INDEX.txt; + 0x80: a frame's pixels are repeated to the whole frame), the rest is the file.
// Frames are full 640 x 480 ones, as the readers require.
void kinect_recording_seeds(const fs::path& dir) {
    std::vector<std::uint16_t> depth(esf::kKinectFramePixels);
    for (std::size_t i = 0; i < depth.size(); ++i)
        depth[i] = static_cast<std::uint16_t>(i % (esf::kKinectRawNoReading + 1));  // 2047 too
    std::ostringstream pgm;
    esf::write_kinect_depth_pgm(pgm, depth);
    write_file(dir / "depth.pgm.seed", std::string(1, '\0') + pgm.str());
    std::vector<std::uint8_t> rgb(3 * esf::kKinectFramePixels);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>(i * 7);
    std::ostringstream ppm;
    esf::write_kinect_rgb_ppm(ppm, rgb);
    write_file(dir / "rgb.ppm.seed", std::string(1, '\1') + ppm.str());
    // Header lines with a few pixels, read whole (truncated) and repeated to a whole frame.
    for (const int pad : {0x00, 0x80}) {
        const std::string tag = pad ? "_header_repeated" : "_header";
        write_file(dir / ("depth" + tag + ".pgm.seed"),
                   std::string(1, static_cast<char>(pad)) + "P5 640 480 65535\n\xff\x07\x10\x01");
        write_file(dir / ("rgb" + tag + ".ppm.seed"),
                   std::string(1, static_cast<char>(pad | 1)) + "P6 640 480 255\n\x01\x02\x03");
    }
    write_file(dir / "index.txt.seed", std::string(1, '\2') +
                                           "r-1294102395.455289-3420483396.ppm\n"
                                           "d-1294102395.455601-3420483397.pgm\r\n"
                                           "\n"
                                           "a-1294102395.456000-0.dump\n"
                                           "d-1294102395.488934-3420484397.pgm\n");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: esf_fuzz_seeds OUT_DIR\n";
        return 1;
    }
    try {
        const fs::path root = argv[1];
        pcd_seeds(root / "pcd");
        lzf_seeds(root / "lzf");
        ply_seeds(root / "ply_cloud");
        xyz_seeds(root / "xyz");
        depth_png_seeds(root / "depth_png");
        csv_seeds(root);
        database_seeds(root / "database");
        mesh_seeds(root / "mesh");
        kinect_recording_seeds(root / "kinect_recording");
    } catch (const std::exception& e) {
        std::cerr << "esf_fuzz_seeds: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
