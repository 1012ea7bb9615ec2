#pragma once
// The header of a PCD file (PCL's format, versions 0.5 to 0.7): fields, layout, data encoding.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/cloud_io_detail.hpp"

namespace esf::detail {

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

struct PcdField {
    std::string name;
    std::uint64_t size = 4;  // bytes per value
    char type = 'F';
    std::uint64_t count = 1;  // values per point
    std::uint64_t bytes() const { return size * count; }
    bool padding() const { return name == "_"; }
    Scalar scalar() const;
};

struct PcdHeader {
    std::vector<PcdField> fields;
    std::uint32_t width = 0;
    std::uint32_t height = 1;
    std::uint64_t points = 0;
    PcdData data = PcdData::kAscii;
    std::size_t data_pos = 0;   // first byte after the DATA line
    std::size_t data_line = 0;  // line number of the DATA line
    std::size_t fields_line = 0;
    std::size_t type_line = 0;
    // Indices into `fields` of x, y, z (always present: the parser checks) and of `label`.
    std::size_t x = 0, y = 0, z = 0;
    std::optional<std::size_t> label;
};

/// Reads the header up to and including the DATA line and checks it: known keywords, SIZE, TYPE
/// and COUNT per field, fields x, y, z of COUNT 1, POINTS = WIDTH x HEIGHT. Settles width, height
/// and points the way PCL does for older files (no WIDTH/HEIGHT: width = POINTS, height = 1).
/// Throws IoError "name:line: bad header: KEY: ...".
PcdHeader parse_pcd_header(std::string_view data, const std::string& name);

}  // namespace esf::detail
