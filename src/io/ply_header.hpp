#pragma once
// PLY headers, parsed in one place: the point-cloud reader (ply_cloud_io.cpp) refuses any header
// that breaks the format; the checks made on a mesh file before Assimp reads it
// (mesh/mesh_checks.cpp) go on with what was understood and check the sizes it announces.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/cloud_io_detail.hpp"

namespace esf::detail {

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

struct PlyProperty {
    std::string name;
    Scalar type = Scalar::kF32;  ///< of the value; of each item for a list
    bool is_list = false;
    Scalar count_type = Scalar::kU8;  ///< of a list's count
    /// False when the line names no PLY type where one belongs (type and count_type then mean
    /// nothing).
    bool known_type = true;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    /// The count as written, as a number: also a count beyond 2^64 or with a fraction, which
    /// `count` cannot hold; NaN when there is no number.
    double written_count = 0.0;
    std::vector<PlyProperty> properties;
    std::size_t line = 0;  ///< of the element line

    bool has_list() const;
    /// Bytes per item in binary; only meaningful without list properties.
    std::uint64_t stride() const;
};

struct PlyHeader {
    bool is_ply = false;  ///< the first line is "ply" (or "PLY")
    bool ended = false;   ///< an end_header line was found
    PlyFormat format = PlyFormat::kAscii;
    std::vector<PlyElement> elements;
    std::size_t data_pos = 0;   ///< the first byte after the end_header line
    std::size_t data_line = 0;  ///< line number of end_header
    /// Where the header first breaks the PLY format: the line (1-based) and why, as the
    /// point-cloud reader reports it ("bad header: ..."); empty when it follows the format.
    std::size_t problem_line = 0;
    std::string problem;
};

/// The header at the start of `data`, never throwing. After a line that breaks the format the
/// rest is still read as far as it can be understood: unknown keywords and properties before
/// any element are passed over, a property whose type is not a PLY type is kept with known_type
/// false, a format line that is not one of the three keeps ascii (binary little endian when it
/// starts with "binary"). Reading stops at end_header, or at once when the first line is not
/// "ply" or "PLY".
PlyHeader read_ply_header(std::string_view data);

/// read_ply_header(), with its first problem thrown as esf::IoError "name:line: problem".
PlyHeader parse_ply_header(std::string_view data, const std::string& name);

}  // namespace esf::detail
