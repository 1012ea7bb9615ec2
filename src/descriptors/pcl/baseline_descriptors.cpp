// The PCL baselines of the evaluation, behind the GlobalDescriptor interface: the module
// libesf_baselines.so, which make_descriptor() opens at run time (baseline_module.cpp), so that
// nothing else links PCL.
//
// pcl-esf runs pcl::ESFEstimation on the finite input points as they are. The others share the
// preprocessing of PCL's global recognition pipeline (pcl::rec_3d_framework, PreProcessorAnd-
// NormalEstimator with "compute mesh resolution" on):
//   1. r = median over the points of (sum of the distances to the 8 nearest neighbours) / 9,
//      the framework's mesh resolution (queried at up to 4,096 evenly spaced points); at least
//      1/4096 of the bounding-box diagonal, so that the voxel grid stays bounded.
//   2. Voxel grid (pcl::VoxelGrid, centroid per cell), leaf = leaf_factor * r (3 r).
//   3. Points with fewer than 5 neighbours within the normal radius removed (isolated flying
//      pixels would get no or random normals).
//   4. Normals by pcl::NormalEstimation, radius = normal_radius_factor leaves (3 leaves = 9 r;
//      PCL's CVFH defaults pair a 5 mm leaf with a 15 mm radius), flipped towards the sensor at
//      the origin; points whose normal is undefined are dropped. (gasd skips this step.)
//   5. At least kMinPreparedPoints points must remain.
// Then, with the sensor at the origin:
//   vfh       pcl::VFHEstimation with PCL's defaults: bins normalised, no size component (the
//             45 distance bins stay 0), 45 x 3 angle bins + 128 viewpoint bins. PCL
//             normalises the direction to the sensor as the 4-vector (sensor - centroid) with
//             w = -1, so a normal facing the sensor reads cosine 1/sqrt(2) (viewpoint bin 109).
//   cvfh      pcl::CVFHEstimation, parameters of rec_3d_framework: EPS angle 0.13 rad (7.4 deg),
//             curvature threshold 0.035, cluster tolerance and normal radius = the normal radius
//             of step 4, at least 50 points per smooth region, bins normalised. One signature
//             per region; one VFH-like signature of the whole cloud when no region is found.
//   our-cvfh  pcl::OURCVFHEstimation, the same parameters plus PCL's defaults for the reference
//             frames (axis ratio 0.8, minimum axis value 0.925, refine factor 1). One signature
//             per region and disambiguated reference frame (1, 2 or 4 per region).
//   gasd      pcl::GASDEstimation, shape only: PCA frame (view direction +z), 8^3 grid,
//             trilinear interpolation, 512 bins.
//   shot      pcl::SHOTEstimation (352 bins, its own SHOT local reference frame) at one
//             keypoint, the centroid of the prepared cloud, with a radius of 1.05 times the
//             largest distance of a point from it, so that the whole object is its support.
// Every signature is then L1-normalised (each method's own scaling differs: VFH sums to about
// 400, SHOT has unit L2 norm); a multi-signature method drops non-finite signatures and fails
// only when none is left.

#include "descriptors/pcl/baseline_descriptors.hpp"

#include <dlfcn.h>
#include <pcl/common/common.h>
#include <pcl/features/cvfh.h>
#include <pcl/features/esf.h>
#include <pcl/features/gasd.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/our_cvfh.h>
#include <pcl/features/shot.h>
#include <pcl/features/vfh.h>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/child_process.hpp"
#include "descriptors/pcl/baseline_child.hpp"
#include "esf/descriptors/esf/esf_descriptor.hpp"

namespace esf::detail {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Normals = pcl::PointCloud<pcl::Normal>;
using Tree = pcl::search::KdTree<pcl::PointXYZ>;

constexpr std::size_t kResolutionQueries = 4096;
constexpr float kMinResolutionOfDiagonal = 1.0f / 4096.0f;
constexpr int kOutlierMinNeighbours = 5;
constexpr std::size_t kMinPreparedPoints = 10;
constexpr float kCvfhEpsAngle = 0.13f;
constexpr float kCvfhCurvature = 0.035f;
constexpr std::size_t kCvfhMinPoints = 50;
constexpr float kShotRadiusMargin = 1.05f;

Cloud::Ptr to_pcl(const Points& points) {
    Cloud::Ptr cloud(new Cloud);
    cloud->reserve(points.size());
    for (const auto& p : points) cloud->emplace_back(p.x(), p.y(), p.z());
    cloud->width = static_cast<std::uint32_t>(cloud->size());
    cloud->height = 1;
    cloud->is_dense = true;
    return cloud;
}

/// rec_3d_framework's mesh resolution (see the top of the file).
float mesh_resolution(const Cloud::Ptr& cloud) {
    Tree tree(false);
    tree.setInputCloud(cloud);
    const std::size_t n = cloud->size();
    const int k = static_cast<int>(std::min<std::size_t>(9, n));
    const std::size_t queries = std::min(n, kResolutionQueries);
    std::vector<float> spacing;
    spacing.reserve(queries);
    pcl::Indices indices;
    std::vector<float> squared;
    for (std::size_t q = 0; q < queries; ++q) {
        const std::size_t i = q * n / queries;
        tree.nearestKSearch((*cloud)[i], k, indices, squared);
        float sum = 0.0f;
        for (std::size_t j = 1; j < squared.size(); ++j) sum += std::sqrt(squared[j]);
        spacing.push_back(sum / 9.0f);
    }
    const auto middle = spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2);
    std::nth_element(spacing.begin(), middle, spacing.end());
    Eigen::Vector4f min_pt, max_pt;
    pcl::getMinMax3D(*cloud, min_pt, max_pt);
    const float diagonal = (max_pt - min_pt).head<3>().norm();
    return std::max(*middle, diagonal * kMinResolutionOfDiagonal);
}

/// A cloud ready for PCL's global descriptors: downsampled, outliers removed, with normals.
struct Prepared {
    Cloud::Ptr cloud;
    Normals::Ptr normals;  // empty unless asked for
    Tree::Ptr tree;        // built on `cloud`
    float normal_radius = 0.0f;
};

Prepared prepare(const Points& points, const DescriptorOptions& options, bool with_normals,
                 const std::string& name) {
    Prepared out;
    const Cloud::Ptr input = to_pcl(points);
    const float resolution = mesh_resolution(input);
    const float leaf = options.leaf_factor * resolution;
    out.normal_radius = options.normal_radius_factor * (leaf > 0.0f ? leaf : resolution);

    Cloud::Ptr cloud = input;
    if (leaf > 0.0f) {
        Cloud::Ptr filtered(new Cloud);
        pcl::VoxelGrid<pcl::PointXYZ> grid;
        grid.setInputCloud(cloud);
        grid.setLeafSize(leaf, leaf, leaf);
        grid.filter(*filtered);
        cloud = filtered;
    }
    if (options.remove_outliers) {
        Cloud::Ptr filtered(new Cloud);
        pcl::RadiusOutlierRemoval<pcl::PointXYZ> outliers;
        outliers.setInputCloud(cloud);
        outliers.setRadiusSearch(out.normal_radius);
        outliers.setMinNeighborsInRadius(kOutlierMinNeighbours);
        outliers.filter(*filtered);
        cloud = filtered;
    }
    const std::size_t kept = cloud->size();

    out.normals.reset(new Normals);
    if (with_normals && kept >= kMinPreparedPoints) {
        Tree::Ptr tree(new Tree(false));
        tree->setInputCloud(cloud);
        pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
        estimation.setInputCloud(cloud);
        estimation.setSearchMethod(tree);
        estimation.setRadiusSearch(out.normal_radius);
        estimation.setViewPoint(0.0f, 0.0f, 0.0f);
        Normals normals;
        estimation.compute(normals);
        Cloud::Ptr with(new Cloud);
        for (std::size_t i = 0; i < cloud->size(); ++i) {
            const pcl::Normal& normal = normals[i];
            if (!std::isfinite(normal.normal_x) || !std::isfinite(normal.normal_y) ||
                !std::isfinite(normal.normal_z) || !std::isfinite(normal.curvature))
                continue;
            with->push_back((*cloud)[i]);
            out.normals->push_back(normal);
        }
        cloud = with;
    }
    if (cloud->size() < kMinPreparedPoints || (with_normals && out.normals->empty()))
        throw std::invalid_argument(
            name + ": too few points left by the preprocessing: " + std::to_string(points.size()) +
            " in, " + std::to_string(kept) + " after the voxel grid (leaf " + std::to_string(leaf) +
            ") and outlier removal" +
            (with_normals ? ", " + std::to_string(out.normals->size()) + " with a normal" : "") +
            "; need " + std::to_string(kMinPreparedPoints));
    cloud->width = static_cast<std::uint32_t>(cloud->size());
    cloud->height = 1;
    cloud->is_dense = true;
    out.normals->width = static_cast<std::uint32_t>(out.normals->size());
    out.normals->height = 1;
    out.normals->is_dense = true;
    out.cloud = cloud;
    out.tree.reset(new Tree(false));
    out.tree->setInputCloud(cloud);
    return out;
}

template <typename PclSignature>
Signature to_signature(const PclSignature& s, std::size_t size) {
    return Signature(std::begin(s.histogram), std::begin(s.histogram) + size);
}

/// Normalises single signatures; throws when one cannot be.
std::vector<Signature> finish_single(Signature signature, const std::string& name) {
    if (!normalise_signature(signature))
        throw std::invalid_argument(name +
                                    ": PCL gave a signature that is not finite or sums to 0 "
                                    "(cloud too small or degenerate for this descriptor?)");
    return {std::move(signature)};
}

/// Normalises each signature, drops those that cannot be; throws when none is left.
std::vector<Signature> finish_multi(std::vector<Signature> signatures, const std::string& name) {
    std::vector<Signature> out;
    for (auto& s : signatures)
        if (normalise_signature(s)) out.push_back(std::move(s));
    if (out.empty())
        throw std::invalid_argument(name + ": PCL gave no finite signature (" +
                                    std::to_string(signatures.size()) + " computed)");
    return out;
}

class PclBaseline : public GlobalDescriptor {
  public:
    PclBaseline(DescriptorInfo info, const DescriptorOptions& options)
        : info_(std::move(info)), options_(options) {}
    const DescriptorInfo& info() const override { return info_; }

  protected:
    DescriptorInfo info_;
    DescriptorOptions options_;
};

/// pcl::ESFEstimation keeps its state in the process-global rand(): one lock for all objects.
std::mutex& pcl_rand_mutex() {
    static std::mutex mutex;
    return mutex;
}

class PclEsf final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        const Points points = describable_points(input, info_.name);
        // PCL redraws rejected triples without a bound: on a cloud with (almost) no non-degenerate
        // triangle it never returns. Probe with the same acceptance test (our PCL-exact sampler)
        // and a bounded budget first; real clouds reject < 1 % of triples.
        EsfOptions probe;
        probe.samples = 1000;
        probe.sampler = EsfSampler::kPcl;
        try {
            compute_esf(points, probe);
        } catch (const std::invalid_argument& e) {
            throw std::invalid_argument(info_.name + ": " + e.what());
        }
        const Cloud::Ptr cloud = to_pcl(points);
        pcl::ESFEstimation<pcl::PointXYZ, pcl::ESFSignature640> estimation;
        estimation.setInputCloud(cloud);
        pcl::PointCloud<pcl::ESFSignature640> out;
        {
            const std::lock_guard<std::mutex> lock(pcl_rand_mutex());
            estimation.compute(out);
        }
        if (out.size() != 1) throw std::invalid_argument(info_.name + ": PCL gave no signature");
        return finish_single(to_signature(out[0], kEsfSize), info_.name);
    }
};

class Vfh final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        const Prepared p =
            prepare(describable_points(input, info_.name), options_, true, info_.name);
        pcl::VFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> vfh;
        vfh.setInputCloud(p.cloud);
        vfh.setInputNormals(p.normals);
        vfh.setSearchMethod(p.tree);
        vfh.setViewPoint(0.0f, 0.0f, 0.0f);
        pcl::PointCloud<pcl::VFHSignature308> out;
        vfh.compute(out);
        if (out.size() != 1) throw std::invalid_argument(info_.name + ": PCL gave no signature");
        return finish_single(to_signature(out[0], 308), info_.name);
    }
};

template <typename Estimation>
void set_cvfh_parameters(Estimation& cvfh, const Prepared& p) {
    cvfh.setInputCloud(p.cloud);
    cvfh.setInputNormals(p.normals);
    cvfh.setSearchMethod(p.tree);
    cvfh.setViewPoint(0.0f, 0.0f, 0.0f);
    cvfh.setEPSAngleThreshold(kCvfhEpsAngle);
    cvfh.setCurvatureThreshold(kCvfhCurvature);
    cvfh.setClusterTolerance(p.normal_radius);
    cvfh.setRadiusNormals(p.normal_radius);
    cvfh.setMinPoints(kCvfhMinPoints);
    cvfh.setNormalizeBins(true);
}

std::vector<Signature> vfh_signatures(const pcl::PointCloud<pcl::VFHSignature308>& out) {
    std::vector<Signature> signatures;
    for (const auto& s : out) signatures.push_back(to_signature(s, 308));
    return signatures;
}

class Cvfh final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        const Prepared p =
            prepare(describable_points(input, info_.name), options_, true, info_.name);
        pcl::CVFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> cvfh;
        set_cvfh_parameters(cvfh, p);
        pcl::PointCloud<pcl::VFHSignature308> out;
        cvfh.compute(out);
        return finish_multi(vfh_signatures(out), info_.name);
    }
};

/// The helper executable beside this module (baseline_child.hpp): the module's own folder,
/// found through the dynamic linker.
std::string child_path() {
    Dl_info info{};
    if (::dladdr(reinterpret_cast<const void*>(&child_path), &info) == 0 || !info.dli_fname)
        throw std::runtime_error("our-cvfh: cannot tell where the baselines module lies");
    const std::string module = info.dli_fname;
    const std::size_t slash = module.rfind('/');
    return (slash == std::string::npos ? std::string(".") : module.substr(0, slash)) +
           "/esf_baseline_child";
}

/// Runs our-cvfh on `points` in the helper process (posix_spawn, never fork()) and returns its
/// signatures; a crash there is this cloud's failure, not the caller's.
std::vector<Signature> describe_in_child(const Points& points, const DescriptorOptions& options,
                                         const std::string& name) {
    const std::string helper = child_path();
    if (::access(helper.c_str(), X_OK) != 0)
        throw std::runtime_error(name + ": its helper " + helper +
                                 " is missing (install the baselines component)");
    ChildResult result;
    try {
        result = run_child(helper, {}, encode_child_request(points, options), ChildLimits{});
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(name + ": " + e.what());
    }
    const std::string& bytes = result.reply;
    std::uint64_t header[3];
    const bool exited = result.end == ChildResult::End::kExited && result.code == 0;
    if (!exited || bytes.size() < sizeof header)
        throw std::invalid_argument(name + ": PCL's OURCVFHEstimation failed on this cloud (" +
                                    describe_end(result) +
                                    "; a smooth region without a reference frame)");
    std::memcpy(header, bytes.data(), sizeof header);
    const char* payload = bytes.data() + sizeof header;
    const std::size_t payload_size = bytes.size() - sizeof header;
    if (header[0] != 0) {
        if (payload_size != header[1]) throw std::runtime_error(name + ": truncated result");
        throw std::invalid_argument(std::string(payload, payload_size));
    }
    if (header[2] > 100000 || payload_size != header[1] * header[2] * sizeof(float))
        throw std::runtime_error(name + ": truncated result");
    std::vector<Signature> signatures(header[1], Signature(header[2]));
    for (std::size_t i = 0; i < signatures.size(); ++i)
        std::memcpy(signatures[i].data(), payload + i * header[2] * sizeof(float),
                    header[2] * sizeof(float));
    return signatures;
}

class OurCvfh final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        // Errors that need no PCL come from here; the rest from the helper.
        return describe_in_child(describable_points(input, info_.name), options_, info_.name);
    }
};

class Gasd final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        const Prepared p =
            prepare(describable_points(input, info_.name), options_, false, info_.name);
        pcl::GASDEstimation<pcl::PointXYZ, pcl::GASDSignature512> gasd;
        gasd.setInputCloud(p.cloud);
        gasd.setSearchMethod(p.tree);
        pcl::PointCloud<pcl::GASDSignature512> out;
        gasd.compute(out);
        if (out.size() != 1) throw std::invalid_argument(info_.name + ": PCL gave no signature");
        return finish_single(to_signature(out[0], 512), info_.name);
    }
};

class Shot final : public PclBaseline {
  public:
    using PclBaseline::PclBaseline;

    std::vector<Signature> compute(std::span<const Eigen::Vector3f> input) const override {
        const Prepared p =
            prepare(describable_points(input, info_.name), options_, true, info_.name);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (const auto& q : *p.cloud) sum += q.getVector3fMap().cast<double>();
        const Eigen::Vector3f centroid = (sum / static_cast<double>(p.cloud->size())).cast<float>();
        float radius = 0.0f;
        for (const auto& q : *p.cloud)
            radius = std::max(radius, (q.getVector3fMap() - centroid).norm());
        radius *= kShotRadiusMargin;

        Cloud::Ptr keypoint(new Cloud);
        keypoint->emplace_back(centroid.x(), centroid.y(), centroid.z());
        pcl::SHOTEstimation<pcl::PointXYZ, pcl::Normal, pcl::SHOT352> shot;
        shot.setInputCloud(keypoint);
        shot.setSearchSurface(p.cloud);
        shot.setInputNormals(p.normals);
        shot.setSearchMethod(p.tree);
        shot.setRadiusSearch(radius);
        shot.setLRFRadius(radius);
        pcl::PointCloud<pcl::SHOT352> out;
        shot.compute(out);
        if (out.size() != 1) throw std::invalid_argument(info_.name + ": PCL gave no signature");
        return finish_single(Signature(std::begin(out[0].descriptor), std::end(out[0].descriptor)),
                             info_.name);
    }
};

std::unique_ptr<GlobalDescriptor> make_baseline(const DescriptorInfo& info,
                                                const DescriptorOptions& options) {
    const std::string& name = info.name;
    if (name == "pcl-esf") return std::make_unique<PclEsf>(info, options);
    if (name == "vfh") return std::make_unique<Vfh>(info, options);
    if (name == "cvfh") return std::make_unique<Cvfh>(info, options);
    if (name == "our-cvfh") return std::make_unique<OurCvfh>(info, options);
    if (name == "gasd") return std::make_unique<Gasd>(info, options);
    if (name == "shot") return std::make_unique<Shot>(info, options);
    return nullptr;
}

constexpr BaselineModule kModule = {kBaselineModuleAbi, &make_baseline};

template <typename T>
void append(std::string& out, const T& value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

template <typename T>
T take(const std::string& in, std::size_t& at) {
    if (in.size() - at < sizeof(T))
        throw std::invalid_argument("our-cvfh helper: truncated request");
    T value;
    std::memcpy(&value, in.data() + at, sizeof value);
    at += sizeof value;
    return value;
}

}  // namespace

std::vector<Signature> our_cvfh_signatures(const Points& points, const DescriptorOptions& options,
                                           const std::string& name) {
    const Prepared p = prepare(describable_points(points, name), options, true, name);
    pcl::OURCVFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> cvfh;
    set_cvfh_parameters(cvfh, p);
    cvfh.setAxisRatio(0.8f);
    cvfh.setMinAxisValue(0.925f);
    cvfh.setRefineClusters(1.0f);
    pcl::PointCloud<pcl::VFHSignature308> out;
    cvfh.compute(out);
    return finish_multi(vfh_signatures(out), name);
}

std::string encode_child_request(const Points& points, const DescriptorOptions& options) {
    std::string out = "ESFC";
    out.reserve(4 + 8 + points.size() * 12 + 9);
    append(out, static_cast<std::uint64_t>(points.size()));
    for (const Eigen::Vector3f& p : points) {
        append(out, p.x());
        append(out, p.y());
        append(out, p.z());
    }
    append(out, options.leaf_factor);
    append(out, options.normal_radius_factor);
    append(out, static_cast<std::uint8_t>(options.remove_outliers ? 1 : 0));
    return out;
}

void decode_child_request(const std::string& bytes, Points& points, DescriptorOptions& options) {
    if (bytes.compare(0, 4, "ESFC") != 0)
        throw std::invalid_argument("our-cvfh helper: not a request");
    std::size_t at = 4;
    const auto count = take<std::uint64_t>(bytes, at);
    if (count > (bytes.size() - at) / 12)
        throw std::invalid_argument("our-cvfh helper: truncated request");
    points.resize(count);
    for (Eigen::Vector3f& p : points) {
        p.x() = take<float>(bytes, at);
        p.y() = take<float>(bytes, at);
        p.z() = take<float>(bytes, at);
    }
    options.leaf_factor = take<float>(bytes, at);
    options.normal_radius_factor = take<float>(bytes, at);
    options.remove_outliers = take<std::uint8_t>(bytes, at) != 0;
}

std::string encode_child_reply(const std::vector<Signature>& signatures) {
    std::string out;
    append(out, std::uint64_t{0});
    append(out, static_cast<std::uint64_t>(signatures.size()));
    append(out, static_cast<std::uint64_t>(signatures.empty() ? 0 : signatures[0].size()));
    for (const Signature& s : signatures)
        out.append(reinterpret_cast<const char*>(s.data()), s.size() * sizeof(float));
    return out;
}

std::string encode_child_error(const std::string& message) {
    std::string out;
    append(out, std::uint64_t{1});
    append(out, static_cast<std::uint64_t>(message.size()));
    append(out, std::uint64_t{0});
    return out + message;
}

}  // namespace esf::detail

extern "C" ESF_BASELINES_EXPORT const esf::detail::BaselineModule* esf_baseline_module() {
    return &esf::detail::kModule;
}
