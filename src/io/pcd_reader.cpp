// Reading PCD files: ascii, binary and binary_compressed, any field layout (x, y, z and an
// optional label are read; other fields are skipped).

#include <algorithm>
#include <array>
#include <cstdlib>
#include <istream>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <vector>

#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "esf/core/point_cloud.hpp"
#include "esf/io/cloud_io.hpp"
#include "io/cloud_io_detail.hpp"
#include "io/lzf.hpp"
#include "io/pcd_header.hpp"

namespace esf {

namespace {

using namespace detail;

/// The error for binary data shorter than its header says.
[[noreturn]] void fail_truncated(const std::string& name, std::uint64_t need,
                                 std::uint64_t available) {
    fail(name, 0,
         "truncated: expected " + str(need) + " bytes of binary data, got " + str(available));
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// One point per line, one token per value (padding '_' included); only the tokens of x, y, z
/// and label are parsed, each with std::from_chars.
void read_pcd_ascii(std::string_view data, const PcdHeader& h, const std::string& name,
                    PointCloud& cloud) {
    std::vector<std::uint64_t> first_token(h.fields.size());
    std::uint64_t values = 0;
    for (std::size_t f = 0; f < h.fields.size(); ++f) {
        first_token[f] = values;
        values = checked_add(values, h.fields[f].count, name);
    }
    const std::uint64_t n = h.points;
    const std::uint64_t available = data.size() - h.data_pos;
    // A point needs at least one character and one separator per value.
    if (n > 0 && (values > available || n > (available + 1) / (2 * values))) {
        fail(name, 0,
             "truncated: expected " + str(n) + " points of ascii data, but only " + str(available) +
                 " bytes follow the header");
    }
    cloud.points.resize(n);
    if (h.label) cloud.labels.resize(n);

    // What each token of a line is: 0, 1, 2 = x, y, z; 3 = label; -1 = skipped.
    std::vector<signed char> role(static_cast<std::size_t>(values), -1);
    const std::array<std::size_t, 3> xyz = {h.x, h.y, h.z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
        role[first_token[xyz[axis]]] = static_cast<signed char>(axis);
    }
    if (h.label) role[first_token[*h.label]] = 3;

    LineCursor cursor(data, h.data_pos, h.data_line);
    std::string_view line;
    std::array<std::string_view, 4> picked;
    std::uint64_t i = 0;
    while (cursor.next(line)) {
        std::uint64_t count = 0;
        for (std::size_t p = 0;;) {
            while (p < line.size() && is_space(line[p])) ++p;
            if (p == line.size()) break;
            const std::size_t start = p;
            while (p < line.size() && !is_space(line[p])) ++p;
            if (count < values && role[count] >= 0) {
                picked[static_cast<std::size_t>(role[count])] = line.substr(start, p - start);
            }
            ++count;
        }
        if (count == 0) continue;
        const std::size_t ln = cursor.line();
        if (i == n) fail(name, ln, "more data lines than POINTS (" + str(n) + ")");
        if (count < values)
            fail(name, ln, "expected " + str(values) + " values, got " + str(count));
        for (std::size_t axis = 0; axis < 3; ++axis) {
            const PcdField& field = h.fields[xyz[axis]];
            float& value = cloud.points[i][static_cast<int>(axis)];
            const NumberText status = field.type == 'F' && field.size == 4
                                          ? parse_float(picked[axis], value)
                                          : parse_float_via_double(picked[axis], value);
            if (status == NumberText::kNotANumber) {
                fail(name, ln,
                     "not a number: " + shown(picked[axis]) + " (field " + shown(field.name) + ")");
            }
            if (status == NumberText::kOutOfRange) {
                fail(name, ln,
                     "out of float range: " + shown(picked[axis]) + " (field " + shown(field.name) +
                         ")");
            }
        }
        if (h.label) {
            double value = 0.0;
            if (!parse_double(picked[3], value) || !to_label(value, cloud.labels[i])) {
                fail(name, ln, "label is not an integer in [0, 2^32): " + shown(picked[3]));
            }
        }
        ++i;
    }
    if (i < n) {
        fail(name, cursor.line(),
             "truncated: expected " + str(n) + " points of ascii data, got " + str(i));
    }
}

/// Where a reader puts the points: all of them into the cloud (`finite` null), or only the finite
/// ones, in order, into *finite, counting the others in `dropped`.
struct PointsOut {
    Points* finite = nullptr;
    std::size_t dropped = 0;
};

/// Reads x, y, z (and label) from fields laid out one after another: AoS (binary, stride =
/// point size) or SoA (decompressed binary_compressed, one block per field).
void read_pcd_fields(const char* base, const PcdHeader& h, const std::vector<std::uint64_t>& start,
                     const std::vector<std::uint64_t>& stride, const std::string& name,
                     PointCloud& cloud, PointsOut& out) {
    const bool swap = !kLittleEndianHost;
    XyzColumns columns;
    const std::array<std::size_t, 3> xyz = {h.x, h.y, h.z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
        const std::size_t f = xyz[axis];
        columns.src[axis] = base + start[f];
        columns.stride[axis] = static_cast<std::size_t>(stride[f]);
        columns.type[axis] = h.fields[f].scalar();
    }
    if (out.finite) {
        out.dropped = read_finite_xyz_columns(columns, swap, h.points, *out.finite);
    } else {
        cloud.points.resize(h.points);
        read_xyz_columns(columns, swap, cloud.points);
    }
    // Labels are checked even when not kept, except uint32 ones (PCL's), which are all valid.
    const bool labels_all_valid = h.label && h.fields[*h.label].scalar() == Scalar::kU32;
    if (h.label && !(out.finite && labels_all_valid)) {
        cloud.labels.resize(h.points);
        const std::size_t f = *h.label;
        const std::size_t bad =
            read_label_column(base + start[f], stride[f], h.fields[f].scalar(), swap, cloud.labels);
        if (bad < cloud.labels.size()) {
            fail(name, 0, "point " + str(bad) + ": label is not an integer in [0, 2^32)");
        }
    }
}

void read_pcd_binary(std::string_view data, const PcdHeader& h, const std::string& name,
                     PointCloud& cloud, PointsOut& out) {
    std::vector<std::uint64_t> start(h.fields.size()), stride(h.fields.size());
    std::uint64_t point_step = 0;
    for (std::size_t f = 0; f < h.fields.size(); ++f) {
        start[f] = point_step;
        point_step =
            checked_add(point_step, checked_mul(h.fields[f].size, h.fields[f].count, name), name);
    }
    std::fill(stride.begin(), stride.end(), point_step);
    const std::uint64_t need = checked_mul(h.points, point_step, name);
    const std::uint64_t available = data.size() - h.data_pos;
    if (available < need) fail_truncated(name, need, available);
    read_pcd_fields(data.data() + h.data_pos, h, start, stride, name, cloud, out);
}

void read_pcd_compressed(std::string_view data, const PcdHeader& h, const std::string& name,
                         PointCloud& cloud, PointsOut& out) {
    const std::uint64_t available = data.size() - h.data_pos;
    const char* base = data.data() + h.data_pos;
    if (available < 8) fail_truncated(name, 8, available);
    const std::uint64_t compressed = load<std::uint32_t>(base, !kLittleEndianHost);
    const std::uint64_t uncompressed = load<std::uint32_t>(base + 4, !kLittleEndianHost);
    if (available - 8 < compressed) fail_truncated(name, compressed + 8, available);
    // PCL stores one block per field, all points' values contiguous, without the padding
    // fields '_'; a block layout that keeps the padding is accepted too.
    std::uint64_t bytes_without_padding = 0, bytes_with_padding = 0;
    for (const auto& f : h.fields) {
        const std::uint64_t b = checked_mul(f.size, f.count, name);
        bytes_with_padding = checked_add(bytes_with_padding, b, name);
        if (!f.padding()) bytes_without_padding = checked_add(bytes_without_padding, b, name);
    }
    const std::uint64_t soa = checked_mul(h.points, bytes_without_padding, name);
    const std::uint64_t soa_padded = checked_mul(h.points, bytes_with_padding, name);
    bool keep_padding = false;
    if (uncompressed == soa) {
        keep_padding = false;
    } else if (uncompressed == soa_padded) {
        keep_padding = true;
    } else {
        fail(name, 0,
             "corrupt binary_compressed data: uncompressed size " + str(uncompressed) +
                 " does not match the header (" + str(h.points) + " points of " +
                 str(bytes_without_padding) + " bytes = " + str(soa) + ")");
    }
    if (uncompressed > compressed * kLzfMaxRatio) {
        fail(name, 0,
             "corrupt binary_compressed data: " + str(compressed) +
                 " compressed bytes cannot hold " + str(uncompressed) + " bytes");
    }
    // One block per field; the blocks after the last one read (the colours, usually) are only
    // checked, not written: the check covers every token as decoding would.
    std::vector<std::uint64_t> start(h.fields.size()), stride(h.fields.size());
    std::uint64_t offset = 0, read_end = 0;
    for (std::size_t f = 0; f < h.fields.size(); ++f) {
        stride[f] = h.fields[f].bytes();
        start[f] = offset;
        if (keep_padding || !h.fields[f].padding()) offset += h.points * stride[f];
        if (f == h.x || f == h.y || f == h.z || (h.label && f == *h.label)) read_end = offset;
    }
    const auto size = static_cast<std::size_t>(uncompressed);
    const auto wanted = static_cast<std::size_t>(read_end);
    auto buffer = std::make_unique_for_overwrite<unsigned char[]>(std::max<std::size_t>(wanted, 1));
    const LzfDecoded decoded = lzf_decompress(
        {reinterpret_cast<const unsigned char*>(base + 8), static_cast<std::size_t>(compressed)},
        {buffer.get(), wanted}, size);
    if (decoded.error) {
        fail(name, 0,
             std::string("corrupt LZF data in binary_compressed block: ") + decoded.error +
                 " (compressed byte " + str(decoded.at) + ")");
    }
    if (decoded.produced != size) {
        fail(name, 0,
             "corrupt binary_compressed data: decompressed to " + str(decoded.produced) +
                 " bytes, expected " + str(uncompressed));
    }
    read_pcd_fields(reinterpret_cast<const char*>(buffer.get()), h, start, stride, name, cloud,
                    out);
}

PointCloud parse_pcd_into(std::string_view data, const std::string& name, PointsOut& out) {
    if (data.empty()) fail(name, 0, "empty file");
    const PcdHeader h = parse_pcd_header(data, name);
    PointCloud cloud;
    cloud.width = h.width;
    cloud.height = h.height;
    switch (h.data) {
        case PcdData::kAscii:
            read_pcd_ascii(data, h, name, cloud);
            if (out.finite) out.dropped = drop_non_finite(cloud.points, *out.finite);
            break;
        case PcdData::kBinary:
            read_pcd_binary(data, h, name, cloud, out);
            break;
        case PcdData::kBinaryCompressed:
            read_pcd_compressed(data, h, name, cloud, out);
            break;
    }
    return cloud;
}

}  // namespace

PointCloud parse_pcd(std::string_view data, const std::string& name) {
    PointsOut all;
    return parse_pcd_into(data, name, all);
}

namespace {

/// The bytes read first: a header that ends within them is parsed before the data is read.
constexpr std::size_t kHeadBytes = 4096;

/// Whether each point is exactly x, y, z as float32 in this host's byte order, nothing else:
/// the data is then the points' own memory layout.
bool packed_xyz_floats(const PcdHeader& h) {
    static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
    if (!kLittleEndianHost || h.data != PcdData::kBinary || h.label || h.fields.size() != 3)
        return false;
    for (const PcdField& f : h.fields)
        if (f.type != 'F' || f.size != 4 || f.count != 1) return false;
    return h.x == 0 && h.y == 1 && h.z == 2;
}

/// read_pcd(path), the points going to `out` (see PointsOut).
PointCloud read_pcd_into(const std::string& path, PointsOut& out) {
    RegularFile file(path);
    const std::size_t size = file.size();
    std::array<char, kHeadBytes> first_bytes;
    const std::size_t head = file.read(first_bytes.data(), std::min(size, kHeadBytes));
    const char* const bytes = first_bytes.data();
    // Binary x y z floats (segmented views are usually stored so) are read straight into the
    // points: one copy from the operating system, none through a buffer of the whole file. The
    // header must end (with its DATA line's newline) within the bytes read first; anything else
    // goes through parse_pcd, which also reports every error.
    PcdHeader h;
    bool direct = false;
    try {
        h = parse_pcd_header({bytes, head}, path);
        direct = h.data_pos <= head && h.data_pos > 0 && bytes[h.data_pos - 1] == '\n' &&
                 h.points > 0 && packed_xyz_floats(h);
    } catch (const IoError&) {
        direct = false;  // an error, or a header longer than the bytes read first
    }
    if (direct) {
        const std::uint64_t need = checked_mul(h.points, 3 * sizeof(float), path);
        if (need <= size - h.data_pos) {
            PointCloud cloud;
            cloud.width = h.width;
            cloud.height = h.height;
            Points& points = out.finite ? *out.finite : cloud.points;
            points.resize(h.points);  // Eigen's vectors are not zero-filled
            char* into = reinterpret_cast<char*>(points.data());
            const std::size_t first = std::min<std::size_t>(head - h.data_pos, need);
            std::copy_n(bytes + h.data_pos, first, into);
            const std::size_t got = first + file.read(into + first, need - first);
            if (got < need) fail_truncated(path, need, got);  // the file shrank meanwhile
            if (out.finite) out.dropped = drop_non_finite_in_place(points);
            return cloud;
        }
    }
    auto whole = std::make_unique_for_overwrite<char[]>(std::max<std::size_t>(size, 1));
    std::copy_n(bytes, head, whole.get());
    const std::size_t total = head + file.read(whole.get() + head, size - head);
    return parse_pcd_into({whole.get(), total}, path, out);
}

}  // namespace

PointCloud read_pcd(const std::string& path) {
    PointsOut all;
    return read_pcd_into(path, all);
}

namespace detail {

std::size_t read_pcd_finite(const std::string& path, Points& finite) {
    PointsOut out{&finite};
    read_pcd_into(path, out);
    return out.dropped;
}

}  // namespace detail

PointCloud read_pcd(std::istream& in, const std::string& name) {
    return parse_pcd(read_all(in, name), name);
}

}  // namespace esf
