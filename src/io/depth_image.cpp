#include "esf/io/depth_image.hpp"

#include <png.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "esf/core/error.hpp"
#include "io/png_writer.hpp"

namespace esf {

namespace {

// libpng reports errors through longjmp. The functions that call setjmp below hold only trivial
// locals, so no destructor is skipped; C++ objects live in their callers.

constexpr std::size_t kMaxPixels = std::size_t{1} << 28;

struct PngState {
    char message[256] = {};
    std::istream* in = nullptr;
};

void on_error(png_structp png, png_const_charp message) {
    auto* state = static_cast<PngState*>(png_get_error_ptr(png));
    std::snprintf(state->message, sizeof state->message, "%s", message ? message : "error");
    png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}

void read_bytes(png_structp png, png_bytep data, png_size_t length) {
    auto* state = static_cast<PngState*>(png_get_error_ptr(png));
    state->in->read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(length));
    if (static_cast<png_size_t>(state->in->gcount()) != length)
        png_error(png, "truncated file (unexpected end of data)");
}

struct Header {
    png_uint_32 width = 0, height = 0;
    int bit_depth = 0, color_type = 0, interlace = 0;
};

bool read_header(png_structp png, png_infop info, Header* header) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_read_info(png, info);
    png_get_IHDR(png, info, &header->width, &header->height, &header->bit_depth,
                 &header->color_type, &header->interlace, nullptr, nullptr);
    return true;
}

bool read_pixels(png_structp png, png_infop info, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    png_read_image(png, rows);
    png_read_end(png, nullptr);
    return true;
}

const char* colour_name(int color_type) {
    switch (color_type) {
        case PNG_COLOR_TYPE_GRAY:
            return "grayscale";
        case PNG_COLOR_TYPE_GRAY_ALPHA:
            return "grayscale+alpha";
        case PNG_COLOR_TYPE_PALETTE:
            return "palette";
        case PNG_COLOR_TYPE_RGB:
            return "RGB";
        case PNG_COLOR_TYPE_RGB_ALPHA:
            return "RGBA";
        default:
            return "unknown colour type";
    }
}

void check_image(const DepthImage& image, const char* who) {
    if (image.width == 0 || image.height == 0)
        throw std::invalid_argument(std::string(who) + ": the depth image is empty");
    if (static_cast<std::size_t>(image.width) * image.height != image.depth.size())
        throw std::invalid_argument(std::string(who) + ": the depth image is " +
                                    std::to_string(image.width) + " x " +
                                    std::to_string(image.height) + " but holds " +
                                    std::to_string(image.depth.size()) + " values");
}

}  // namespace

DepthImage read_depth_png(std::istream& in, const std::string& name) {
    png_byte signature[8] = {};
    in.read(reinterpret_cast<char*>(signature), sizeof signature);
    if (in.gcount() != static_cast<std::streamsize>(sizeof signature) ||
        png_sig_cmp(signature, 0, sizeof signature) != 0)
        throw IoError(file_message(name, 0, "not a PNG file"));

    PngState state;
    state.in = &in;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    struct Guard {
        png_structp* png;
        png_infop* info;
        ~Guard() { png_destroy_read_struct(png, info, nullptr); }
    } guard{&png, &info};
    if (!png || !info) throw IoError(file_message(name, 0, "cannot initialise libpng"));
    png_set_read_fn(png, &state, read_bytes);
    png_set_sig_bytes(png, sizeof signature);
    png_set_user_limits(png, 1u << 20, 1u << 20);

    Header header;
    if (!read_header(png, info, &header))
        throw IoError(file_message(name, 0, std::string("corrupt PNG: ") + state.message));
    if (header.color_type != PNG_COLOR_TYPE_GRAY || header.bit_depth != 16)
        throw IoError(file_message(
            name, 0,
            std::to_string(header.bit_depth) + "-bit " + colour_name(header.color_type) +
                " PNG; a depth image must be 16-bit grayscale (one value per pixel)"));
    if (static_cast<std::size_t>(header.width) * header.height > kMaxPixels)
        throw IoError(file_message(name, 0,
                                   "image too large (" + std::to_string(header.width) + " x " +
                                       std::to_string(header.height) + " pixels)"));

    const std::size_t row_bytes = 2 * static_cast<std::size_t>(header.width);
    std::vector<png_byte> bytes(row_bytes * header.height);
    std::vector<png_bytep> rows(header.height);
    for (std::size_t v = 0; v < header.height; ++v) rows[v] = bytes.data() + v * row_bytes;
    if (!read_pixels(png, info, rows.data())) {
        const bool truncated = std::strstr(state.message, "truncated") != nullptr;
        throw IoError(
            file_message(name, 0, std::string(truncated ? "" : "corrupt PNG: ") + state.message));
    }

    DepthImage image;
    image.width = header.width;
    image.height = header.height;
    image.depth.resize(static_cast<std::size_t>(header.width) * header.height);
    for (std::size_t i = 0; i < image.depth.size(); ++i)  // PNG samples are big-endian
        image.depth[i] = static_cast<std::uint16_t>((bytes[2 * i] << 8) | bytes[2 * i + 1]);
    return image;
}

DepthImage read_depth_png(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw IoError(file_message(path, 0, "cannot open: " + std::string(std::strerror(errno))));
    return read_depth_png(in, path);
}

void write_depth_png(std::ostream& out, const DepthImage& image, const std::string& name) {
    check_image(image, "write_depth_png");
    std::vector<std::uint8_t> samples(2 * image.depth.size());  // 16-bit big-endian
    for (std::size_t i = 0; i < image.depth.size(); ++i) {
        samples[2 * i] = static_cast<std::uint8_t>(image.depth[i] >> 8);
        samples[2 * i + 1] = static_cast<std::uint8_t>(image.depth[i] & 0xFF);
    }
    std::vector<std::uint8_t> png;
    try {
        png = detail::encode_png(samples, static_cast<std::uint32_t>(image.width),
                                 static_cast<std::uint32_t>(image.height), 1, 16);
    } catch (const std::runtime_error& e) {
        throw IoError(file_message(name, 0, std::string("cannot write PNG: ") + e.what()));
    }
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    if (!out) throw IoError(file_message(name, 0, "write failed"));
}

void write_depth_png(const std::string& path, const DepthImage& image) {
    check_image(image, "write_depth_png");
    detail::write_file_atomically(path,
                                  [&](std::ostream& out) { write_depth_png(out, image, path); });
}

PointCloud depth_to_cloud(const DepthImage& image, const CameraIntrinsics& k,
                          double metres_per_unit) {
    check_image(image, "depth_to_cloud");
    auto positive = [](double value, const char* what) {
        if (!(value > 0.0) || !std::isfinite(value))
            throw std::invalid_argument(std::string("depth_to_cloud: ") + what +
                                        " must be positive and finite, got " +
                                        std::to_string(value));
    };
    positive(k.fx, "fx");
    positive(k.fy, "fy");
    positive(metres_per_unit, "the depth scale");
    if (!std::isfinite(k.cx) || !std::isfinite(k.cy))
        throw std::invalid_argument("depth_to_cloud: cx and cy must be finite");

    PointCloud cloud;
    cloud.width = image.width;
    cloud.height = image.height;
    cloud.points.resize(image.depth.size());
    std::vector<double> x_factor(image.width);
    for (std::uint32_t u = 0; u < image.width; ++u) x_factor[u] = (u - k.cx) / k.fx;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::uint32_t v = 0; v < image.height; ++v) {
        const double y_factor = (v - k.cy) / k.fy;
        for (std::uint32_t u = 0; u < image.width; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * image.width + u;
            const std::uint16_t raw = image.depth[i];
            if (raw == 0) {
                cloud.points[i] = Eigen::Vector3f(nan, nan, nan);
                continue;
            }
            const double z = raw * metres_per_unit;
            cloud.points[i] = Eigen::Vector3d(x_factor[u] * z, y_factor * z, z).cast<float>();
        }
    }
    return cloud;
}

}  // namespace esf
