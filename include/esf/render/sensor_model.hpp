#pragma once
// A Kinect v1-like depth sensor model for synthetic views: axial noise growing with depth
// (Nguyen, Izadi & Lovell 2012, "Modeling Kinect Sensor Noise for Improved 3D Reconstruction
// and Tracking"), disparity quantisation (Khoshelham & Elberink 2012) and missing pixels
// at grazing angles. Randomness is a counter-based generator keyed by (seed, view, pixel), so a
// pixel's noise depends neither on the thread count nor on which other pixels are cast.
// The sensor's range limits (about 0.5 to 4 m) are not modelled, so that small models may be
// rendered close up; lateral noise and shadows at depth edges are not modelled either.

#include <array>
#include <cstdint>
#include <string>

#include "esf/core/enum_names.hpp"

namespace esf {

enum class SensorNoise { kNone, kKinect };

/// "none", "kinect" (to_string, parse_enum<SensorNoise>).
template <>
struct EnumNames<SensorNoise> {
    static constexpr const char* what = "sensor noise";
    static constexpr std::array<EnumName<SensorNoise>, 2> table{
        {{SensorNoise::kNone, "none"}, {SensorNoise::kKinect, "kinect"}}};
};

inline constexpr double kKinectBaseline = 0.075;           ///< metres, projector to IR camera
inline constexpr double kKinectDisparityStep = 1.0 / 8.0;  ///< pixels (sub-pixel quantisation)
inline constexpr double kGrazingDropStartDeg = 65.0;       ///< no pixel dropped below this angle
inline constexpr double kGrazingDropEndDeg = 85.0;         ///< every pixel dropped above it

/// Standard deviation (metres) of the axial noise at depth z (metres) and incidence angle theta
/// (radians, between the viewing ray and the surface normal): 0.0012 + 0.0019 (z - 0.4)^2, plus
/// 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2 when theta > 60 degrees (Nguyen et al. 2012).
double kinect_axial_sigma(double z, double theta);

/// Depth after Kinect disparity quantisation: disparity fx * baseline / z (pixels) rounded to
/// the nearest 1/8 pixel, converted back. Returns +infinity when the disparity rounds to zero.
double quantise_kinect_depth(double z, double fx, double baseline = kKinectBaseline);

/// Probability that a pixel seen at incidence angle theta (radians) returns no depth: 0 below
/// 65 degrees, 1 above 85, a smoothstep in between (0.5 at 75 degrees).
double grazing_drop_probability(double theta);

/// Uniform and normal draws for one pixel: splitmix64 seeded with a hash of (seed, view, pixel).
class PixelRandom {
  public:
    PixelRandom(std::uint64_t seed, std::uint64_t view, std::uint64_t pixel);
    double uniform();  ///< in [0, 1)
    double normal();   ///< standard normal (inverse CDF, Acklam's approximation)

  private:
    std::uint64_t state_;
};

/// One measurement of the Kinect model: the true depth z (metres) of a surface whose normal
/// makes an angle with |cos| = cos_incidence with the viewing ray, seen by a camera with focal
/// length fx (pixels): grazing-angle drop, axial noise, disparity quantisation. Returns the
/// measured depth, or NaN when the pixel is dropped (or the depth leaves the sensor's range).
double kinect_measure(double z, double cos_incidence, double fx, PixelRandom& random);

}  // namespace esf
