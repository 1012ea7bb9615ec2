// libFuzzer target: a depth PNG and intrinsics. The first 32 bytes are fx, fy, cx, cy (doubles,
// any bit pattern); the rest is the PNG, read by esf::read_depth_png and back-projected by
// esf::depth_to_cloud. Bad files must throw esf::IoError, bad intrinsics std::invalid_argument.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include "esf/core/error.hpp"
#include "esf/io/depth_image.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHead = 4 * sizeof(double);
    if (size < kHead) return 0;
    double k[4];
    std::memcpy(k, data, kHead);
    std::istringstream in(std::string(esf::fuzz::bytes_of(data + kHead, size - kHead)));
    esf::DepthImage image;
    try {
        image = esf::read_depth_png(in, "depth.png");
    } catch (const esf::IoError&) {
        return 0;
    }
    if (std::uint64_t{image.width} * image.height != image.depth.size()) __builtin_trap();
    esf::CameraIntrinsics intrinsics;
    intrinsics.fx = k[0];
    intrinsics.fy = k[1];
    intrinsics.cx = k[2];
    intrinsics.cy = k[3];
    try {
        const esf::PointCloud cloud = esf::depth_to_cloud(image, intrinsics);
        if (cloud.points.size() != image.depth.size()) __builtin_trap();
    } catch (const std::invalid_argument&) {
    }
    return 0;
}
