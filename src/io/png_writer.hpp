#pragma once
// Internal: encodes images as PNG in memory (libpng), for the depth PNGs of depth_image.cpp and
// the pictures of report.cpp.

#include <cstdint>
#include <span>
#include <vector>

namespace esf::detail {

/// PNG bytes of a width x height image of `channels` samples a pixel (1 = grey, 3 = RGB), each of
/// `bit_depth` bits (8, or 16 stored big-endian as PNG stores them), rows top to bottom without
/// padding. Throws std::runtime_error with libpng's message ("png: ...").
std::vector<std::uint8_t> encode_png(std::span<const std::uint8_t> pixels, std::uint32_t width,
                                     std::uint32_t height, int channels, int bit_depth);

}  // namespace esf::detail
