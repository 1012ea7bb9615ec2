// Writing PCD files: x y z (and rgb, label), PCL's header, ascii / binary / binary_compressed.

#include <array>
#include <cstring>
#include <limits>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "esf/io/cloud_io.hpp"
#include "io/cloud_io_detail.hpp"
#include "io/lzf.hpp"

namespace esf {

namespace {

using namespace detail;

template <class T>
void put_le(char* out, T value) {
    std::memcpy(out, &value, sizeof(T));
    if constexpr (!kLittleEndianHost) std::reverse(out, out + sizeof(T));
}

std::string encode_pcd(const PointCloud& cloud, PcdEncoding encoding) {
    const std::size_t n = cloud.points.size();
    const bool with_rgb = !cloud.rgb.empty();
    const bool with_labels = !cloud.labels.empty();
    if (with_labels && cloud.labels.size() != n) {
        throw std::invalid_argument("write_pcd: " + str(cloud.labels.size()) + " labels for " +
                                    str(n) + " points");
    }
    if (with_rgb && cloud.rgb.size() != n) {
        throw std::invalid_argument("write_pcd: " + str(cloud.rgb.size()) + " colours for " +
                                    str(n) + " points");
    }
    if (n > std::numeric_limits<std::uint32_t>::max()) {
        throw std::invalid_argument("write_pcd: too many points for a PCD file");
    }
    std::uint32_t width = cloud.width, height = cloud.height;
    if (height == 0 || std::uint64_t{width} * height != n) {
        width = static_cast<std::uint32_t>(n);
        height = 1;
    }
    // The unsigned fields after x y z: rgb (0x00RRGGBB, as PCL packs it), then label.
    std::vector<const std::vector<std::uint32_t>*> extra;
    std::string names = "x y z", sizes = "4 4 4", types = "F F F", counts = "1 1 1";
    const auto add_field = [&](const char* name, const std::vector<std::uint32_t>& values) {
        extra.push_back(&values);
        names += std::string(" ") + name;
        sizes += " 4";
        types += " U";
        counts += " 1";
    };
    if (with_rgb) add_field("rgb", cloud.rgb);
    if (with_labels) add_field("label", cloud.labels);
    std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
    out += "FIELDS " + names + "\nSIZE " + sizes + "\nTYPE " + types + "\nCOUNT " + counts + "\n";
    out += "WIDTH " + str(width) + "\nHEIGHT " + str(height) +
           "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + str(n) + "\n";
    const std::size_t fields = 3 + extra.size();
    const std::size_t point_step = 4 * fields;

    if (encoding == PcdEncoding::kAscii) {
        // Shortest round-trip text per value (std::to_chars): reads back bit for bit.
        out += "DATA ascii\n";
        out.reserve(out.size() + n * 12 * fields);
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3f& p = cloud.points[i];
            append_float(out, p.x());
            out += ' ';
            append_float(out, p.y());
            out += ' ';
            append_float(out, p.z());
            for (const std::vector<std::uint32_t>* values : extra) {
                out += ' ';
                append_uint(out, (*values)[i]);
            }
            out += '\n';
        }
        return out;
    }
    if (encoding == PcdEncoding::kBinary) {
        out += "DATA binary\n";
        std::size_t pos = out.size();
        out.resize(pos + n * point_step);
        if (extra.empty() && kLittleEndianHost && n > 0) {
            std::memcpy(out.data() + pos, cloud.points.data(), n * point_step);
            return out;
        }
        for (std::size_t i = 0; i < n; ++i, pos += point_step) {
            for (int axis = 0; axis < 3; ++axis) {
                put_le(out.data() + pos + 4 * static_cast<std::size_t>(axis),
                       cloud.points[i][axis]);
            }
            for (std::size_t f = 0; f < extra.size(); ++f)
                put_le(out.data() + pos + 12 + 4 * f, (*extra[f])[i]);
        }
        return out;
    }

    // binary_compressed: one block per field (all x, then all y, ...), LZF-compressed, behind
    // the compressed and uncompressed sizes as two little-endian uint32.
    out += "DATA binary_compressed\n";
    const std::uint64_t raw_size = std::uint64_t{n} * point_step;
    if (raw_size > std::numeric_limits<std::uint32_t>::max() / 2) {
        throw std::invalid_argument("write_pcd: cloud too large for binary_compressed");
    }
    std::vector<unsigned char> raw(static_cast<std::size_t>(raw_size));
    char* soa = reinterpret_cast<char*>(raw.data());
    for (std::size_t i = 0; i < n; ++i) {
        for (int axis = 0; axis < 3; ++axis) {
            put_le(soa + 4 * (static_cast<std::size_t>(axis) * n + i), cloud.points[i][axis]);
        }
        for (std::size_t f = 0; f < extra.size(); ++f)
            put_le(soa + 4 * ((3 + f) * n + i), (*extra[f])[i]);
    }
    const std::size_t pos = out.size();
    out.resize(pos + 8 + lzf_compress_bound(raw.size()));
    const std::size_t packed = lzf_compress(
        raw, {reinterpret_cast<unsigned char*>(out.data() + pos + 8), out.size() - pos - 8});
    put_le(out.data() + pos, static_cast<std::uint32_t>(packed));
    put_le(out.data() + pos + 4, static_cast<std::uint32_t>(raw.size()));
    out.resize(pos + 8 + packed);
    return out;
}

}  // namespace

void write_pcd(std::ostream& out, const PointCloud& cloud, PcdEncoding encoding) {
    const std::string bytes = encode_pcd(cloud, encoding);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError("write_pcd: writing to the output stream failed");
}

void write_pcd(const std::string& path, const PointCloud& cloud, PcdEncoding encoding) {
    write_file_atomically(path, encode_pcd(cloud, encoding));
}

}  // namespace esf
