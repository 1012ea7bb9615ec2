// Uses the installed esf: describes a generated cloud, writes and reads it back, and checks
// that the descriptor is a 640-bin histogram summing to 1 and the same after the round trip;
// writes a mesh and loads it back (through the installed mesh importer helper) and renders it
// (Embree, opened on the first rendering call: the package does not link it).

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "esf/esf.hpp"  // the umbrella header: the whole installed API

int main(int argc, char** argv) {
    try {
        esf::PointCloud cloud;
        for (int i = 0; i < 40; ++i)  // three faces of a 10 cm box, 1,600 points each
            for (int j = 0; j < 40; ++j) {
                const float u = 0.0025f * static_cast<float>(i),
                            v = 0.0025f * static_cast<float>(j);
                cloud.points.emplace_back(u, v, 0.8f);
                cloud.points.emplace_back(u, 0.1f, 0.8f + v);
                cloud.points.emplace_back(0.1f, u, 0.8f + v);
            }
        const std::string path =
            (std::filesystem::path(argc > 1 ? argv[1] : ".") / "consumer_cloud.pcd").string();
        esf::write_pcd(path, cloud);
        const esf::PointCloud back = esf::read_cloud(path);
        const esf::EsfResult a = esf::compute_esf(cloud.points);
        const esf::EsfResult b = esf::compute_esf(back.points);
        double sum = 0.0;
        for (const float v : a.descriptor) sum += v;
        if (a.descriptor != b.descriptor || std::abs(sum - 1.0) > 1e-4) {
            std::fprintf(stderr, "consumer: unexpected descriptor (sum %f)\n", sum);
            return 1;
        }
        esf::Mesh mesh;
        mesh.vertices = {{0.0f, 0.0f, 0.0f}, {0.1f, 0.0f, 0.0f}, {0.0f, 0.1f, 0.0f}};
        mesh.triangles = {{0, 1, 2}};
        const std::string mesh_path =
            (std::filesystem::path(argc > 1 ? argv[1] : ".") / "consumer_mesh.ply").string();
        esf::write_ply_mesh(mesh_path, mesh);
        const esf::Mesh loaded = esf::load_mesh(mesh_path);
        if (loaded.vertices != mesh.vertices || loaded.triangles != mesh.triangles) {
            std::fprintf(stderr, "consumer: the mesh read back differs\n");
            return 1;
        }
        esf::RenderOptions options;
        options.level = 0;
        options.threads = 1;
        std::size_t rendered = 0;
        for (const esf::RenderedView& view : esf::render_views(loaded, options))
            rendered += view.points.size();
        if (rendered == 0) {
            std::fprintf(stderr, "consumer: no view of the mesh has a point\n");
            return 1;
        }
        std::printf(
            "consumer: esf descriptor of %zu points, sum %.6f; %zu descriptors known; %zu points "
            "rendered\n",
            back.points.size(), sum, esf::descriptor_names().size(), rendered);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 2;
    }
    return 0;
}
