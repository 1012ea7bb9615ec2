#include "esf/io/depth_image.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "esf/core/error.hpp"

namespace {

namespace fs = std::filesystem;

class TempDir {
  public:
    TempDir() {
        path_ = fs::temp_directory_path() /
                ("esf_depth_image_test_" +
                 std::to_string(::testing::UnitTest::GetInstance()->current_test_info()->line()));
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() { fs::remove_all(path_); }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

  private:
    fs::path path_;
};

// libpng longjmps here on error; only trivial locals live in this frame.
bool write_rows(png_structp png, png_infop info, FILE* file, png_uint_32 width, png_uint_32 height,
                int bit_depth, int color_type, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_set_IHDR(png, info, width, height, bit_depth, color_type, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

// Writes a PNG with libpng directly (independently of write_depth_png): `samples` holds one
// value per channel per pixel, row-major.
bool write_png_raw(const std::string& path, png_uint_32 width, png_uint_32 height, int bit_depth,
                   int color_type, const std::vector<std::uint16_t>& samples) {
    const int channels = color_type == PNG_COLOR_TYPE_RGB ? 3 : 1;
    const std::size_t bytes_per_sample = bit_depth == 16 ? 2 : 1;
    const std::size_t row_bytes = width * channels * bytes_per_sample;
    std::vector<png_byte> bytes;
    for (const std::uint16_t value : samples) {
        if (bit_depth == 16) bytes.push_back(static_cast<png_byte>(value >> 8));
        bytes.push_back(static_cast<png_byte>(value & 0xFF));
    }
    if (bytes.size() != row_bytes * height) return false;
    FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) return false;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(height);
    for (std::size_t v = 0; v < height; ++v) rows[v] = bytes.data() + v * row_bytes;
    const bool ok = write_rows(png, info, file, width, height, bit_depth, color_type, rows.data());
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return ok;
}

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_all(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <typename F>
std::string io_error_message(F&& f) {
    try {
        f();
    } catch (const esf::IoError& e) {
        return e.what();
    }
    return "(no IoError)";
}

TEST(DepthToCloud, BackProjectsKnownPixels) {
    // 4 x 3 image, intrinsics fx = 2, fy = 4, cx = 1.5, cy = 1; depth in millimetres.
    esf::DepthImage image{4, 3, std::vector<std::uint16_t>(12, 0)};
    image.depth[0 * 4 + 0] = 1000;  // (u, v) = (0, 0): z = 1 m
    image.depth[1 * 4 + 3] = 2000;  // (3, 1): z = 2 m
    image.depth[2 * 4 + 1] = 500;   // (1, 2): z = 0.5 m
    const esf::CameraIntrinsics k{2.0, 4.0, 1.5, 1.0};
    const esf::PointCloud cloud = esf::depth_to_cloud(image, k);
    ASSERT_EQ(cloud.width, 4u);
    ASSERT_EQ(cloud.height, 3u);
    ASSERT_EQ(cloud.points.size(), 12u);
    EXPECT_TRUE(cloud.labels.empty());
    // x = (u - cx) z / fx, y = (v - cy) z / fy.
    EXPECT_FLOAT_EQ(cloud.points[0].x(), (0 - 1.5f) * 1.0f / 2.0f);  // -0.75
    EXPECT_FLOAT_EQ(cloud.points[0].y(), (0 - 1.0f) * 1.0f / 4.0f);  // -0.25
    EXPECT_FLOAT_EQ(cloud.points[0].z(), 1.0f);
    EXPECT_FLOAT_EQ(cloud.points[7].x(), 1.5f);  // (3 - 1.5) * 2 / 2
    EXPECT_FLOAT_EQ(cloud.points[7].y(), 0.0f);  // (1 - 1) * 2 / 4
    EXPECT_FLOAT_EQ(cloud.points[7].z(), 2.0f);
    EXPECT_FLOAT_EQ(cloud.points[9].x(), -0.125f);  // (1 - 1.5) * 0.5 / 2
    EXPECT_FLOAT_EQ(cloud.points[9].y(), 0.125f);   // (2 - 1) * 0.5 / 4
    EXPECT_FLOAT_EQ(cloud.points[9].z(), 0.5f);
    int missing = 0;
    for (const auto& p : cloud.points) missing += std::isnan(p.x()) && std::isnan(p.z()) ? 1 : 0;
    EXPECT_EQ(missing, 9);
}

TEST(DepthToCloud, KinectDefaultsAndScale) {
    esf::DepthImage image{640, 480, std::vector<std::uint16_t>(640 * 480, 0)};
    image.depth[240 * 640 + 320] = 5000;  // TUM-style units: 5000 per metre -> 1 m
    const esf::PointCloud cloud = esf::depth_to_cloud(image, {}, 1.0 / 5000.0);
    const Eigen::Vector3f p = cloud.points[240 * 640 + 320];
    EXPECT_FLOAT_EQ(p.z(), 1.0f);
    EXPECT_FLOAT_EQ(p.x(), 0.5f / 525.0f);  // (320 - 319.5) / 525
    EXPECT_FLOAT_EQ(p.y(), 0.5f / 525.0f);  // (240 - 239.5) / 525
}

TEST(DepthToCloud, RejectsBadArguments) {
    const esf::DepthImage image{2, 2, {1, 2, 3, 4}};
    EXPECT_THROW(esf::depth_to_cloud(esf::DepthImage{}), std::invalid_argument);
    EXPECT_THROW(esf::depth_to_cloud(esf::DepthImage{3, 2, {1, 2}}), std::invalid_argument);
    EXPECT_THROW(esf::depth_to_cloud(image, {0.0, 525.0, 1.0, 1.0}), std::invalid_argument);
    EXPECT_THROW(esf::depth_to_cloud(image, {525.0, -1.0, 1.0, 1.0}), std::invalid_argument);
    EXPECT_THROW(esf::depth_to_cloud(image, {525.0, 525.0, NAN, 1.0}), std::invalid_argument);
    EXPECT_THROW(esf::depth_to_cloud(image, {}, 0.0), std::invalid_argument);
    try {
        esf::depth_to_cloud(esf::DepthImage{3, 2, {1, 2}});
        FAIL();
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("3 x 2 but holds 2 values"), std::string::npos)
            << e.what();
    }
}

TEST(DepthPng, ReadsPngWrittenByLibpng) {
    TempDir dir;
    const std::string path = dir.file("depth.png");
    std::vector<std::uint16_t> values(5 * 3);
    for (std::size_t i = 0; i < values.size(); ++i)
        values[i] = static_cast<std::uint16_t>(i * 4099 % 65536);  // high and low bytes vary
    values[4] = 0;
    values[5] = 65535;
    ASSERT_TRUE(write_png_raw(path, 5, 3, 16, PNG_COLOR_TYPE_GRAY, values));
    const esf::DepthImage image = esf::read_depth_png(path);
    EXPECT_EQ(image.width, 5u);
    EXPECT_EQ(image.height, 3u);
    EXPECT_EQ(image.depth, values);
}

TEST(DepthPng, RoundTripThroughFileAndStream) {
    TempDir dir;
    esf::DepthImage image{7, 4, {}};
    for (std::uint32_t i = 0; i < 28; ++i)
        image.depth.push_back(static_cast<std::uint16_t>(i % 5 == 0 ? 0 : 300 + 257 * i));
    const std::string path = dir.file("round.png");
    esf::write_depth_png(path, image);
    const esf::DepthImage back = esf::read_depth_png(path);
    EXPECT_EQ(back.width, image.width);
    EXPECT_EQ(back.height, image.height);
    EXPECT_EQ(back.depth, image.depth);

    std::stringstream memory;
    esf::write_depth_png(memory, image, "memory");
    const esf::DepthImage from_memory = esf::read_depth_png(memory, "memory");
    EXPECT_EQ(from_memory.depth, image.depth);
    EXPECT_EQ(memory.str(), read_all(path));
}

TEST(DepthPng, ErrorsNameTheFile) {
    TempDir dir;
    const std::string text = dir.file("not_a_png.png");
    write_all(text, "P2\n2 2\n255\n0 1 2 3\n");
    EXPECT_EQ(io_error_message([&] { esf::read_depth_png(text); }), text + ": not a PNG file");

    const std::string eight = dir.file("eight_bit.png");
    ASSERT_TRUE(write_png_raw(eight, 2, 2, 8, PNG_COLOR_TYPE_GRAY, {1, 2, 3, 4}));
    EXPECT_EQ(io_error_message([&] { esf::read_depth_png(eight); }),
              eight +
                  ": 8-bit grayscale PNG; a depth image must be 16-bit grayscale (one value "
                  "per pixel)");

    const std::string rgb = dir.file("rgb16.png");
    ASSERT_TRUE(write_png_raw(rgb, 1, 1, 16, PNG_COLOR_TYPE_RGB, {1, 2, 3}));
    EXPECT_NE(io_error_message([&] { esf::read_depth_png(rgb); }).find(rgb + ": 16-bit RGB PNG"),
              std::string::npos);

    const std::string missing = dir.file("missing.png");
    EXPECT_EQ(
        io_error_message([&] { esf::read_depth_png(missing); }).rfind(missing + ": cannot open", 0),
        0u);

    // Truncated at every length: an error naming the file, never a crash or garbage.
    esf::DepthImage image{16, 16, std::vector<std::uint16_t>(256)};
    for (std::size_t i = 0; i < 256; ++i) image.depth[i] = static_cast<std::uint16_t>(i * 97);
    std::stringstream memory;
    esf::write_depth_png(memory, image, "memory");
    const std::string full = memory.str();
    const std::string cut = dir.file("cut.png");
    for (std::size_t length = 0; length + 1 < full.size(); length += 7) {
        write_all(cut, full.substr(0, length));
        const std::string message = io_error_message([&] { esf::read_depth_png(cut); });
        EXPECT_EQ(message.rfind(cut + ": ", 0), 0u) << "length " << length << ": " << message;
    }
    write_all(cut, full.substr(0, full.size() / 2));
    EXPECT_EQ(io_error_message([&] { esf::read_depth_png(cut); }),
              cut + ": truncated file (unexpected end of data)");

    // A flipped byte in the compressed data: corrupt, caught by the checksums.
    std::string flipped = full;
    flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x5A);
    const std::string bad = dir.file("bad.png");
    write_all(bad, flipped);
    EXPECT_EQ(io_error_message([&] { esf::read_depth_png(bad); }).rfind(bad + ": corrupt PNG", 0),
              0u);
}

TEST(DepthPng, WriteRejectsInconsistentImage) {
    std::stringstream out;
    EXPECT_THROW(esf::write_depth_png(out, esf::DepthImage{2, 2, {1}}, "x"), std::invalid_argument);
    TempDir dir;
    EXPECT_THROW(esf::write_depth_png(dir.file("no_such_dir/x.png"), esf::DepthImage{1, 1, {1}}),
                 esf::IoError);
}

}  // namespace
