#pragma once
// Reading and writing point clouds: PCD (ascii, binary, binary_compressed; any field layout),
// PLY point clouds (ascii, binary little and big endian) and plain "x y z" text.
//
// Readers take a path, any std::istream or the bytes of a whole file (so tests run in memory);
// every failure throws esf::IoError with a message naming the file (and line or element where
// known). Only x, y, z (and an optional integer `label` field) are read; the organised layout
// width x height is kept. Non-finite points are kept as they are: drop them with
// drop_non_finite() before describing.
//
// Paths must name regular files: a directory, FIFO, socket or device is refused before anything
// is read (never blocks). Point counts in headers are checked against the bytes present before
// anything is allocated. Text numbers must fit a float: "1e39" is an error naming the line and
// the value, "1e-50" reads as 0 (values below the float range round to 0 or a subnormal).

#include <array>
#include <iosfwd>
#include <string>
#include <string_view>

#include "esf/core/enum_names.hpp"
#include "esf/core/point_cloud.hpp"

namespace esf {

enum class CloudFormat { kPcd, kPly, kXyz };

/// Format from the file extension (.pcd, .ply, .xyz / .txt / .pts); throws IoError otherwise.
CloudFormat cloud_format_from_path(const std::string& path);

/// Reads a cloud, choosing the format from the extension.
PointCloud read_cloud(const std::string& path);

/// The finite points of a cloud file, in file order, into `finite` (replaced; its memory is
/// reused from call to call): drop_non_finite(read_cloud(path).points, finite), with the same
/// checks and errors, without building the cloud. Returns how many points were dropped. Labels
/// and the organised layout are not kept; a binary_compressed PCD's x, y, z columns are
/// interleaved and filtered in one pass.
std::size_t read_finite_points(const std::string& path, Points& finite);

PointCloud read_pcd(const std::string& path);
PointCloud read_pcd(std::istream& in, const std::string& name);
/// Reads a PCD file already in memory; `name` is used in messages only.
PointCloud parse_pcd(std::string_view bytes, const std::string& name);

PointCloud read_ply_cloud(const std::string& path);
PointCloud read_ply_cloud(std::istream& in, const std::string& name);
PointCloud parse_ply_cloud(std::string_view bytes, const std::string& name);

/// Whitespace- or comma-separated "x y z [more columns]" per line; '#' starts a comment.
PointCloud read_xyz(const std::string& path);
PointCloud read_xyz(std::istream& in, const std::string& name);
PointCloud parse_xyz(std::string_view bytes, const std::string& name);

enum class PcdEncoding { kAscii, kBinary, kBinaryCompressed };

/// "binary", "ascii", "binary_compressed": the DATA line of the header.
template <>
struct EnumNames<PcdEncoding> {
    static constexpr const char* what = "PCD encoding";
    static constexpr std::array<EnumName<PcdEncoding>, 3> table{
        {{PcdEncoding::kBinary, "binary"},
         {PcdEncoding::kAscii, "ascii"},
         {PcdEncoding::kBinaryCompressed, "binary_compressed"}}};
};

/// Writes x y z (then `rgb` and `label` when the cloud has colours or labels), keeping width x
/// height. The file is written to a temporary name beside the target and renamed, so a failure
/// leaves no partial file.
void write_pcd(const std::string& path, const PointCloud& cloud,
               PcdEncoding encoding = PcdEncoding::kBinary);
void write_pcd(std::ostream& out, const PointCloud& cloud,
               PcdEncoding encoding = PcdEncoding::kBinary);

/// Writes one "x y z" line per point (shortest text that reads back as the same float; NaN as
/// "nan"), atomically like write_pcd. Labels and the organised layout are not kept.
void write_xyz(const std::string& path, const PointCloud& cloud);
void write_xyz(std::ostream& out, const PointCloud& cloud);

}  // namespace esf
