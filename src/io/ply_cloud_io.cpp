// Reading PLY point clouds: the vertex element's x, y, z and an optional label; ascii, binary
// little and big endian; other elements (faces, materials, lists) are skipped.

#include <algorithm>
#include <array>
#include <istream>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/number_text.hpp"
#include "esf/io/cloud_io.hpp"
#include "io/cloud_io_detail.hpp"
#include "io/ply_header.hpp"

namespace esf {

namespace {

using namespace detail;

/// What each vertex property is to us: 0 x, 1 y, 2 z, 3 label, -1 skipped.
std::vector<int> vertex_roles(const PlyElement& vertex, const std::string& name) {
    std::vector<int> roles(vertex.properties.size(), -1);
    const std::array<std::string_view, 4> wanted = {"x", "y", "z", "label"};
    for (std::size_t w = 0; w < wanted.size(); ++w) {
        const auto it = std::find_if(vertex.properties.begin(), vertex.properties.end(),
                                     [&](const PlyProperty& p) { return p.name == wanted[w]; });
        if (it == vertex.properties.end()) {
            if (w == 3) continue;
            fail(name, vertex.line, "element 'vertex' has no property " + shown(wanted[w]));
        }
        if (it->is_list) {
            fail(name, vertex.line,
                 "property " + shown(wanted[w]) + " of element 'vertex' is a list");
        }
        roles[static_cast<std::size_t>(it - vertex.properties.begin())] = static_cast<int>(w);
    }
    return roles;
}

class PlyBinaryReader {
  public:
    PlyBinaryReader(std::string_view data, const PlyHeader& h, const std::string& name)
        : data_(data),
          begin_(h.data_pos),
          pos_(h.data_pos),
          name_(name),
          swap_((h.format == PlyFormat::kBinaryBig) == kLittleEndianHost) {}

    void skip(const PlyElement& e) {
        if (!e.has_list()) {
            require(checked_mul(e.count, e.stride(), name_), e, std::nullopt);
            pos_ += static_cast<std::size_t>(e.count * e.stride());
            return;
        }
        for (std::uint64_t i = 0; i < e.count; ++i) {
            for (const auto& p : e.properties) skip_property(p, e, i);
        }
    }

    PointCloud vertices(const PlyElement& e) {
        const std::vector<int> roles = vertex_roles(e, name_);
        PointCloud cloud;
        if (!e.has_list()) {
            // Fixed stride: check the whole block once, then read x, y, z in one pass and the
            // label column.
            const std::uint64_t stride = e.stride();
            require(checked_mul(e.count, stride, name_), e, std::nullopt);
            cloud.points.resize(e.count);
            XyzColumns columns;
            const char* label_src = nullptr;
            Scalar label_type = Scalar::kU32;
            std::uint64_t offset = 0;
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const char* src = data_.data() + pos_ + offset;
                const Scalar type = e.properties[k].type;
                if (roles[k] >= 0 && roles[k] < 3) {
                    const auto axis = static_cast<std::size_t>(roles[k]);
                    columns.src[axis] = src;
                    columns.stride[axis] = static_cast<std::size_t>(stride);
                    columns.type[axis] = type;
                } else if (roles[k] == 3) {
                    label_src = src;
                    label_type = type;
                }
                offset += scalar_size(type);
            }
            read_xyz_columns(columns, swap_, cloud.points);
            if (label_src) {
                cloud.labels.resize(e.count);
                const std::size_t bad = read_label_column(
                    label_src, static_cast<std::size_t>(stride), label_type, swap_, cloud.labels);
                if (bad < cloud.labels.size()) {
                    fail(name_, 0, "point " + str(bad) + ": label is not an integer in [0, 2^32)");
                }
            }
            pos_ += static_cast<std::size_t>(e.count * stride);
        } else {
            // Lists inside vertices: walk each one. Every vertex takes at least one byte per
            // property, so the count is checked against the bytes left before reserving.
            require(checked_mul(e.count, e.properties.size(), name_), e, std::nullopt);
            cloud.points.resize(e.count);
            bool has_label = std::find(roles.begin(), roles.end(), 3) != roles.end();
            if (has_label) cloud.labels.resize(e.count);
            for (std::uint64_t i = 0; i < e.count; ++i) {
                for (std::size_t k = 0; k < e.properties.size(); ++k) {
                    const PlyProperty& p = e.properties[k];
                    if (roles[k] < 0) {
                        skip_property(p, e, i);
                        continue;
                    }
                    require(scalar_size(p.type), e, i);
                    visit_scalar(p.type, [&](auto tag) {
                        using T = decltype(tag);
                        const T value = load<T>(data_.data() + pos_, swap_);
                        if (roles[k] < 3) {
                            cloud.points[i][roles[k]] = static_cast<float>(value);
                        } else if (!to_label(value, cloud.labels[i])) {
                            fail(name_, 0,
                                 "element 'vertex' " + str(i) +
                                     ": label is not an integer in [0, 2^32)");
                        }
                    });
                    pos_ += scalar_size(p.type);
                }
            }
        }
        return cloud;
    }

  private:
    /// Throws "truncated" unless `bytes` more bytes follow the current position.
    void require(std::uint64_t bytes, const PlyElement& e, std::optional<std::uint64_t> item) {
        const std::uint64_t available = data_.size() - pos_;
        if (bytes <= available) return;
        const std::string where =
            item ? "element " + shown(e.name) + " " + str(*item) : "element " + shown(e.name);
        fail(name_, 0,
             "truncated: expected " + str(checked_add(pos_ - begin_, bytes, name_)) +
                 " bytes of binary data, got " + str(data_.size() - begin_) + " (" + where + ")");
    }

    void skip_property(const PlyProperty& p, const PlyElement& e, std::uint64_t item) {
        if (!p.is_list) {
            require(scalar_size(p.type), e, item);
            pos_ += scalar_size(p.type);
            return;
        }
        require(scalar_size(p.count_type), e, item);
        const std::int64_t length = visit_scalar(p.count_type, [&](auto tag) -> std::int64_t {
            using T = decltype(tag);
            if constexpr (std::is_floating_point_v<T>) {
                return -1;  // rejected by the header parser
            } else {
                const T value = load<T>(data_.data() + pos_, swap_);
                if constexpr (std::is_same_v<T, std::uint64_t>) {
                    if (value >
                        static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
                        return -1;
                    }
                }
                return static_cast<std::int64_t>(value);
            }
        });
        if (length < 0) {
            fail(name_, 0,
                 "corrupt data: element " + shown(e.name) + " " + str(item) + ": property " +
                     shown(p.name) + " has a negative list length");
        }
        pos_ += scalar_size(p.count_type);
        const std::uint64_t bytes =
            checked_mul(static_cast<std::uint64_t>(length), scalar_size(p.type), name_);
        require(bytes, e, item);
        pos_ += static_cast<std::size_t>(bytes);
    }

    std::string_view data_;
    std::size_t begin_;
    std::size_t pos_;
    const std::string& name_;
    bool swap_;
};

/// Whitespace-separated tokens across lines, keeping the line number of the last token.
class TokenCursor {
  public:
    TokenCursor(std::string_view data, std::size_t pos, std::size_t line)
        : data_(data), pos_(pos), line_(line) {}

    bool next(std::string_view& token) {
        while (pos_ < data_.size()) {
            const char c = data_[pos_];
            if (c == '\n') {
                ++line_;
            } else if (kSpace.find(c) == std::string_view::npos) {
                break;
            }
            ++pos_;
        }
        if (pos_ >= data_.size()) return false;
        const std::size_t start = pos_;
        while (pos_ < data_.size() && data_[pos_] != '\n' &&
               kSpace.find(data_[pos_]) == std::string_view::npos) {
            ++pos_;
        }
        token = data_.substr(start, pos_ - start);
        return true;
    }
    std::size_t line() const { return line_; }

  private:
    std::string_view data_;
    std::size_t pos_;
    std::size_t line_;
};

PointCloud read_ply_ascii(std::string_view data, const PlyHeader& h, const std::string& name) {
    TokenCursor cursor(data, h.data_pos, h.data_line + 1);
    std::string_view token;
    for (const PlyElement& e : h.elements) {
        const bool is_vertex = e.name == "vertex";
        std::vector<int> roles(e.properties.size(), -1);
        PointCloud cloud;
        if (is_vertex) {
            roles = vertex_roles(e, name);
            // Each value takes at least one character and one separator.
            const std::uint64_t available = data.size() - h.data_pos;
            const std::uint64_t per_vertex = 2 * e.properties.size();
            if (e.count > 0 && e.count > (available + 1) / per_vertex) {
                fail(name, e.line,
                     "truncated: expected " + str(e.count) + " vertices, but only " +
                         str(available) + " bytes follow the header");
            }
            cloud.points.resize(e.count);
            if (std::find(roles.begin(), roles.end(), 3) != roles.end()) {
                cloud.labels.resize(e.count);
            }
        }
        if (e.properties.empty() && !is_vertex) continue;
        for (std::uint64_t i = 0; i < e.count; ++i) {
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                auto where = [&] {
                    return "element " + shown(e.name) + " " + str(i) + ", property " +
                           shown(p.name);
                };
                auto next = [&] {
                    if (!cursor.next(token)) {
                        fail(name, cursor.line(),
                             "truncated: unexpected end of file in " + where());
                    }
                };
                next();
                if (p.is_list) {
                    std::uint64_t length = 0;
                    if (!parse_integer(token, length)) {
                        fail(name, cursor.line(),
                             "list length is not a non-negative integer: " + shown(token) + " (" +
                                 where() + ")");
                    }
                    for (std::uint64_t j = 0; j < length; ++j) next();
                } else if (roles[k] >= 0 && roles[k] < 3) {
                    float& value = cloud.points[i][roles[k]];
                    const NumberText status = p.type == Scalar::kF32
                                                  ? parse_float(token, value)
                                                  : parse_float_via_double(token, value);
                    if (status == NumberText::kNotANumber) {
                        fail(name, cursor.line(),
                             "not a number: " + shown(token) + " (" + where() + ")");
                    }
                    if (status == NumberText::kOutOfRange) {
                        fail(name, cursor.line(),
                             "out of float range: " + shown(token) + " (" + where() + ")");
                    }
                } else if (roles[k] == 3) {
                    double label = 0.0;
                    if (!parse_double(token, label) || !to_label(label, cloud.labels[i])) {
                        fail(name, cursor.line(),
                             "label is not an integer in [0, 2^32): " + shown(token) + " (" +
                                 where() + ")");
                    }
                }
            }
        }
        if (is_vertex) return cloud;
    }
    fail(name, 0, "no element 'vertex'");
}

}  // namespace

PointCloud parse_ply_cloud(std::string_view data, const std::string& name) {
    if (data.empty()) fail(name, 0, "empty file");
    const PlyHeader h = parse_ply_header(data, name);
    const auto vertex = std::find_if(h.elements.begin(), h.elements.end(),
                                     [](const PlyElement& e) { return e.name == "vertex"; });
    if (vertex == h.elements.end()) fail(name, 0, "no element 'vertex'");
    if (vertex->count > std::numeric_limits<std::uint32_t>::max()) {
        fail(name, vertex->line, "too many vertices: " + str(vertex->count));
    }
    vertex_roles(*vertex, name);  // x, y, z present before any data is touched
    PointCloud cloud;
    if (h.format == PlyFormat::kAscii) {
        cloud = read_ply_ascii(data, h, name);
    } else {
        PlyBinaryReader reader(data, h, name);
        for (auto e = h.elements.begin(); e != vertex; ++e) reader.skip(*e);
        cloud = reader.vertices(*vertex);
    }
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    cloud.height = 1;
    return cloud;
}

PointCloud read_ply_cloud(const std::string& path) {
    const FileBytes bytes = read_regular_file(path);
    return parse_ply_cloud(bytes.view(), path);
}

PointCloud read_ply_cloud(std::istream& in, const std::string& name) {
    return parse_ply_cloud(read_all(in, name), name);
}

}  // namespace esf
