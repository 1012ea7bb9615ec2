#include "esf/recognizer.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "esf/error.hpp"
#include "esf/knn_index.hpp"
#include "esf/parallel.hpp"
#include "neighbour_merge.hpp"
#include "splitmix64.hpp"

namespace esf {

namespace {

// ---- settings -------------------------------------------------------------------------------

const SettingValue* find_setting(const Settings& settings, const std::string& key) {
    const auto it = settings.find(key);
    return it == settings.end() ? nullptr : &it->second;
}

std::int64_t integer_setting(const Settings& settings, const std::string& key,
                             std::int64_t fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* i = std::get_if<std::int64_t>(value)) return *i;
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) +
                                " is not an integer");
}

int int_setting(const Settings& settings, const std::string& key, int fallback) {
    const std::int64_t v = integer_setting(settings, key, fallback);
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
        throw std::invalid_argument("setting " + key + " = " + std::to_string(v) +
                                    " is out of range");
    return static_cast<int>(v);
}

double real_setting(const Settings& settings, const std::string& key, double fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* d = std::get_if<double>(value)) return *d;
    if (const auto* i = std::get_if<std::int64_t>(value)) return static_cast<double>(*i);
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) + " is not a number");
}

std::string text_setting(const Settings& settings, const std::string& key,
                         const std::string& fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* s = std::get_if<std::string>(value)) return *s;
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) + " is not text");
}

/// The run's seed: an integer, or the decimal text training stores for seeds above 2^63 - 1.
std::uint64_t seed_setting(const Settings& settings) {
    const SettingValue* value = find_setting(settings, "seed");
    if (!value) return 0;
    if (const auto* i = std::get_if<std::int64_t>(value)) {
        if (*i < 0) throw std::invalid_argument("setting seed = " + std::to_string(*i) + " < 0");
        return static_cast<std::uint64_t>(*i);
    }
    if (const auto* s = std::get_if<std::string>(value)) {
        std::size_t used = 0;
        std::uint64_t seed = 0;
        try {
            seed = std::stoull(*s, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == s->size() && !s->empty() && s->front() != '-') return seed;
    }
    throw std::invalid_argument("setting seed = " + to_string(*value) + " is not a seed");
}

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

/// Our ESF with the database's options (estimators reused across calls, never shared); with
/// several samplings, the mean of the descriptors of as many seeds.
class EsfDescriber final : public Describer {
  public:
    EsfDescriber(const EsfOptions& options, int samplings) {
        for (int s = 0; s < samplings; ++s) {
            EsfOptions o = options;
            o.seed = sampling_seed(options.seed, s);
            pools_.push_back(std::make_unique<EsfEstimatorPool>(o));
        }
    }

    std::vector<float> describe(std::span<const Eigen::Vector3f> points) const override {
        std::array<double, kEsfSize> sum{};
        for (const auto& pool : pools_) {
            EsfResult result;
            try {
                result = pool->compute(points);
            } catch (const std::invalid_argument& e) {
                // "ESF needs ..." -> "esf: needs ...", the form of the other descriptors' errors.
                std::string what = e.what();
                if (what.rfind("ESF ", 0) == 0) what.erase(0, 4);
                throw std::invalid_argument("esf: " + what);
            }
            if (pools_.size() == 1) return {result.descriptor.begin(), result.descriptor.end()};
            for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += result.descriptor[i];
        }
        std::vector<float> out(sum.size());
        const double scale = 1.0 / static_cast<double>(pools_.size());
        for (std::size_t i = 0; i < sum.size(); ++i) out[i] = static_cast<float>(sum[i] * scale);
        return out;
    }

  private:
    std::vector<std::unique_ptr<EsfEstimatorPool>> pools_;
};

/// Any descriptor of the registry (descriptor.hpp).
class RegistryDescriber final : public Describer {
  public:
    RegistryDescriber(const std::string& name, const DescriptorOptions& options)
        : descriptor_(make_descriptor(name, options)) {}

    std::vector<float> describe(std::span<const Eigen::Vector3f> points) const override {
        const std::vector<Signature> signatures = descriptor_->compute(points);
        const auto dim = static_cast<std::size_t>(descriptor_->info().dimension);
        std::vector<float> out;
        out.reserve(signatures.size() * dim);
        for (const Signature& s : signatures) {
            if (s.size() != dim)
                throw std::invalid_argument(descriptor_->info().name + ": a signature of " +
                                            std::to_string(s.size()) + " floats, expected " +
                                            std::to_string(dim));
            out.insert(out.end(), s.begin(), s.end());
        }
        if (out.empty()) throw std::invalid_argument(descriptor_->info().name + ": no signature");
        return out;
    }

  private:
    std::unique_ptr<GlobalDescriptor> descriptor_;
};

std::unique_ptr<Describer> make_describer(const QuerySetup& setup, int samplings) {
    if (setup.kind.name == "esf") return std::make_unique<EsfDescriber>(setup.esf, samplings);
    return std::make_unique<RegistryDescriber>(setup.kind.name, setup.options);
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

int descriptor_version(const std::string& name) {
    const std::vector<std::string> names = descriptor_names();
    if (std::find(names.begin(), names.end(), name) == names.end())
        throw std::invalid_argument("unknown descriptor '" + name + "' (this build knows " +
                                    joined(names) + ")");
    return stored_descriptor_version(name);
}

QuerySetup query_setup(const Settings& settings, const DescriptorKind& kind) {
    QuerySetup setup;
    setup.kind = kind;
    const int version = descriptor_version(kind.name);
    if (kind.version != version)
        throw std::invalid_argument("descriptor " + kind.name + " version " +
                                    std::to_string(kind.version) +
                                    ", but this build computes version " + std::to_string(version) +
                                    ": retrain the database");
    const int dimension = descriptor_info(kind.name).dimension;
    if (kind.dimension != dimension)
        throw std::invalid_argument(
            "descriptor " + kind.name + " has " + std::to_string(kind.dimension) +
            " floats, but this build computes " + std::to_string(dimension));
    // The settings describe the kind the database was trained with; a database may also hold
    // kinds added later, whose version and dimension are checked above.
    if (text_setting(settings, "descriptor", kind.name) == kind.name) {
        const std::int64_t stored_version =
            integer_setting(settings, "descriptor_version", version);
        if (stored_version != version)
            throw std::invalid_argument(
                "setting descriptor_version = " + std::to_string(stored_version) +
                ", but this build computes " + kind.name + " version " + std::to_string(version) +
                ": retrain the database");
        const std::int64_t stored_dimension =
            integer_setting(settings, "descriptor_dimension", dimension);
        if (stored_dimension != dimension)
            throw std::invalid_argument(
                "setting descriptor_dimension = " + std::to_string(stored_dimension) + ", but " +
                kind.name + " has " + std::to_string(dimension) + " floats");
    }
    const std::uint64_t seed = seed_setting(settings);
    if (kind.name == "esf") {
        EsfOptions& e = setup.esf;
        e.samples = int_setting(settings, "esf_samples", e.samples);
        e.grid_size = int_setting(settings, "esf_grid_size", e.grid_size);
        e.sampler = parse_esf_sampler(text_setting(settings, "esf_sampler", to_string(e.sampler)));
        e.max_attempts_per_sample =
            int_setting(settings, "esf_max_attempts_per_sample", e.max_attempts_per_sample);
        e.seed = seed;
        try {
            EsfEstimator check(e);
        } catch (const std::invalid_argument& error) {
            throw std::invalid_argument(std::string("esf settings: ") + error.what());
        }
    } else {
        DescriptorOptions& o = setup.options;
        o.seed = seed;
        o.samples = int_setting(settings, "descriptor_samples", o.samples);
        o.leaf_factor = static_cast<float>(
            real_setting(settings, "descriptor_leaf_factor", static_cast<double>(o.leaf_factor)));
        o.normal_radius_factor =
            static_cast<float>(real_setting(settings, "descriptor_normal_radius_factor",
                                            static_cast<double>(o.normal_radius_factor)));
        const std::int64_t remove =
            integer_setting(settings, "descriptor_remove_outliers", o.remove_outliers ? 1 : 0);
        if (remove != 0 && remove != 1)
            throw std::invalid_argument("setting descriptor_remove_outliers = " +
                                        std::to_string(remove) + " is not 0 or 1");
        o.remove_outliers = remove == 1;
        o.angles_weight = real_setting(settings, "descriptor_angles_weight", o.angles_weight);
        check_descriptor_options(kind.name, o);  // throws for options out of range
    }
    return setup;
}

// ---- recognizer -----------------------------------------------------------------------------

struct Recognizer::Impl {
    RecognizerOptions options;
    RecognizerInfo info;
    std::unique_ptr<Describer> describer;
    std::unique_ptr<Classifier> classifier;
    std::size_t dimension = 0;
};

Recognizer::Recognizer(const std::string& path, const RecognizerOptions& options)
    : impl_(std::make_unique<Impl>()) {
    if (options.k == 0) throw std::invalid_argument("recognizer: k must be >= 1");
    if (options.query_samplings < 1)
        throw std::invalid_argument("recognizer: query samplings must be >= 1, got " +
                                    std::to_string(options.query_samplings));
    resolve_threads(options.threads);
    impl_->options = options;
    auto fail = [&](const std::string& reason) {
        throw std::invalid_argument(file_message(path, 0, reason));
    };

    const Database db(path, OpenMode::kRead);
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
    impl_->describer = make_describer(impl_->info.setup, options.query_samplings);

    DescriptorMatrix matrix = db.load_descriptors(kind.name);
    if (matrix.rows() == 0)
        fail("empty database: no views with " + kind.name + " descriptors (" +
             std::to_string(matrix.models.size()) + " complete models)");
    const auto dim = static_cast<std::size_t>(kind.dimension);
    impl_->dimension = dim;

    KnnIndexOptions index_options;
    index_options.threads = options.threads;
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
    ClassifierOptions classifier_options;
    classifier_options.k = options.k;
    classifier_options.vote = options.vote;
    impl_->classifier =
        std::make_unique<Classifier>(std::move(index), std::move(labels), classifier_options);
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
    if (signatures.size() == dim) return classifier.classify(signatures);
    std::vector<KnnResult> results;
    for (std::size_t s = 0; s < signatures.size(); s += dim)
        results.push_back(classifier.index().search(signatures.subspan(s, dim), impl_->options.k));
    const std::vector<KnnNeighbour> neighbours =
        merge_neighbours(results, impl_->options.k, classifier.index());
    return classify_neighbours(neighbours, classifier.labels(), classifier.options().vote);
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
        for (std::size_t j = 0; j < batch_items.size(); ++j)
            out[batch_items[j]].classification = std::move(results[j]);
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
    return classify_descriptor(d.signatures);
}

std::vector<CloudClassification> Recognizer::classify_batch(std::span<const Points> clouds) const {
    return classify_batch(describe_batch(clouds));
}

SceneRecognition Recognizer::recognize(SegmentationResult segmentation) const {
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

SceneRecognition Recognizer::recognize_scene(const PointCloud& scene,
                                             const SegmentationOptions& options) const {
    return recognize(segment_scene(scene, options));
}

}  // namespace esf
