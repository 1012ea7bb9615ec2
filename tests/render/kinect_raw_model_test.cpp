// The raw 11-bit conversion (io/kinect_raw.hpp) and the sensor model's disparity quantisation
// (render/sensor_model.hpp) describe the same sensor.

#include <gtest/gtest.h>

#include "esf/io/kinect_raw.hpp"
#include "esf/render/sensor_model.hpp"

namespace {

static_assert(esf::kKinectRawBaseline == esf::kKinectBaseline);
static_assert(esf::kKinectRawStepsPerPixel * esf::kKinectDisparityStep == 1.0);

TEST(KinectRawModel, MetresToRawToMetresIsTheSensorModelsQuantisation) {
    for (double z = 0.3; z < 8.0; z += 0.00137) {
        const double quantised = esf::quantise_kinect_depth(z, 525.0);
        const double through_raw = esf::kinect_raw_to_metres(esf::kinect_metres_to_raw(z));
        EXPECT_EQ(through_raw, quantised) << z;  // bit for bit
    }
}

}  // namespace
