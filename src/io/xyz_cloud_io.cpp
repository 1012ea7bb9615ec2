// Plain-text point clouds: "x y z [more columns]" per line, whitespace or commas, '#' comments.

#include <istream>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "esf/io/cloud_io.hpp"
#include "io/cloud_io_detail.hpp"

namespace esf {

using namespace detail;

PointCloud parse_xyz(std::string_view data, const std::string& name) {
    if (data.empty()) fail(name, 0, "empty file");
    constexpr std::string_view kSeparators = " \t\r\v\f,";
    PointCloud cloud;
    LineCursor cursor(data, 0, 0);
    std::vector<std::string_view> tok;
    std::string_view line;
    while (cursor.next(line)) {
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
            line = line.substr(0, hash);
        }
        split(line, kSeparators, tok);
        if (tok.empty()) continue;
        if (tok.size() < 3) {
            fail(name, cursor.line(),
                 "expected at least 3 numbers (x y z), got " + str(tok.size()));
        }
        Eigen::Vector3f p;
        for (int axis = 0; axis < 3; ++axis) {
            const std::string_view token = tok[static_cast<std::size_t>(axis)];
            const NumberText status = parse_float(token, p[axis]);
            if (status == NumberText::kNotANumber) {
                fail(name, cursor.line(), "not a number: " + shown(token));
            }
            if (status == NumberText::kOutOfRange) {
                fail(name, cursor.line(), "out of float range: " + shown(token));
            }
        }
        cloud.points.push_back(p);
    }
    if (cloud.points.size() > std::numeric_limits<std::uint32_t>::max()) {
        fail(name, 0, "too many points");
    }
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    cloud.height = 1;
    return cloud;
}

PointCloud read_xyz(const std::string& path) {
    const FileBytes bytes = read_regular_file(path);
    return parse_xyz(bytes.view(), path);
}

PointCloud read_xyz(std::istream& in, const std::string& name) {
    return parse_xyz(read_all(in, name), name);
}

namespace {

std::string encode_xyz(const PointCloud& cloud) {
    std::string out;
    out.reserve(cloud.points.size() * 36);
    for (const Eigen::Vector3f& p : cloud.points) {
        append_float(out, p.x());
        out += ' ';
        append_float(out, p.y());
        out += ' ';
        append_float(out, p.z());
        out += '\n';
    }
    return out;
}

}  // namespace

void write_xyz(std::ostream& out, const PointCloud& cloud) {
    const std::string bytes = encode_xyz(cloud);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError("write_xyz: writing to the output stream failed");
}

void write_xyz(const std::string& path, const PointCloud& cloud) {
    write_file_atomically(path, encode_xyz(cloud));
}

}  // namespace esf
