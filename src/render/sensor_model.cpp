#include "esf/render/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/splitmix64.hpp"

namespace esf {
namespace {

using detail::kGoldenGamma;
using detail::mix64;

constexpr double kDegree = std::numbers::pi / 180.0;

}  // namespace

double kinect_axial_sigma(double z, double theta) {
    double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
    if (theta > 60.0 * kDegree) {
        const double half_pi = std::numbers::pi / 2.0;
        const double t = std::min(theta, half_pi - 1e-6);
        sigma += 0.0001 / std::sqrt(z) * t * t / ((half_pi - t) * (half_pi - t));
    }
    return sigma;
}

double quantise_kinect_depth(double z, double fx, double baseline) {
    const double disparity = fx * baseline / z;
    if (std::isnan(disparity)) return disparity;
    if (disparity >= 1e15) return z;  // too close for the step to matter (and for int64)
    // Round half up; disparities are positive (cast instead of std::round: no libm call).
    const auto steps = static_cast<std::int64_t>(disparity / kKinectDisparityStep + 0.5);
    if (steps <= 0) return std::numeric_limits<double>::infinity();
    return fx * baseline / (static_cast<double>(steps) * kKinectDisparityStep);
}

double grazing_drop_probability(double theta) {
    const double x =
        (theta / kDegree - kGrazingDropStartDeg) / (kGrazingDropEndDeg - kGrazingDropStartDeg);
    if (x <= 0.0) return 0.0;
    if (x >= 1.0) return 1.0;
    return x * x * (3.0 - 2.0 * x);
}

PixelRandom::PixelRandom(std::uint64_t seed, std::uint64_t view, std::uint64_t pixel)
    : state_(mix64(mix64(mix64(seed + kGoldenGamma) ^ (view + kGoldenGamma)) ^
                   (pixel + kGoldenGamma))) {}

double PixelRandom::uniform() { return detail::splitmix64_uniform(state_); }

double PixelRandom::normal() {
    // Inverse normal CDF of one uniform, Acklam's rational approximation (relative error
    // < 1.2e-9): the central 95 % needs no log, sqrt or trigonometry.
    constexpr double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
    constexpr double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
    constexpr double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
    constexpr double d[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
    constexpr double kLow = 0.02425;
    double p = uniform();
    while (p == 0.0) p = uniform();
    if (p > kLow && p < 1.0 - kLow) {
        const double q = p - 0.5;
        const double r = q * q;
        return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
               (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    }
    const double tail = std::sqrt(-2.0 * std::log(p < 0.5 ? p : 1.0 - p));
    const double x =
        (((((c[0] * tail + c[1]) * tail + c[2]) * tail + c[3]) * tail + c[4]) * tail + c[5]) /
        ((((d[0] * tail + d[1]) * tail + d[2]) * tail + d[3]) * tail + 1.0);
    return p < 0.5 ? x : -x;
}

double kinect_measure(double z, double cos_incidence, double fx, PixelRandom& random) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    double sigma = 0.0;
    if (cos_incidence >= 0.5) {  // theta <= 60 degrees: no drop, no angle term
        sigma = kinect_axial_sigma(z, 0.0);
    } else {
        const double theta = std::acos(std::clamp(cos_incidence, 0.0, 1.0));
        const double drop = grazing_drop_probability(theta);
        if (drop > 0.0 && random.uniform() < drop) return nan;
        sigma = kinect_axial_sigma(z, theta);
    }
    const double noisy = z + sigma * random.normal();
    if (!(noisy > 0.0)) return nan;
    const double measured = quantise_kinect_depth(noisy, fx);
    return std::isfinite(measured) ? measured : nan;
}

}  // namespace esf
