#include "esf/recognition/recognizer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "core/splitmix64.hpp"
#include "esf/core/error.hpp"
#include "esf/core/parallel.hpp"
#include "esf/descriptors/primitive_fit.hpp"
#include "esf/mesh/mesh.hpp"
#include "esf/recognition/knn_index.hpp"
#include "esf/training/descriptor_settings.hpp"
#include "esf/training/training.hpp"
#include "recognition/neighbour_merge.hpp"

namespace esf {

namespace {

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

// ---- query descriptors ----------------------------------------------------------------------

/// Describes query clouds; thread-safe.
class Describer {
  public:
    virtual ~Describer() = default;
    /// Signatures, row-major. Throws std::invalid_argument naming the descriptor.
    virtual std::vector<float> describe(std::span<const Eigen::Vector3f> points) const = 0;
};

/// Seed of sampling s of a query: the database's seed for s = 0 (so one sampling describes a
/// query as before), then seeds derived from it.
std::uint64_t sampling_seed(std::uint64_t seed, int sampling) {
    if (sampling == 0) return seed;
    return detail::mix64(seed + detail::kGoldenGamma * static_cast<std::uint64_t>(sampling));
}

/// The database's descriptor (descriptor_settings.hpp); with several samplings, one descriptor
/// per sampling seed and the mean of their signatures (single-signature descriptors).
class SeededDescriber final : public Describer {
  public:
    SeededDescriber(const QuerySetup& setup, int samplings) {
        const DescriptorSetup descriptor{setup.kind.name, setup.esf, setup.options};
        const std::uint64_t seed =
            descriptor_info(setup.kind.name).esf_options ? setup.esf.seed : setup.options.seed;
        for (int s = 0; s < samplings; ++s)
            descriptors_.push_back(make_descriptor(descriptor, sampling_seed(seed, s)));
        if (samplings > 1 && descriptors_.front()->info().multi_signature)
            throw std::invalid_argument(setup.kind.name +
                                        ": several samplings need a single-signature descriptor");
    }

    std::vector<float> describe(std::span<const Eigen::Vector3f> points) const override {
        const DescriptorInfo& info = descriptors_.front()->info();
        const auto dim = static_cast<std::size_t>(info.dimension);
        std::vector<double> sum;
        std::vector<float> out;
        for (const auto& descriptor : descriptors_) {
            const std::vector<Signature> signatures = descriptor->compute(points);
            if (signatures.empty()) throw std::invalid_argument(info.name + ": no signature");
            for (const Signature& sig : signatures)
                if (sig.size() != dim)
                    throw std::invalid_argument(info.name + ": a signature of " +
                                                std::to_string(sig.size()) + " floats, expected " +
                                                std::to_string(dim));
            if (descriptors_.size() == 1) {
                out.reserve(signatures.size() * dim);
                for (const Signature& sig : signatures)
                    out.insert(out.end(), sig.begin(), sig.end());
                return out;
            }
            sum.resize(dim, 0.0);
            for (std::size_t i = 0; i < dim; ++i) sum[i] += signatures.front()[i];
        }
        out.resize(dim);
        const double scale = 1.0 / static_cast<double>(descriptors_.size());
        for (std::size_t i = 0; i < dim; ++i) out[i] = static_cast<float>(sum[i] * scale);
        return out;
    }

  private:
    std::vector<std::unique_ptr<GlobalDescriptor>> descriptors_;
};

std::unique_ptr<Describer> make_describer(const QuerySetup& setup, int samplings) {
    return std::make_unique<SeededDescriber>(setup, samplings);
}

/// Merges the k nearest views of each query signature into the k nearest views of the query:
/// a view's distance is its smallest over the signatures (ties: the lower row); one per model.
std::vector<KnnNeighbour> merge_neighbours(const std::vector<KnnResult>& results, std::size_t k,
                                           const KnnIndex& index) {
    std::vector<KnnNeighbour> all;
    for (const KnnResult& r : results)
        all.insert(all.end(), r.neighbours.begin(), r.neighbours.end());
    return detail::merge_signature_neighbours(std::move(all), k, index,
                                              [](std::uint32_t) { return true; });
}

}  // namespace

// ---- setup ----------------------------------------------------------------------------------

int descriptor_version(const std::string& name) { return stored_descriptor_version(name); }

QuerySetup query_setup(const Settings& settings, const DescriptorKind& kind) {
    const DescriptorSetup read = read_descriptor_setup(settings, kind);
    QuerySetup setup;
    setup.kind = kind;
    setup.esf = read.esf;
    setup.options = read.options;
    return setup;
}

// ---- recognizer -----------------------------------------------------------------------------

struct Recognizer::Impl {
    RecognizerOptions options;
    RecognizerInfo info;
    std::unique_ptr<Describer> describer;
    std::unique_ptr<Classifier> classifier;
    std::size_t dimension = 0;
    // Where the descriptor's cylinder-box block lies (size 0: none), and each model's mean
    // contrast over its views (NaN: none), by model id.
    std::size_t primitive_offset = 0, primitive_size = 0;
    std::vector<double> model_contrast;
    std::vector<ModelInfo> models;  // by model id (DescriptorMatrix::models)
    // Verification: each model's surface (stored, or sampled from its mesh) and its search grid,
    // loaded on first use; `stored` reads the database's surfaces (under surfaces_mutex).
    bool verifies = false;
    std::uint64_t training_seed = 0;  // the models' surface seeds derive from it, as in training
    std::optional<Database> stored;
    mutable std::mutex surfaces_mutex;
    mutable std::map<int, std::shared_ptr<const PreparedModel>> surfaces;

    std::shared_ptr<const PreparedModel> surface(int model_id) const {
        const std::lock_guard<std::mutex> lock(surfaces_mutex);
        const auto it = surfaces.find(model_id);
        if (it != surfaces.end()) return it->second;
        const ModelInfo& m = models.at(static_cast<std::size_t>(model_id));
        std::optional<ModelSurface> sampled;
        if (stored) {
            sampled = stored->model_surface(m.category, m.name);
            if (!sampled)
                throw IoError(file_message(
                    stored->path(), 0,
                    "model '" + m.category + "/" + m.name + "' has no stored surface"));
        } else {
            const std::string path =
                (std::filesystem::path(options.verification_meshes) / m.file).string();
            sampled =
                sample_model_surface(load_mesh(path), m.scale, options.verification.surface_points,
                                     model_seed(training_seed, m.category, m.name));
        }
        auto surface = std::make_shared<const PreparedModel>(std::move(*sampled));
        surfaces.emplace(model_id, surface);
        return surface;
    }
};

Recognizer::Recognizer(const std::string& path, const RecognizerOptions& options)
    : impl_(std::make_unique<Impl>()) {
    if (options.k == 0) throw std::invalid_argument("recognizer: k must be >= 1");
    if (options.query_samplings < 1)
        throw std::invalid_argument("recognizer: query samplings must be >= 1, got " +
                                    std::to_string(options.query_samplings));
    resolve_threads(options.threads);
    if (options.verify) validate(options.verification);
    if (!(options.merge_min_inliers >= 0.0 && options.merge_min_inliers <= 1.0))
        throw std::invalid_argument("recognizer: merge_min_inliers must be in [0, 1], got " +
                                    std::to_string(options.merge_min_inliers));
    if (options.verify && !options.verification_meshes.empty()) {
        if (!std::filesystem::is_directory(options.verification_meshes))
            throw IoError(file_message(options.verification_meshes, 0,
                                       "not a folder (verification needs the training meshes)"));
    }
    impl_->options = options;
    auto fail = [&](const std::string& reason) {
        throw std::invalid_argument(file_message(path, 0, reason));
    };

    Database db(path, OpenMode::kRead);  // kept for the stored surfaces when they verify
    const std::vector<DescriptorKind> kinds = db.descriptor_kinds();
    if (kinds.empty()) fail("empty database: no descriptors (train it first with esf train)");
    DescriptorKind kind;
    if (options.descriptor.empty()) {
        if (kinds.size() > 1) {
            std::vector<std::string> names;
            for (const auto& k : kinds) names.push_back(k.name);
            fail("the database holds several descriptors (" + joined(names) + "); choose one");
        }
        kind = kinds.front();
    } else {
        const auto it = std::find_if(kinds.begin(), kinds.end(), [&](const DescriptorKind& k) {
            return k.name == options.descriptor;
        });
        if (it == kinds.end()) fail("the database holds no " + options.descriptor + " descriptors");
        kind = *it;
    }
    try {
        impl_->info.setup = query_setup(db.settings(), kind);
    } catch (const std::invalid_argument& e) {
        fail(e.what());
    }
    if (!kernels_supported(options.kernels))
        throw std::invalid_argument(std::string("recognizer: this CPU does not run the ") +
                                    to_string(options.kernels) + " kernels");
    impl_->info.setup.esf.kernels = options.kernels;
    impl_->info.setup.options.kernels = options.kernels;
    impl_->describer = make_describer(impl_->info.setup, options.query_samplings);

    DescriptorMatrix matrix = db.load_descriptors(kind.name);
    if (matrix.rows() == 0)
        fail("empty database: no views with " + kind.name + " descriptors (" +
             std::to_string(matrix.models.size()) + " complete models)");
    const auto dim = static_cast<std::size_t>(kind.dimension);
    impl_->dimension = dim;
    {
        const DescriptorInfo info = descriptor_info(kind.name);
        std::size_t offset = 0;
        for (std::size_t b = 0; b < info.blocks.size() && b < info.block_names.size(); ++b) {
            const auto size = static_cast<std::size_t>(info.blocks[b]);
            if (info.block_names[b] == kPrimitiveBlockName && offset + size <= dim) {
                impl_->primitive_offset = offset;
                impl_->primitive_size = size;
            }
            offset += size;
        }
    }

    KnnIndexOptions index_options;
    index_options.threads = options.threads;
    index_options.kernels = options.kernels;
    index_options.sketch_group = descriptor_sketch_group(kind.name);
    if (options.use_weights) {
        if (const auto weights = db.weights(kind.name)) {
            try {
                index_options.weights =
                    descriptor_dimension_weights(descriptor_info(kind.name), *weights);
            } catch (const std::invalid_argument& e) {
                fail(e.what());
            }
            impl_->info.weighted = true;
        }
    }

    // One index view per (model, view index); consecutive rows of a view are its signatures.
    std::vector<std::uint32_t> row_views(matrix.rows());
    std::vector<ViewLabel> labels;
    bool grouped = false;
    for (std::size_t r = 0; r < matrix.rows(); ++r) {
        const DescriptorRow& row = matrix.row_info[r];
        const bool same_view = r > 0 && matrix.row_info[r - 1].model == row.model &&
                               matrix.row_info[r - 1].view_index == row.view_index;
        if (same_view) {
            grouped = true;
        } else {
            ViewLabel label;
            label.class_name = matrix.categories[row.category];
            label.class_id = static_cast<int>(row.category);
            label.model_name = matrix.models[row.model].name;
            label.model_id = static_cast<int>(row.model);
            label.view = row.view_index;
            label.pose = row.pose;
            labels.push_back(std::move(label));
        }
        row_views[r] = static_cast<std::uint32_t>(labels.size() - 1);
    }
    if (options.one_view_per_model) {
        // Models numbered densely in view order (the matrix holds a model's views together).
        index_options.view_families.reserve(labels.size());
        std::uint32_t family = 0;
        for (std::size_t v = 0; v < labels.size(); ++v) {
            if (v > 0 && labels[v].model_id != labels[v - 1].model_id) ++family;
            index_options.view_families.push_back(family);
        }
    }
    KnnIndex index = grouped ? KnnIndex(matrix.data, dim, row_views, index_options)
                             : KnnIndex(matrix.data, dim, index_options);
    impl_->info.database = path;
    impl_->info.views = labels.size();
    impl_->info.rows = matrix.rows();
    impl_->info.models = matrix.models.size();
    impl_->info.categories = matrix.categories;
    impl_->models = matrix.models;
    impl_->info.verification = "off";
    if (options.verify && !options.verification_meshes.empty()) {
        impl_->verifies = true;
        try {
            impl_->training_seed = stored_seed(db.settings());
        } catch (const std::invalid_argument& e) {
            fail(e.what());
        }
        impl_->info.verification = "meshes of " + options.verification_meshes;
    } else if (options.verify) {
        const DatabaseSummary summary = db.summary();
        if (summary.surfaces == summary.models) {
            impl_->verifies = true;
            impl_->info.verification = "stored surfaces";
            impl_->stored.emplace(std::move(db));
        } else {
            impl_->info.verification = "off: " + std::to_string(summary.models - summary.surfaces) +
                                       " of " + std::to_string(summary.models) +
                                       " models have no stored surface (trained by an earlier esf)";
        }
    }
    ClassifierOptions classifier_options;
    classifier_options.k = options.k;
    classifier_options.vote = options.vote;
    impl_->classifier =
        std::make_unique<Classifier>(std::move(index), std::move(labels), classifier_options);
    // Each model's mean cylinder-box contrast over its views, for verification's shape term.
    impl_->model_contrast.assign(impl_->models.size(), std::numeric_limits<double>::quiet_NaN());
    if (impl_->primitive_size > 0) {
        const Classifier& classifier = *impl_->classifier;
        std::vector<double> sum(impl_->models.size(), 0.0);
        std::vector<std::size_t> count(impl_->models.size(), 0);
        for (std::size_t r = 0; r < classifier.labels().size(); ++r) {
            const auto model = static_cast<std::size_t>(classifier.labels()[r].model_id);
            const double contrast = shape_contrast(classifier.index().row(r));
            if (model >= sum.size() || !std::isfinite(contrast)) continue;
            sum[model] += contrast;
            ++count[model];
        }
        for (std::size_t m = 0; m < sum.size(); ++m)
            if (count[m] > 0) impl_->model_contrast[m] = sum[m] / static_cast<double>(count[m]);
    }
}

double Recognizer::shape_contrast(std::span<const float> signatures) const {
    if (impl_->primitive_size == 0 || signatures.size() < impl_->dimension)
        return std::numeric_limits<double>::quiet_NaN();
    return primitive_contrast(signatures.subspan(impl_->primitive_offset, impl_->primitive_size));
}

Recognizer::~Recognizer() = default;
Recognizer::Recognizer(Recognizer&&) noexcept = default;
Recognizer& Recognizer::operator=(Recognizer&&) noexcept = default;

const RecognizerInfo& Recognizer::info() const { return impl_->info; }
const RecognizerOptions& Recognizer::options() const { return impl_->options; }
const Classifier& Recognizer::classifier() const { return *impl_->classifier; }

QueryDescriptor Recognizer::describe(std::span<const Eigen::Vector3f> points) const {
    QueryDescriptor out;
    out.points = points.size();
    try {
        out.signatures = impl_->describer->describe(points);
    } catch (const std::exception& e) {  // a bad cloud; never fatal to a batch or a scene
        out.signatures.clear();
        out.error = e.what();
    }
    return out;
}

std::vector<QueryDescriptor> Recognizer::describe_batch(std::span<const Points> clouds) const {
    std::vector<QueryDescriptor> out(clouds.size());
    parallel_for(clouds.size(), impl_->options.threads,
                 [&](std::size_t i) { out[i] = describe(clouds[i]); });
    return out;
}

Classification Recognizer::classify_descriptor(std::span<const float> signatures) const {
    const std::size_t dim = impl_->dimension;
    if (signatures.empty() || signatures.size() % dim != 0)
        throw std::invalid_argument(
            "recognizer: a descriptor of " + std::to_string(signatures.size()) +
            " floats is not one or more signatures of " + std::to_string(dim));
    const Classifier& classifier = *impl_->classifier;
    Classification out;
    if (signatures.size() == dim) {
        out = classifier.classify(signatures);
    } else {
        std::vector<KnnResult> results;
        for (std::size_t s = 0; s < signatures.size(); s += dim)
            results.push_back(
                classifier.index().search(signatures.subspan(s, dim), impl_->options.k));
        const std::vector<KnnNeighbour> neighbours =
            merge_neighbours(results, impl_->options.k, classifier.index());
        out = classify_neighbours(neighbours, classifier.labels(), classifier.options().vote);
    }
    out.shape_contrast = shape_contrast(signatures);
    return out;
}

std::vector<CloudClassification> Recognizer::classify_batch(
    std::span<const QueryDescriptor> descriptors) const {
    std::vector<CloudClassification> out(descriptors.size());
    // Single signatures go to the classifier as one batch; multi-signature queries one by one.
    const std::size_t dim = impl_->dimension;
    std::vector<float> batch;
    std::vector<std::size_t> batch_items, other_items;
    for (std::size_t i = 0; i < descriptors.size(); ++i) {
        const QueryDescriptor& d = descriptors[i];
        if (!d.ok()) {
            out[i].error = d.error;
        } else if (d.signatures.size() == dim) {
            batch.insert(batch.end(), d.signatures.begin(), d.signatures.end());
            batch_items.push_back(i);
        } else {
            other_items.push_back(i);
        }
    }
    if (!batch_items.empty()) {
        std::vector<Classification> results =
            impl_->classifier->classify_batch(batch, impl_->options.threads);
        for (std::size_t j = 0; j < batch_items.size(); ++j) {
            Classification& c = out[batch_items[j]].classification;
            c = std::move(results[j]);
            c.shape_contrast = shape_contrast(descriptors[batch_items[j]].signatures);
        }
    }
    parallel_for(other_items.size(), impl_->options.threads, [&](std::size_t j) {
        const std::size_t i = other_items[j];
        try {
            out[i].classification = classify_descriptor(descriptors[i].signatures);
        } catch (const std::invalid_argument& e) {
            out[i].error = e.what();
        }
    });
    return out;
}

Classification Recognizer::classify(std::span<const Eigen::Vector3f> points) const {
    const QueryDescriptor d = describe(points);
    if (!d.ok()) throw std::invalid_argument(d.error);
    Classification c = classify_descriptor(d.signatures);
    if (verifies()) {
        const Points finite = drop_non_finite(points).points;
        verify(c, Observation{finite, nullptr});
    }
    return c;
}

std::vector<CloudClassification> Recognizer::classify_batch(std::span<const Points> clouds) const {
    std::vector<CloudClassification> out = classify_batch(describe_batch(clouds));
    if (verifies())
        parallel_for(out.size(), impl_->options.threads, [&](std::size_t i) {
            if (!out[i].ok()) return;
            const Points finite = drop_non_finite(clouds[i]).points;
            verify(out[i].classification, Observation{finite, nullptr});
        });
    return out;
}

bool Recognizer::verifies() const { return impl_->verifies; }

Points Recognizer::posed_surface(const Classification& c) const {
    if (!verifies() || !c.fit) return {};
    const auto& models = impl_->models;
    const auto it = std::find_if(models.begin(), models.end(), [&](const ModelInfo& m) {
        return m.category == c.class_name && m.name == c.best_model;
    });
    if (it == models.end()) return {};
    const auto model = impl_->surface(static_cast<int>(it - models.begin()));
    const ModelSurface& surface = model->surface();
    // The pose takes the file's coordinates to the camera; the samples are those times the scale.
    const Eigen::Matrix4d pose = c.pose.cast<double>();
    const Eigen::Matrix3d linear = pose.topLeftCorner<3, 3>() / surface.scale;
    const Eigen::Vector3d t = pose.topRightCorner<3, 1>();
    Points out;
    for (std::size_t i = 0; i < surface.points.size(); ++i) {
        const Eigen::Vector3d p = linear * surface.points[i].cast<double>() + t;
        const Eigen::Vector3d n = linear * surface.normals[i].cast<double>();
        if (n.dot(p) < 0.0) out.push_back(p.cast<float>());
    }
    return out;
}

void Recognizer::verify(Classification& c, const Observation& observation, const PriorFit* prior,
                        std::vector<CandidateFit>* out_candidates) const {
    if (!verifies() || c.neighbours.empty()) return;
    verify_prepared(c, PreparedObservation(observation, impl_->options.verification.camera), prior,
                    out_candidates);
}

void Recognizer::verify_prepared(Classification& c, const PreparedObservation& prepared,
                                 const PriorFit* prior,
                                 std::vector<CandidateFit>* out_candidates) const {
    if (!verifies() || c.neighbours.empty()) return;
    const VerificationOptions& o = impl_->options.verification;
    // A model the database rescaled (not metric in its catalog) has a guessed size.
    const auto guessed = [&](int model) {
        return impl_->models.at(static_cast<std::size_t>(model)).scale != 1.0;
    };
    const auto size_free = [&](int model) { return o.every_size_free || guessed(model); };
    std::vector<std::size_t> picks;  // neighbours fitted, each with its fit in `fits`
    std::vector<PoseFit> fits;
    if (prior && prior->pose.allFinite()) {
        const auto same = [&](const NeighbourView& n) { return n.model_id == prior->model_id; };
        const auto it = std::find_if(c.neighbours.begin(), c.neighbours.end(), same);
        if (it != c.neighbours.end() && (o.decide_class || it->class_name == c.class_name)) {
            picks.push_back(static_cast<std::size_t>(it - c.neighbours.begin()));
            fits.push_back(fit_model(*impl_->surface(prior->model_id), prior->pose.cast<double>(),
                                     prepared, o, size_free(prior->model_id),
                                     FitStart::kCameraPose));
        }
    }
    // Candidates compete by score, less the shape term where both contrasts are known.
    const auto shape_term = [&](int model_id) {
        const auto model = static_cast<std::size_t>(model_id);
        const double model_contrast = model < impl_->model_contrast.size()
                                          ? impl_->model_contrast[model]
                                          : std::numeric_limits<double>::quiet_NaN();
        const double term = o.shape_weight * std::abs(model_contrast - c.shape_contrast);
        return std::isfinite(term) ? term : 0.0;
    };
    const auto compared = [&](std::size_t j) {
        if (fits[j].abandoned) return -std::numeric_limits<double>::infinity();
        return fits[j].fit.score() - shape_term(c.neighbours[picks[j]].model_id);
    };
    // What a candidate's compared score must exceed to be named: the best so far, less the best's
    // resizing where the candidate shares its class (the look-alike rule below may then name
    // it for needing less).
    const auto bar_for = [&](const std::string& class_name) {
        double bar = -std::numeric_limits<double>::infinity();
        std::size_t best = 0;
        for (std::size_t j = 0; j < fits.size(); ++j)
            if (compared(j) > bar) {
                bar = compared(j);
                best = j;
            }
        if (!fits.empty() && std::isfinite(bar) &&
            c.neighbours[picks[best]].class_name == class_name)
            bar -= o.resize_weight * std::abs(std::log(fits[best].scale));
        return bar;
    };
    const bool prior_kept = !fits.empty() && fits.front().verified &&
                            fits.front().fit.score() >= prior->score - o.prior_tolerance;
    if (!prior_kept) {
        // The nearest neighbours of distinct models (of the named class unless decide_class).
        std::vector<std::size_t> candidates;
        std::vector<int> models;
        for (std::size_t i = 0; i < c.neighbours.size() && models.size() < o.candidates; ++i) {
            if (!o.decide_class && c.neighbours[i].class_name != c.class_name) continue;
            const int model = c.neighbours[i].model_id;
            if (std::find(models.begin(), models.end(), model) != models.end()) continue;
            models.push_back(model);
            candidates.push_back(i);
        }
        for (const std::size_t i : candidates) {
            if (!fits.empty() && fits.back().verified && fits.back().fit.score() >= o.accept_score)
                break;  // good enough: the farther candidates are not fitted
            const int model = c.neighbours[i].model_id;
            // A candidate that cannot win is dropped as soon as that is sure (where no fit ends
            // the search early, which needs every fit whole).
            const double must_beat = o.accept_score > 1.0 && !out_candidates
                                         ? bar_for(c.neighbours[i].class_name) + shape_term(model)
                                         : -std::numeric_limits<double>::infinity();
            picks.push_back(i);
            fits.push_back(fit_model(*impl_->surface(model), c.neighbours[i].pose.cast<double>(),
                                     prepared, o, size_free(model), FitStart::kTrainingView,
                                     must_beat));
        }
    }
    if (picks.empty()) return;
    if (out_candidates)
        for (std::size_t j = 0; j < fits.size(); ++j)
            out_candidates->push_back(
                {picks[j], fits[j], shape_term(c.neighbours[picks[j]].model_id)});
    std::size_t best = 0;
    for (std::size_t j = 1; j < fits.size(); ++j)
        if (compared(j) > compared(best)) best = j;
    // Look-alike models of the class named (a small and a large bottle of one make): the one
    // that needs the least resizing names the model and pose; the class stays.
    const std::string& named = c.neighbours[picks[best]].class_name;
    const auto resized = [&](std::size_t j) {
        return compared(j) - o.resize_weight * std::abs(std::log(fits[j].scale));
    };
    for (std::size_t j = 0; j < fits.size(); ++j)
        if (c.neighbours[picks[j]].class_name == named && resized(j) > resized(best)) best = j;

    // The best fit first, the other neighbours in their order.
    const std::size_t chosen = picks[best];
    std::rotate(c.neighbours.begin(), c.neighbours.begin() + static_cast<std::ptrdiff_t>(chosen),
                c.neighbours.begin() + static_cast<std::ptrdiff_t>(chosen) + 1);
    const NeighbourView& n = c.neighbours.front();
    adopt_neighbour(c, n);
    // A model of known size competed at a free size: its pose and fit are given at its own.
    if (o.every_size_free && !guessed(n.model_id) && !fits[best].abandoned)
        fits[best] = fit_model(*impl_->surface(n.model_id), fits[best].model_to_camera, prepared, o,
                               false, FitStart::kCameraPose);
    const double scale = impl_->models.at(static_cast<std::size_t>(n.model_id)).scale;
    Eigen::Matrix4d scaled = fits[best].model_to_camera;
    scaled.topLeftCorner<3, 3>() *= scale;
    c.pose = scaled.cast<float>();
    c.fit = fits[best].fit;
    c.verified = fits[best].verified;
    std::size_t same = 0;
    for (const NeighbourView& v : c.neighbours) same += v.class_name == c.class_name;
    c.confidence = static_cast<double>(same) / static_cast<double>(c.neighbours.size());
    const auto vote = std::find_if(c.votes.begin(), c.votes.end(), [&](const ClassVote& v) {
        return v.class_name == c.class_name;
    });
    if (vote != c.votes.end()) std::rotate(c.votes.begin(), vote, vote + 1);
}

SceneRecognition Recognizer::recognize(SegmentationResult segmentation) const {
    SceneRecognition out = recognize_unverified(std::move(segmentation));
    if (verifies()) verify_objects(out, nullptr, {});
    return out;
}

SceneRecognition Recognizer::recognize_unverified(SegmentationResult segmentation) const {
    SceneRecognition out;
    out.plane_found = segmentation.plane_found;
    out.plane = segmentation.plane;
    out.plane_inliers = segmentation.plane_inliers;
    out.finite_points = segmentation.finite_points;
    out.message = std::move(segmentation.message);
    std::vector<Cluster>& clusters = segmentation.clusters;
    std::vector<QueryDescriptor> descriptors(clusters.size());
    parallel_for(clusters.size(), impl_->options.threads,
                 [&](std::size_t i) { descriptors[i] = describe(clusters[i].points); });
    std::vector<CloudClassification> classes = classify_batch(descriptors);
    out.objects.resize(clusters.size());
    for (std::size_t i = 0; i < clusters.size(); ++i) {
        out.objects[i].cluster = std::move(clusters[i]);
        out.objects[i].classification = std::move(classes[i].classification);
        out.objects[i].error = std::move(classes[i].error);
    }
    return out;
}

const PointCloud* verification_frame(const PointCloud& scene, const CameraIntrinsics& camera,
                                     std::optional<PointCloud>& image) {
    // The frame is the free-space witness when it is what the camera model describes: its
    // image, or a cloud that is that image's points.
    if (scene.width == static_cast<std::uint32_t>(camera.width) &&
        scene.height == static_cast<std::uint32_t>(camera.height))
        return &scene;
    image.reset();
    if (!scene.organised()) image = depth_image_of(scene.points, camera);
    return image ? &*image : nullptr;
}

SceneRecognition Recognizer::recognize_scene(const PointCloud& scene,
                                             const SegmentationOptions& options) const {
    return recognize(segment_scene(scene, options), scene);
}

SceneRecognition Recognizer::recognize(SegmentationResult segmentation,
                                       const PointCloud& scene) const {
    return recognize(std::move(segmentation), scene, {});
}

SceneRecognition Recognizer::recognize(SegmentationResult segmentation, const PointCloud& scene,
                                       std::span<const std::optional<PriorFit>> priors) const {
    if (!priors.empty() && priors.size() != segmentation.clusters.size())
        throw std::invalid_argument("recognize: " + std::to_string(priors.size()) +
                                    " prior fits for " +
                                    std::to_string(segmentation.clusters.size()) + " clusters");
    SceneRecognition out = recognize_unverified(std::move(segmentation));
    if (verifies()) {
        std::optional<PointCloud> image;
        const PointCloud* frame =
            verification_frame(scene, impl_->options.verification.camera, image);
        verify_objects(out, frame, priors);
        if (frame && impl_->options.merge_parts && out.plane_found) merge_parts(out, *frame);
    }
    return out;
}

void Recognizer::adopt_part_model(Classification& merged, const Classification& part,
                                  const PreparedObservation& observation, double bar) const {
    if (!part.verified || part.best_model_id < 0) return;
    const VerificationOptions& o = impl_->options.verification;
    const ModelInfo& model = impl_->models.at(static_cast<std::size_t>(part.best_model_id));
    const bool guessed = model.scale != 1.0;  // a size the database guessed
    // The part's pose less the database's scale: the surface's own frame -> camera.
    Eigen::Matrix4d start = part.pose.cast<double>();
    start.topLeftCorner<3, 3>() /= model.scale;
    const PreparedModel& surface = *impl_->surface(part.best_model_id);
    // A fit that cannot beat the union's own verified fit, or the bar, changes nothing: it is
    // dropped as soon as that is sure.
    const double must_beat =
        merged.verified && merged.fit ? std::max(bar, merged.fit->score()) : bar;
    PoseFit fit = fit_model(surface, start, observation, o, o.every_size_free || guessed,
                            FitStart::kCameraPose, must_beat);
    if (!fit.verified || fit.abandoned) return;
    // A model of known size is given at its own size, as verify() gives it.
    if (o.every_size_free && !guessed)
        fit = fit_model(surface, fit.model_to_camera, observation, o, false, FitStart::kCameraPose);
    if (!fit.verified) return;
    if (merged.verified && merged.fit && merged.fit->score() >= fit.fit.score()) return;
    Classification adopted = part;
    Eigen::Matrix4d scaled = fit.model_to_camera;
    scaled.topLeftCorner<3, 3>() *= model.scale;
    adopted.pose = scaled.cast<float>();
    adopted.fit = fit.fit;
    adopted.verified = true;
    merged = std::move(adopted);
}

void Recognizer::merge_parts(SceneRecognition& scene, const PointCloud& frame) const {
    // Parts meet where a pixel of one, up to 6 pixels on along its row or column from a pixel of
    // the other, is within this of it (a thin stem or handle between them may be lost).
    constexpr float kContactDistance = 0.03f;
    constexpr std::size_t kMinContacts = 5;
    constexpr std::array<long, 4> kSteps = {1, 2, 4, 6};  // pixels along a row or column
    constexpr long kReach = kSteps.back();
    const CameraIntrinsics& camera = impl_->options.verification.camera;
    std::vector<RecognizedObject>& objects = scene.objects;
    // Stable names of the objects, so that a pair found wanting is not fitted again.
    std::vector<std::size_t> names(objects.size());
    for (std::size_t i = 0; i < names.size(); ++i) names[i] = i;
    std::size_t next_name = names.size();
    std::set<std::pair<std::size_t, std::size_t>> rejected;
    // Each object's pixel per point (kNoPixel where it falls outside the image), projected once:
    // a merged object's are its parts' in its points' order. Pixels are numbered within the
    // box that holds them all, so that only that box is cleared and visited.
    constexpr std::uint32_t kNoPixel = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::vector<std::uint32_t>> pixels(objects.size());
    // The box of each object's pixels, in the numbering's box: a pixel meets another object only
    // within kReach pixels of that object's box.
    using PixelBox = Eigen::AlignedBox<long, 2>;
    std::vector<PixelBox> boxes(objects.size());
    PixelBox all;
    long width = 0, height = 0;  // of the numbering's box
    {
        std::vector<std::vector<std::pair<long, long>>> uv(objects.size());
        for (std::size_t i = 0; i < objects.size(); ++i) {
            uv[i].reserve(objects[i].cluster.points.size());
            for (const Eigen::Vector3f& p : objects[i].cluster.points) {
                long u = 0, v = 0;
                if (!camera.pixel(p.x(), p.y(), p.z(), u, v)) {
                    uv[i].emplace_back(-1, -1);
                    continue;
                }
                boxes[i].extend(PixelBox::VectorType(u, v));
                uv[i].emplace_back(u, v);
            }
            all.extend(boxes[i]);
        }
        if (all.isEmpty()) return;
        width = all.sizes().x() + 1;
        height = all.sizes().y() + 1;
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (!boxes[i].isEmpty()) boxes[i].translate(-all.min());
            pixels[i].reserve(uv[i].size());
            for (const auto& [u, v] : uv[i])
                pixels[i].push_back(u < 0 ? kNoPixel
                                          : static_cast<std::uint32_t>((v - all.min().y()) * width +
                                                                       (u - all.min().x())));
        }
    }
    // Objects made in the last round. A pair of two older ones was judged before: rejected, or
    // short of contacts or of a fit then as now. Only pairs with a new one are looked for.
    std::vector<bool> fresh(objects.size(), true);
    // The owner of each pixel (the last point on a pixel owns it); only the pixels objects hold
    // are reset.
    std::vector<int> owner(static_cast<std::size_t>(width * height), -1);
    std::vector<const Eigen::Vector3f*> seen(owner.size());
    std::vector<std::size_t> held;
    for (;;) {
        for (const std::size_t pixel : held) owner[pixel] = -1;
        held.clear();
        for (std::size_t i = 0; i < objects.size(); ++i)
            for (std::size_t k = 0; k < pixels[i].size(); ++k) {
                const std::uint32_t pixel = pixels[i][k];
                if (pixel == kNoPixel) continue;
                if (owner[pixel] < 0) held.push_back(pixel);
                owner[pixel] = static_cast<int>(i);
                seen[pixel] = &objects[i].cluster.points[k];
            }
        // Parts meet where a pixel of one, up to 6 pixels on along its row or column from a
        // pixel of the other, is within kContactDistance of it. Each such pixel pair counts once:
        // from the new object's pixel, or from the older one's pixel before it.
        std::map<std::pair<int, int>, std::size_t> contacts;
        const bool older = std::find(fresh.begin(), fresh.end(), false) != fresh.end();
        // Each fresh object reads only its pixels near the boxes of the objects it may meet.
        std::vector<PixelBox> reach(objects.size());
        for (std::size_t i = 0; i < objects.size(); ++i)
            if (!boxes[i].isEmpty())
                reach[i] =
                    PixelBox(boxes[i].min().array() - kReach, boxes[i].max().array() + kReach);
        std::vector<PixelBox> near;
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (!fresh[i]) continue;
            const int a = static_cast<int>(i);
            near.clear();
            for (std::size_t j = 0; j < objects.size(); ++j)
                if (j != i && reach[j].intersects(boxes[i])) near.push_back(reach[j]);
            if (near.empty()) continue;
            for (std::size_t k = 0; k < pixels[i].size(); ++k) {
                const std::uint32_t pixel = pixels[i][k];
                // Once a pixel: where its last point, which owns it, lies.
                if (pixel == kNoPixel || seen[pixel] != &objects[i].cluster.points[k]) continue;
                const auto u = static_cast<long>(pixel) % width;
                const auto v = static_cast<long>(pixel) / width;
                if (std::none_of(near.begin(), near.end(), [&](const PixelBox& box) {
                        return box.contains(PixelBox::VectorType(u, v));
                    }))
                    continue;
                for (const long step : kSteps)
                    for (const auto& [du, dv] : {std::pair{step, 0L}, std::pair{0L, step}}) {
                        if (u + du < width && v + dv < height) {
                            const auto other = static_cast<std::size_t>((v + dv) * width + u + du);
                            const int b = owner[other];
                            if (b >= 0 && b != a &&
                                (*seen[pixel] - *seen[other]).norm() <= kContactDistance)
                                ++contacts[{std::min(a, b), std::max(a, b)}];
                        }
                        if (!older || u - du < 0 || v - dv < 0) continue;
                        const auto other = static_cast<std::size_t>((v - dv) * width + u - du);
                        const int b = owner[other];
                        if (b >= 0 && !fresh[static_cast<std::size_t>(b)] &&
                            (*seen[other] - *seen[pixel]).norm() <= kContactDistance)
                            ++contacts[{std::min(a, b), std::max(a, b)}];
                    }
            }
        }
        struct Pair {
            std::size_t a = 0, b = 0;
            bool fits = false;
            double gain = 0.0;
            RecognizedObject merged;
        };
        std::vector<Pair> pairs;
        const auto fitted = [&](std::size_t i) {
            return objects[i].classified() && objects[i].classification.fit.has_value();
        };
        for (const auto& [ab, count] : contacts) {
            const auto a = static_cast<std::size_t>(ab.first);
            const auto b = static_cast<std::size_t>(ab.second);
            if (count < kMinContacts || !fitted(a) || !fitted(b) ||
                rejected.count(std::minmax(names[a], names[b])))
                continue;
            Pair pair;
            pair.a = a;
            pair.b = b;
            pairs.push_back(std::move(pair));
        }
        if (pairs.empty()) return;
        parallel_for(pairs.size(), impl_->options.threads, [&](std::size_t k) {
            Pair& pair = pairs[k];
            const RecognizedObject& a = objects[pair.a];
            const RecognizedObject& b = objects[pair.b];
            RecognizedObject& merged = pair.merged;
            merged.cluster = merge_clusters(a.cluster, b.cluster, scene.plane);
            const QueryDescriptor d = describe(merged.cluster.points);
            if (!d.ok()) return;
            merged.classification = classify_descriptor(d.signatures);
            // One observation for the union's candidates and the parts' models.
            const PreparedObservation prepared(Observation{merged.cluster.points, &frame},
                                               impl_->options.verification.camera);
            verify_prepared(merged.classification, prepared);
            // Each part's own verified model, from where it stood: the model that explains the
            // larger part often explains the smaller one too (a mug's body and its handle)
            // when the union's nearest views hold no such model.
            const double na = static_cast<double>(a.cluster.points.size());
            const double nb = static_cast<double>(b.cluster.points.size());
            // What the union's fit must exceed for the pair to become one object.
            const double bar =
                (na * a.classification.fit->score() + nb * b.classification.fit->score()) /
                (na + nb);
            for (const RecognizedObject* part : {&a, &b})
                adopt_part_model(merged.classification, part->classification, prepared, bar);
            const std::optional<FitScore>& fit = merged.classification.fit;
            if (!fit || !merged.classification.verified ||
                fit->inliers < impl_->options.merge_min_inliers)
                return;
            pair.gain = fit->score() - bar;
            pair.fits = pair.gain >= 0.0;
        });
        std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
            return x.fits != y.fits ? x.fits : x.gain > y.gain;
        });
        std::vector<bool> used(objects.size(), false);
        std::vector<RecognizedObject> next;
        std::vector<std::size_t> next_names;
        std::vector<std::vector<std::uint32_t>> next_pixels;
        std::vector<PixelBox> next_boxes;
        for (Pair& pair : pairs) {
            if (!pair.fits) {
                rejected.insert(std::minmax(names[pair.a], names[pair.b]));
                continue;
            }
            if (used[pair.a] || used[pair.b]) continue;  // fitted again next round
            used[pair.a] = used[pair.b] = true;
            next.push_back(std::move(pair.merged));
            next_names.push_back(next_name++);
            next_pixels.push_back(pixels[pair.a]);  // merge_clusters: a's points, then b's
            next_pixels.back().insert(next_pixels.back().end(), pixels[pair.b].begin(),
                                      pixels[pair.b].end());
            next_boxes.push_back(boxes[pair.a].merged(boxes[pair.b]));
        }
        if (next.empty()) return;
        const std::size_t made = next.size();
        for (std::size_t i = 0; i < objects.size(); ++i)
            if (!used[i]) {
                next.push_back(std::move(objects[i]));
                next_names.push_back(names[i]);
                next_pixels.push_back(std::move(pixels[i]));
                next_boxes.push_back(boxes[i]);
            }
        // Largest first, as segmentation orders them.
        std::vector<std::size_t> order(next.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
            return next[x].cluster.points.size() > next[y].cluster.points.size();
        });
        objects.clear();
        names.clear();
        pixels.clear();
        boxes.clear();
        fresh.clear();
        for (const std::size_t i : order) {
            objects.push_back(std::move(next[i]));
            names.push_back(next_names[i]);
            pixels.push_back(std::move(next_pixels[i]));
            boxes.push_back(next_boxes[i]);
            fresh.push_back(i < made);
        }
    }
}

void Recognizer::verify_objects(SceneRecognition& scene, const PointCloud* frame,
                                std::span<const std::optional<PriorFit>> priors) const {
    parallel_for(scene.objects.size(), impl_->options.threads, [&](std::size_t i) {
        RecognizedObject& object = scene.objects[i];
        if (!object.classified() || object.cluster.points.size() < 3) return;
        const PriorFit* prior = i < priors.size() && priors[i] ? &*priors[i] : nullptr;
        verify(object.classification, Observation{object.cluster.points, frame}, prior);
    });
}

}  // namespace esf
