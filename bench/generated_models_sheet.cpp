// Contact sheet of the procedural training models (esf/shape_generator.hpp): three models of each
// of the ten categories, shaded orthographic z-buffer renderings with the longest side in cm.
// Faces seen from behind would show in magenta (a wrongly oriented or open mesh).
//
//   generated_models_sheet OUT.png [--seed S] [--first I] [--only CATEGORY] [--cell PIXELS]
//                                  [--models N]

#include <png.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include "esf/shapes/shape_generator.hpp"

namespace {

constexpr int kSuper = 3;          // supersampling factor per axis
constexpr int kDefaultModels = 3;  // per category
constexpr int kBlocks = 2;         // side-by-side blocks of categories
constexpr int kGap = 16;           // pixels between blocks
constexpr double kCrease = 35.0;   // degrees: sharper edges are not smoothed

struct Image {
    int width, height;
    std::vector<std::array<float, 3>> rgb;
    Image(int w, int h, std::array<float, 3> fill)
        : width(w),
          height(h),
          rgb(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), fill) {}
    std::array<float, 3>& at(int x, int y) {
        return rgb[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                   static_cast<std::size_t>(x)];
    }
};

/// Per-corner normals: the face normals around a vertex within kCrease of the corner's face.
std::vector<std::array<Eigen::Vector3f, 3>> corner_normals(const esf::Mesh& m) {
    std::vector<Eigen::Vector3f> face(m.triangles.size());
    std::vector<std::vector<std::size_t>> around(m.vertices.size());
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        const Eigen::Vector3i& t = m.triangles[f];
        const Eigen::Vector3f& a = m.vertices[static_cast<std::size_t>(t[0])];
        face[f] = (m.vertices[static_cast<std::size_t>(t[1])] - a)
                      .cross(m.vertices[static_cast<std::size_t>(t[2])] - a);  // area-weighted
        for (int k = 0; k < 3; ++k) around[static_cast<std::size_t>(t[k])].push_back(f);
    }
    const float cos_crease = static_cast<float>(std::cos(kCrease * M_PI / 180.0));
    std::vector<std::array<Eigen::Vector3f, 3>> normals(m.triangles.size());
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
        const Eigen::Vector3f own = face[f].normalized();
        for (int k = 0; k < 3; ++k) {
            Eigen::Vector3f sum = Eigen::Vector3f::Zero();
            for (const std::size_t g : around[static_cast<std::size_t>(m.triangles[f][k])])
                if (face[g].normalized().dot(own) >= cos_crease) sum += face[g];
            normals[f][static_cast<std::size_t>(k)] = sum.normalized();
        }
    }
    return normals;
}

/// Renders `mesh` into the cell whose top-left corner is (x0, y0) of `image` (supersampled).
void render(const esf::Mesh& mesh, const std::array<float, 3>& colour, Image& image, int x0, int y0,
            int size) {
    const double az = -55.0 * M_PI / 180.0, el = 28.0 * M_PI / 180.0;
    const Eigen::Vector3f eye(static_cast<float>(std::cos(el) * std::cos(az)),
                              static_cast<float>(std::cos(el) * std::sin(az)),
                              static_cast<float>(std::sin(el)));
    const Eigen::Vector3f right = Eigen::Vector3f::UnitZ().cross(eye).normalized();
    const Eigen::Vector3f up = eye.cross(right);
    const Eigen::Vector3f light = (eye + 0.7f * up - 0.5f * right).normalized();

    std::vector<Eigen::Vector3f> screen(mesh.vertices.size());
    Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector2f hi = -lo;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3f& p = mesh.vertices[i];
        screen[i] = {p.dot(right), -p.dot(up), p.dot(eye)};
        lo = lo.cwiseMin(screen[i].head<2>());
        hi = hi.cwiseMax(screen[i].head<2>());
    }
    const float scale = 0.80f * static_cast<float>(size) / (hi - lo).maxCoeff();
    const Eigen::Vector2f centre = 0.5f * (lo + hi);
    for (Eigen::Vector3f& s : screen) {
        s.head<2>() = (s.head<2>() - centre) * scale +
                      Eigen::Vector2f::Constant(0.5f * static_cast<float>(size));
    }
    std::vector<float> depth(static_cast<std::size_t>(size) * static_cast<std::size_t>(size),
                             -std::numeric_limits<float>::max());
    const auto normals = corner_normals(mesh);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Eigen::Vector3i& t = mesh.triangles[f];
        const Eigen::Vector3f& a = screen[static_cast<std::size_t>(t[0])];
        const Eigen::Vector3f& b = screen[static_cast<std::size_t>(t[1])];
        const Eigen::Vector3f& c = screen[static_cast<std::size_t>(t[2])];
        const float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
        if (std::abs(area) < 1e-12f) continue;
        // Screen y points down, so front faces (counter-clockwise from outside) have area < 0.
        const bool back = area > 0.0f;
        const int xa = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
        const int xb =
            std::min(size - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
        const int ya = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
        const int yb =
            std::min(size - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
        for (int y = ya; y <= yb; ++y) {
            for (int x = xa; x <= xb; ++x) {
                const float px = static_cast<float>(x) + 0.5f, py = static_cast<float>(y) + 0.5f;
                const float w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
                const float w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
                const float w2 = 1.0f - w0 - w1;
                if (w0 < 0.0f || w1 < 0.0f || w2 < 0.0f) continue;
                const float z = w0 * a.z() + w1 * b.z() + w2 * c.z();
                float& d = depth[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) +
                                 static_cast<std::size_t>(x)];
                if (z <= d) continue;
                d = z;
                std::array<float, 3>& out = image.at(x0 + x, y0 + y);
                if (back) {
                    out = {1.0f, 0.0f, 1.0f};
                    continue;
                }
                const Eigen::Vector3f n =
                    (w0 * normals[f][0] + w1 * normals[f][1] + w2 * normals[f][2]).normalized();
                const float diffuse = std::max(0.0f, n.dot(light));
                const Eigen::Vector3f half = (light + eye).normalized();
                const float specular = std::pow(std::max(0.0f, n.dot(half)), 40.0f);
                const float rim = 0.15f * std::max(0.0f, n.dot(eye));
                for (std::size_t k = 0; k < 3; ++k)
                    out[k] = std::min(
                        1.0f, colour[k] * (0.22f + 0.68f * diffuse + rim) + 0.25f * specular);
            }
        }
    }
}

// 5 x 7 capitals, digits and a few signs; one string of 35 '0'/'1' per glyph.
const char* glyph(char ch) {
    static const std::pair<char, const char*> kFont[] = {
        {'A', "01110100011000111111100011000110001"}, {'B', "11110100011000111110100011000111110"},
        {'C', "01110100011000010000100001000101110"}, {'D', "11100100101000110001100011001011100"},
        {'E', "11111100001000011110100001000011111"}, {'F', "11111100001000011110100001000010000"},
        {'G', "01110100011000010111100011000101111"}, {'H', "10001100011000111111100011000110001"},
        {'I', "01110001000010000100001000010001110"}, {'J', "00111000100001000010000101001001100"},
        {'K', "10001100101010011000101001001010001"}, {'L', "10000100001000010000100001000011111"},
        {'M', "10001110111010110101100011000110001"}, {'N', "10001100011100110101100111000110001"},
        {'O', "01110100011000110001100011000101110"}, {'P', "11110100011000111110100001000010000"},
        {'Q', "01110100011000110001101011001001101"}, {'R', "11110100011000111110101001001010001"},
        {'S', "01111100001000001110000010000111110"}, {'T', "11111001000010000100001000010000100"},
        {'U', "10001100011000110001100011000101110"}, {'V', "10001100011000110001100010101000100"},
        {'W', "10001100011000110101101011010101010"}, {'X', "10001100010101000100010101000110001"},
        {'Y', "10001100011000101010001000010000100"}, {'Z', "11111000010001000100010001000011111"},
        {'0', "01110100011001110101110011000101110"}, {'1', "00100011000010000100001000010001110"},
        {'2', "01110100010000100010001000100011111"}, {'3', "11111000100010000010000011000101110"},
        {'4', "00010001100101010010111110001000010"}, {'5', "11111100001111000001000011000101110"},
        {'6', "00110010001000011110100011000101110"}, {'7', "11111000010001000100010000100001000"},
        {'8', "01110100011000101110100011000101110"}, {'9', "01110100011000101111000010001001100"},
        {'_', "00000000000000000000000000000011111"}, {'.', "00000000000000000000000000110001100"},
        {'#', "01010010101111101010111110101001010"},
    };
    for (const auto& [c, bits] : kFont)
        if (c == ch) return bits;
    return nullptr;
}

void text(Image& image, int x, int y, const std::string& s, int scale,
          const std::array<float, 3>& colour) {
    for (const char ch : s) {
        if (const char* bits =
                glyph(static_cast<char>(std::toupper(static_cast<unsigned char>(ch))))) {
            for (int r = 0; r < 7; ++r)
                for (int c = 0; c < 5; ++c)
                    if (bits[r * 5 + c] == '1')
                        for (int dy = 0; dy < scale; ++dy)
                            for (int dx = 0; dx < scale; ++dx) {
                                const int px = x + c * scale + dx, py = y + r * scale + dy;
                                if (px >= 0 && py >= 0 && px < image.width && py < image.height)
                                    image.at(px, py) = colour;
                            }
        }
        x += 6 * scale;
    }
}

bool write_png(const std::string& path, Image& image) {
    FILE* file = std::fopen(path.c_str(), "wb");
    if (file == nullptr) return false;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(file);
        return false;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
                 static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 9);
    png_write_info(png, info);
    std::vector<png_byte> row(static_cast<std::size_t>(image.width) * 3);
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x)
            for (std::size_t k = 0; k < 3; ++k)
                row[static_cast<std::size_t>(x) * 3 + k] = static_cast<png_byte>(
                    std::lround(std::clamp(image.at(x, y)[k], 0.0f, 1.0f) * 255.0f));
        png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return std::fclose(file) == 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || argc % 2 != 0) {
        std::fprintf(stderr,
                     "usage: %s OUT.png [--seed S] [--first I] [--only CATEGORY] [--cell PIXELS]\n"
                     "       [--models N]\n",
                     argv[0]);
        return 1;
    }
    const std::string out = argv[1];
    std::uint64_t seed = 0;
    int first = 0, cell_px = 180, models = kDefaultModels;
    std::vector<std::string> categories = esf::generated_categories();
    for (int i = 2; i + 1 < argc; i += 2) {
        const std::string flag = argv[i];
        if (flag == "--seed") {
            seed = std::strtoull(argv[i + 1], nullptr, 10);
        } else if (flag == "--first") {
            first = std::atoi(argv[i + 1]);
        } else if (flag == "--cell") {
            cell_px = std::clamp(std::atoi(argv[i + 1]), 64, 1024);
        } else if (flag == "--models") {
            models = std::clamp(std::atoi(argv[i + 1]), 1, 12);
        } else if (flag == "--only") {
            categories = {argv[i + 1]};
        } else {
            std::fprintf(stderr, "unknown option %s\n", flag.c_str());
            return 1;
        }
    }
    const std::vector<std::string> all = esf::generated_categories();
    const int blocks = categories.size() > 1 ? kBlocks : 1;
    const int rows = (static_cast<int>(categories.size()) + blocks - 1) / blocks;
    const int block_w = models * cell_px;
    Image image(blocks * block_w + (blocks - 1) * kGap, rows * cell_px, {1.0f, 1.0f, 1.0f});
    const std::array<std::array<float, 3>, 10> palette = {{{0.80f, 0.20f, 0.18f},
                                                           {0.95f, 0.82f, 0.25f},
                                                           {0.30f, 0.62f, 0.45f},
                                                           {0.85f, 0.80f, 0.70f},
                                                           {0.25f, 0.45f, 0.85f},
                                                           {0.80f, 0.55f, 0.30f},
                                                           {0.60f, 0.55f, 0.50f},
                                                           {0.55f, 0.75f, 0.90f},
                                                           {0.92f, 0.92f, 0.88f},
                                                           {0.95f, 0.95f, 0.95f}}};
    const std::array<float, 3> ink = {0.15f, 0.15f, 0.15f};
    try {
        for (std::size_t c = 0; c < categories.size(); ++c) {
            const int block = static_cast<int>(c) / rows, row = static_cast<int>(c) % rows;
            const auto hue = static_cast<std::size_t>(
                std::find(all.begin(), all.end(), categories[c]) - all.begin());
            for (int m = 0; m < models; ++m) {
                const esf::Mesh mesh = esf::generate_shape(categories[c], seed, first + m);
                Image cell(cell_px * kSuper, cell_px * kSuper, {1.0f, 1.0f, 1.0f});
                render(mesh, palette[hue % palette.size()], cell, 0, 0, cell_px * kSuper);
                const int x0 = block * (block_w + kGap) + m * cell_px, y0 = row * cell_px;
                for (int y = 0; y < cell_px; ++y)
                    for (int x = 0; x < cell_px; ++x) {
                        std::array<float, 3> sum{};
                        for (int dy = 0; dy < kSuper; ++dy)
                            for (int dx = 0; dx < kSuper; ++dx)
                                for (std::size_t k = 0; k < 3; ++k)
                                    sum[k] += cell.at(x * kSuper + dx, y * kSuper + dy)[k];
                        for (std::size_t k = 0; k < 3; ++k) sum[k] /= kSuper * kSuper;
                        image.at(x0 + x, y0 + y) = sum;
                    }
                const Eigen::Vector3f size = mesh.max_corner() - mesh.min_corner();
                char label[32];
                std::snprintf(label, sizeof label, "%.1f CM", 100.0 * size.maxCoeff());
                text(image, x0 + cell_px - 6 * static_cast<int>(std::string(label).size()) - 4,
                     y0 + cell_px - 11, label, 1, ink);
                if (m == 0) text(image, x0 + 4, y0 + 4, categories[c], 2, ink);
                std::printf("%-13s #%d  %6zu triangles  %5.1f x %5.1f x %5.1f cm\n",
                            categories[c].c_str(), first + m, mesh.triangles.size(),
                            100.0 * size.x(), 100.0 * size.y(), 100.0 * size.z());
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    if (!write_png(out, image)) {
        std::fprintf(stderr, "cannot write %s\n", out.c_str());
        return 2;
    }
    return 0;
}
