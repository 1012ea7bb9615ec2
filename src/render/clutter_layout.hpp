#pragma once
// Internal: the composer of cluttered table scenes behind esf::ClutterComposer. Its models and
// options, and the layout of a scene (clutter_layout.cpp): models picked evenly by category,
// posed standing or lying, and placed on the table apart, touching, stacked, leaning or in front
// of one another, by scene type. The camera, the surroundings and the frame are
// clutter_scene.cpp's.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/splitmix64.hpp"
#include "esf/render/clutter_scene.hpp"
#include "render/clutter_geometry.hpp"

namespace esf {

namespace detail {

/// The random numbers of one scene (its layout, then its camera and surroundings).
class ClutterRandom {
  public:
    explicit ClutterRandom(std::uint64_t seed) : mixer_(seed) {}
    double uniform() { return mixer_.uniform(); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    std::size_t below(std::size_t n) { return mixer_.below(n); }
    int between(int lo, int hi) {
        return lo + static_cast<int>(below(static_cast<std::size_t>(hi - lo + 1)));
    }
    bool chance(double p) { return uniform() < p; }

  private:
    SplitMix64 mixer_;
};

}  // namespace detail

struct ClutterComposer::Impl {
    std::vector<ClutterModel> models;
    ClutterOptions options;
    std::vector<detail::ModelShape> shapes;
    std::vector<std::string> categories;  // sorted, distinct

    /// The bodies of a scene of `type` on the table (z = 0), drawn from `random`; the camera's
    /// azimuth `camera_azimuth` (radians) says where objects hide others in occluded scenes.
    std::vector<detail::Body> layout(detail::ClutterRandom& random, ClutterType type,
                                     double camera_azimuth) const;

  private:
    /// A model whose shape passes `accept` (any model when none does): a category first, evenly,
    /// then one of its models, so that categories with many models do not fill every scene.
    template <class Accept>
    std::size_t pick_model(detail::ClutterRandom& random, Accept accept) const;
    /// The model scaled by `size` and posed by `rotation` (about its bounding box centre),
    /// lowest point on z = 0, footprint centred at the origin.
    detail::Body make_body(std::size_t model, const Eigen::Matrix3d& rotation,
                           const std::string& placement, double size) const;
    /// Upright (or, with `lying`, on its side) at a random yaw, of a random size where
    /// options.size_spread > 0.
    detail::Body random_body(detail::ClutterRandom& random, std::size_t model,
                             double lying_share) const;
    /// The share of poses in which the model lies on its side.
    double lying_share(std::size_t model) const;
    /// Whether `body` keeps clear of `bodies` (the one it stands on and `except` aside) by `gap`.
    static bool free(const detail::Body& body, const std::vector<detail::Body>& bodies, double gap,
                     int except = -1);
    /// Somewhere in a disc around the origin, at least `gap` from every other body.
    bool place_apart(detail::ClutterRandom& random, detail::Body& body,
                     const std::vector<detail::Body>& bodies, double radius, double gap) const;
    /// Slid from `anchor`'s centre (offset sideways by `side`) along `angle` until it no longer
    /// overlaps the anchor, then `gap` further.
    static void slide_from(detail::Body& body, const detail::Body& anchor, double angle,
                           double side, double gap);
    /// Touching one of `bodies` (on the table), no closer than 1 mm to the others.
    bool place_touching(detail::ClutterRandom& random, detail::Body& body,
                        const std::vector<detail::Body>& bodies, double max_gap,
                        double tilt_deg = 0.0) const;
    /// On the top of `base`, its centre within the base's top.
    bool place_on(detail::ClutterRandom& random, detail::Body& body,
                  const std::vector<detail::Body>& bodies, std::size_t base) const;
    /// Between `target` and the camera (azimuth `towards`), hiding part of it.
    bool place_in_front(detail::ClutterRandom& random, detail::Body& body,
                        const std::vector<detail::Body>& bodies, std::size_t target,
                        double towards) const;
};

}  // namespace esf
