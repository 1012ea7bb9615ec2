#include "io/png_writer.hpp"

#include <png.h>

#include <csetjmp>
#include <stdexcept>
#include <string>

namespace esf::detail {

namespace {

// libpng reports errors through longjmp: the function that calls setjmp holds only trivial
// locals, so no destructor is skipped; C++ objects live in its caller.

struct PngState {
    std::vector<std::uint8_t>* out = nullptr;
    std::string error;
};

void on_error(png_structp png, png_const_charp message) {
    static_cast<PngState*>(png_get_error_ptr(png))->error = message ? message : "error";
    png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}
void append_bytes(png_structp png, png_bytep data, png_size_t length) {
    auto* state = static_cast<PngState*>(png_get_io_ptr(png));
    state->out->insert(state->out->end(), data, data + length);
}
void flush_nothing(png_structp) {}

bool write_rows(png_structp png, png_infop info, png_uint_32 width, png_uint_32 height,
                int bit_depth, int color_type, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_IHDR(png, info, width, height, bit_depth, color_type, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

}  // namespace

std::vector<std::uint8_t> encode_png(std::span<const std::uint8_t> pixels, std::uint32_t width,
                                     std::uint32_t height, int channels, int bit_depth) {
    if ((channels != 1 && channels != 3) || (bit_depth != 8 && bit_depth != 16))
        throw std::invalid_argument("png: unsupported format");
    const std::size_t row_bytes = std::size_t{width} * static_cast<std::size_t>(channels) *
                                  static_cast<std::size_t>(bit_depth / 8);
    if (pixels.size() != row_bytes * height)
        throw std::invalid_argument("png: pixel buffer does not match the image size");
    std::vector<std::uint8_t> out;
    PngState state{&out, {}};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    struct Guard {
        png_structp* png;
        png_infop* info;
        ~Guard() { png_destroy_write_struct(png, info); }
    } guard{&png, &info};
    if (!png || !info) throw std::runtime_error("png: cannot allocate the encoder");
    png_set_write_fn(png, &state, append_bytes, flush_nothing);
    std::vector<png_bytep> rows(height);
    auto* base = const_cast<std::uint8_t*>(pixels.data());  // libpng does not write to them
    for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = base + y * row_bytes;
    if (!write_rows(png, info, width, height, bit_depth,
                    channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, rows.data()))
        throw std::runtime_error("png: " + state.error);
    return out;
}

}  // namespace esf::detail
