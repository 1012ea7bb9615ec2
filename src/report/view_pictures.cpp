#include "esf/report/view_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "esf/io/cloud_io.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/report/point_picture.hpp"

namespace esf {

struct ViewRenderer::Impl {
    std::string mesh_root;
    CameraIntrinsics camera;
    std::map<std::pair<std::string, std::string>, ModelInfo> models;
    std::map<std::pair<std::string, std::string>, std::unique_ptr<MeshRenderer>> renderers;
};

ViewRenderer::ViewRenderer(const std::string& database, const std::string& mesh_root,
                           const CameraIntrinsics& camera)
    : impl_(std::make_unique<Impl>()) {
    impl_->mesh_root = mesh_root;
    impl_->camera = camera;
    const Database db(database, OpenMode::kRead);
    for (ModelInfo& m : db.models()) {
        auto key = std::make_pair(m.category, m.name);
        impl_->models.emplace(std::move(key), std::move(m));
    }
}

ViewRenderer::~ViewRenderer() = default;
ViewRenderer::ViewRenderer(ViewRenderer&&) noexcept = default;
ViewRenderer& ViewRenderer::operator=(ViewRenderer&&) noexcept = default;

Points ViewRenderer::render(const std::string& category, const std::string& model,
                            const Eigen::Matrix4f& pose) {
    const auto key = std::make_pair(category, model);
    const auto found = impl_->models.find(key);
    if (found == impl_->models.end())
        throw std::invalid_argument("no model " + category + "/" + model + " in the database");
    // The pose's upper-left block is scale * rotation.
    const Eigen::Matrix3d block = pose.block<3, 3>(0, 0).cast<double>();
    const double scale = block.col(0).norm();
    if (!(scale > 0.0) || !std::isfinite(scale))
        throw std::invalid_argument("view of " + category + "/" + model + ": a degenerate pose");
    auto& renderer = impl_->renderers[key];
    if (!renderer) {
        const Mesh mesh =
            load_mesh((std::filesystem::path(impl_->mesh_root) / found->second.file).string());
        RenderOptions options;
        options.camera = impl_->camera;
        options.noise = SensorNoise::kNone;
        options.scale = scale;
        options.threads = 1;
        renderer = std::make_unique<MeshRenderer>(mesh, options);
    }
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    motion.linear() = block / scale;
    motion.translation() = pose.block<3, 1>(0, 3).cast<double>();
    return renderer->render_pose(motion, 0);
}

namespace {

/// The nearest view of each class among all views: class name -> (distance, view id).
std::map<std::string, std::pair<double, std::uint32_t>> nearest_per_class(
    const Recognizer& recognizer, const QueryDescriptor& query) {
    const Classifier& classifier = recognizer.classifier();
    const KnnIndex& index = classifier.index();
    const std::size_t dim = index.dimension();
    std::map<std::string, std::pair<double, std::uint32_t>> best;
    for (std::size_t s = 0; s + dim <= query.signatures.size(); s += dim) {
        const std::span<const float> signature(query.signatures.data() + s, dim);
        for (std::size_t row = 0; row < index.rows(); ++row) {
            const std::uint32_t view = index.view_of(row);
            const double d = index.distance(signature, row);
            const std::string& name = classifier.labels()[view].class_name;
            auto it = best.find(name);
            if (it == best.end())
                best.emplace(name, std::make_pair(d, view));
            else if (std::make_pair(d, view) < it->second)
                it->second = {d, view};
        }
    }
    return best;
}

std::string view_name(const ViewLabel& label) {
    return label.model_name + " #" + std::to_string(label.view);
}

GalleryPicture picture_of(const Points& points, const GalleryOptions& options, std::uint8_t tint,
                          const std::string& caption) {
    PointPictureOptions p;
    p.width = options.width;
    p.height = options.height;
    const std::vector<std::uint8_t> tints(points.size(), tint);
    const PointPicture picture = draw_points(points, p, tints);
    return {png_data_uri(picture_png(picture)), caption};
}

}  // namespace

std::vector<GalleryEntry> misclassified_gallery(const Recognizer& recognizer,
                                                const EvaluationReport& report,
                                                const GalleryOptions& options) {
    std::vector<GalleryEntry> out;
    std::map<std::string, std::size_t> per_class;
    const auto& labels = recognizer.classifier().labels();
    for (const QueryResult& q : report.queries) {
        if (q.predicted == q.true_class) continue;
        std::size_t& shown = per_class[q.true_class];
        if (options.per_class && shown >= options.per_class) continue;
        ++shown;
        GalleryEntry e;
        e.file = q.file;
        e.true_class = q.true_class;
        e.predicted = q.predicted;
        e.matched_distance = q.distance;
        e.rank = q.rank;
        e.query.caption = "query: " + q.true_class;
        try {
            const PointCloud cloud = read_cloud(q.file);
            const Points points = drop_non_finite(cloud.points).points;
            e.query = picture_of(points, options, kTintBlue, e.query.caption);
            const QueryDescriptor d = recognizer.describe(points);
            if (!d.ok()) throw std::invalid_argument(d.error);
            const auto best = nearest_per_class(recognizer, d);
            std::pair<double, std::uint32_t> nearest{std::numeric_limits<double>::infinity(), 0};
            for (const auto& [name, v] : best) nearest = std::min(nearest, v);
            const ViewLabel& matched = labels[nearest.second];
            e.predicted = matched.class_name;
            e.matched_view = view_name(matched);
            e.matched_distance = nearest.first;
            e.matched.caption = "nearest: " + matched.class_name;
            const auto true_it = best.find(q.true_class);
            const ViewLabel* truth = nullptr;
            if (true_it != best.end()) {
                truth = &labels[true_it->second.second];
                e.true_view = view_name(*truth);
                e.true_distance = true_it->second.first;
                e.nearest_true.caption = "nearest " + q.true_class;
            }
            if (!options.views) {
                e.note = "training views are drawn when the meshes are given";
            } else {
                try {
                    e.matched = picture_of(
                        options.views->render(matched.class_name, matched.model_name, matched.pose),
                        options, kTintGrey, e.matched.caption);
                    if (truth)
                        e.nearest_true =
                            picture_of(options.views->render(truth->class_name, truth->model_name,
                                                             truth->pose),
                                       options, kTintGrey, e.nearest_true.caption);
                } catch (const std::exception& error) {
                    e.note = error.what();
                }
            }
        } catch (const std::exception& error) {
            e.note = error.what();
        }
        out.push_back(std::move(e));
    }
    return out;
}

}  // namespace esf
