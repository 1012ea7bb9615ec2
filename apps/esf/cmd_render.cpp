// esf render MESH -o DIR : synthetic partial views of a CAD model from a tessellated view sphere.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/atomic_file.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/render/render.hpp"

namespace esf::cli {

namespace {

struct RenderArgs {
    std::string mesh;
    std::string output;
    int level = 1;
    bool pcl_camera = false;
    std::optional<int> width, height;
    std::optional<double> fx, fy, cx, cy;
    double fill = 0.5;
    std::optional<double> distance;
    std::optional<double> scale;
    std::optional<double> extent;
    SensorNoise noise = RenderOptions{}.noise;
    std::uint64_t seed = 0;
    int threads = 0;
    PcdEncoding encoding = PcdEncoding::kBinary;
    bool json = false;
};

std::string view_name(std::size_t index, std::size_t count) {
    int digits = 3;
    for (std::size_t n = count > 0 ? count - 1 : 0; n >= 1000; n /= 10) ++digits;
    std::ostringstream name;
    name << "view_" << std::setw(digits) << std::setfill('0') << index << ".pcd";
    return name.str();
}

void run_render(const RenderArgs& args) {
    RenderOptions options;
    options.level = args.level;
    options.camera =
        args.pcl_camera ? CameraIntrinsics::pcl_renderer() : CameraIntrinsics::kinect();
    if (args.width) {
        options.camera.width = *args.width;
        if (!args.cx) options.camera.cx = (*args.width - 1) / 2.0;
    }
    if (args.height) {
        options.camera.height = *args.height;
        if (!args.cy) options.camera.cy = (*args.height - 1) / 2.0;
    }
    if (args.fx) options.camera.fx = *args.fx;
    if (args.fy) options.camera.fy = *args.fy;
    if (args.cx) options.camera.cx = *args.cx;
    if (args.cy) options.camera.cy = *args.cy;
    options.fill_fraction = args.fill;
    options.distance = args.distance;
    if (args.scale) options.scale = *args.scale;
    options.target_extent = args.extent;
    options.noise = args.noise;
    options.seed = args.seed;
    options.threads = args.threads;
    const PcdEncoding encoding = args.encoding;

    const auto start = std::chrono::steady_clock::now();
    const Mesh mesh = load_mesh(args.mesh);
    const MeshRenderer renderer(mesh, options);  // validates the options

    const std::filesystem::path dir(args.output);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir))
        throw IoError(file_message(
            args.output, 0,
            "cannot create the output directory" + (ec ? ": " + ec.message() : std::string())));

    const std::size_t count = renderer.view_count();
    std::vector<Eigen::Matrix4f> poses(count);
    std::vector<std::size_t> points(count);
    Progress progress("render", count);
    std::atomic<std::size_t> done{0};
    parallel_for_slots(count, args.threads, [&](std::size_t i, int slot) {
        RenderedView view = renderer.render_view(i);
        poses[i] = view.pose;
        points[i] = view.points.size();
        PointCloud cloud;
        cloud.width = static_cast<std::uint32_t>(view.points.size());
        cloud.height = 1;
        cloud.points = std::move(view.points);
        write_pcd((dir / view_name(i, count)).string(), cloud, encoding);
        ++done;
        if (slot == 0) progress.update(done.load());
    });
    progress.finish();

    // poses.csv: one row per view, the model -> camera matrix row by row.
    std::ostringstream csv;
    csv << "view";
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) csv << ",r" << r << c;
    csv << '\n' << std::setprecision(9);
    for (std::size_t i = 0; i < count; ++i) {
        csv << i;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) csv << ',' << poses[i](r, c);
        csv << '\n';
    }
    detail::write_file_atomically(dir / "poses.csv", csv.str());

    const CameraIntrinsics& k = options.camera;
    nlohmann::json summary = {
        {"mesh", args.mesh},
        {"output", args.output},
        {"views", count},
        {"level", options.level},
        {"camera",
         {{"width", k.width},
          {"height", k.height},
          {"fx", k.fx},
          {"fy", k.fy},
          {"cx", k.cx},
          {"cy", k.cy}}},
        {"noise", to_string(options.noise)},
        {"seed", options.seed},
        {"scale", renderer.scale()},
        {"centre", {renderer.centre().x(), renderer.centre().y(), renderer.centre().z()}},
        {"radius_m", renderer.radius()},
        {"camera_distance_m", renderer.camera_distance()},
    };
    nlohmann::json view_list = nlohmann::json::array();
    std::size_t total = 0;
    for (std::size_t i = 0; i < count; ++i) {
        total += points[i];
        std::vector<std::vector<float>> rows;
        for (int r = 0; r < 4; ++r)
            rows.push_back({poses[i](r, 0), poses[i](r, 1), poses[i](r, 2), poses[i](r, 3)});
        view_list.push_back(
            {{"view", i}, {"file", view_name(i, count)}, {"points", points[i]}, {"pose", rows}});
    }
    summary["points"] = total;
    summary["seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    nlohmann::json file_summary = summary;
    file_summary["view_list"] = view_list;
    detail::write_file_atomically(dir / "render.json", file_summary.dump(1) + "\n");

    if (args.json) {
        std::cout << summary.dump(1) << '\n';
    } else {
        std::printf(
            "rendered %zu views of %s to %s: %.0f points per view, camera %.3f m from the "
            "centre, scale %g, %.2f s\n",
            count, args.mesh.c_str(), args.output.c_str(),
            count ? static_cast<double>(total) / static_cast<double>(count) : 0.0,
            renderer.camera_distance(), renderer.scale(), summary["seconds"].get<double>());
    }
}

}  // namespace

void add_render_command(CLI::App& app) {
    auto args = std::make_shared<RenderArgs>();
    CLI::App* cmd = add_command(
        app, "render", "Render synthetic partial views of a CAD mesh from a view sphere",
        "Render synthetic partial views of a CAD mesh (PLY, OBJ, OFF, STL, glTF/GLB, DAE, 3DS, "
        "...)\nfrom cameras on a tessellated view sphere looking at the model's bounding-box "
        "centre.\nWrites DIR/view_NNN.pcd (points in the camera frame: x right, y down, z "
        "forward, metres),\nDIR/poses.csv (view,r00..r33: the 4x4 model -> camera matrix row by "
        "row; with --scale or\n--extent its 3x3 block is scale * rotation) and DIR/render.json "
        "(settings, points per view).");
    cmd->add_option("mesh", args->mesh, "Mesh file (several meshes in one file are merged)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", args->output, "Output directory (created if missing)")
        ->required();
    cmd->add_option("--level", args->level,
                    "View sphere subdivisions: 0 = 20 views, 1 = 80 (paper), 2 = 320, ... 6")
        ->check(CLI::Range(0, 6))
        ->capture_default_str();
    cmd->add_flag("--pcl-camera", args->pcl_camera,
                  "PCL's renderer camera: 150x150 pixels, 57 deg field of view (default: Kinect "
                  "v1, 640x480, fx = fy = 525 px)");
    cmd->add_option("--width", args->width, "Image width, pixels (cx defaults to the centre)")
        ->check(CLI::Range(1, CameraIntrinsics::kMaxSide));
    cmd->add_option("--height", args->height, "Image height, pixels (cy defaults to the centre)")
        ->check(CLI::Range(1, CameraIntrinsics::kMaxSide));
    cmd->add_option("--fx", args->fx, "Focal length x, pixels")->check(CLI::PositiveNumber);
    cmd->add_option("--fy", args->fy, "Focal length y, pixels")->check(CLI::PositiveNumber);
    cmd->add_option("--cx", args->cx, "Principal point x, pixels (pixel centres are integers)");
    cmd->add_option("--cy", args->cy, "Principal point y, pixels");
    auto* fill = cmd->add_option("--fill", args->fill,
                                 "Fraction of the smaller image side the model's bounding sphere "
                                 "spans (sets the camera distance)")
                     ->check(CLI::PositiveNumber)
                     ->capture_default_str();
    cmd->add_option("--distance", args->distance,
                    "Camera distance from the model's centre, metres (instead of --fill)")
        ->check(CLI::PositiveNumber)
        ->excludes(fill);
    auto* scale = cmd->add_option("--scale", args->scale,
                                  "Factor from file units to metres, e.g. 0.001 for millimetres "
                                  "(default 1: the file is in metres)")
                      ->check(CLI::PositiveNumber);
    cmd->add_option("--extent", args->extent,
                    "Rescale the model so its longest bounding-box side is this many metres "
                    "(for non-metric meshes, e.g. KIT)")
        ->check(CLI::PositiveNumber)
        ->excludes(scale);
    add_enum_option(*cmd, "--noise", args->noise,
                    "Sensor model: kinect (axial noise, 1/8 px disparity quantisation, drops at "
                    "grazing angles) or none (exact depth)");
    add_seed_option(*cmd, args->seed, "Noise seed; same seed, same views (any thread count)");
    add_threads_option(*cmd, args->threads);
    add_enum_option(*cmd, "--encoding", args->encoding,
                    "PCD encoding: binary, ascii or binary_compressed");
    cmd->add_flag("--json", args->json, "Print the summary as JSON");
    cmd->callback([args] { run_render(*args); });
}

}  // namespace esf::cli
