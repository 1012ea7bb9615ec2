#include "io/pcd_header.hpp"

#include <algorithm>
#include <limits>
#include <span>

#include "core/number_text.hpp"

namespace esf::detail {

namespace {

std::optional<Scalar> pcd_scalar(char type, std::uint64_t size) {
    if (type == 'F') {
        if (size == 4) return Scalar::kF32;
        if (size == 8) return Scalar::kF64;
        return std::nullopt;
    }
    const bool is_signed = type == 'I';
    switch (size) {
        case 1:
            return is_signed ? Scalar::kI8 : Scalar::kU8;
        case 2:
            return is_signed ? Scalar::kI16 : Scalar::kU16;
        case 4:
            return is_signed ? Scalar::kI32 : Scalar::kU32;
        case 8:
            return is_signed ? Scalar::kI64 : Scalar::kU64;
        default:
            return std::nullopt;
    }
}

}  // namespace

Scalar PcdField::scalar() const { return *pcd_scalar(type, size); }

PcdHeader parse_pcd_header(std::string_view data, const std::string& name) {
    PcdHeader h;
    LineCursor cursor(data, 0, 0);
    std::vector<std::string_view> tok;
    std::string_view line;
    bool have_fields = false;
    std::optional<std::uint32_t> width, height;
    std::optional<std::uint64_t> points;
    std::size_t width_line = 0, points_line = 0;
    while (cursor.next(line)) {
        const std::size_t ln = cursor.line();
        split(line, kSpace, tok);
        if (tok.empty() || tok[0][0] == '#') continue;
        const std::string key(tok[0]);
        const std::span<const std::string_view> values = std::span(tok).subspan(1);
        auto bad = [&](const std::string& why) {
            fail(name, ln, "bad header: " + key + ": " + why);
        };
        auto one_value = [&]() -> std::string_view {
            if (values.size() != 1) bad("expected one value, got " + str(values.size()));
            return values[0];
        };
        if (key == "VERSION") continue;
        if (key == "FIELDS" || key == "COLUMNS") {
            if (values.empty()) bad("no field names");
            h.fields.clear();
            for (const auto v : values) h.fields.push_back(PcdField{.name = std::string(v)});
            have_fields = true;
            h.fields_line = ln;
            continue;
        }
        if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
            if (!have_fields) bad("comes before FIELDS");
            if (values.size() != h.fields.size()) {
                bad(str(values.size()) + " entries for " + str(h.fields.size()) + " FIELDS");
            }
            for (std::size_t i = 0; i < values.size(); ++i) {
                if (key == "TYPE") {
                    if (values[i] != "F" && values[i] != "U" && values[i] != "I") {
                        bad("unknown type " + shown(values[i]) + " (expected F, U or I)");
                    }
                    h.fields[i].type = values[i][0];
                    continue;
                }
                std::uint64_t v = 0;
                if (!parse_integer(values[i], v) || v == 0) {
                    bad("expected a positive integer, got " + shown(values[i]));
                }
                if (key == "SIZE") {
                    if (v != 1 && v != 2 && v != 4 && v != 8) {
                        bad("size must be 1, 2, 4 or 8, got " + str(v));
                    }
                    h.fields[i].size = v;
                } else {
                    h.fields[i].count = v;
                }
            }
            if (key == "TYPE") h.type_line = ln;
            continue;
        }
        if (key == "WIDTH" || key == "HEIGHT") {
            std::uint32_t v = 0;
            const std::string_view value = one_value();
            if (!parse_integer(value, v))
                bad("expected an integer in [0, 2^32), got " + shown(value));
            if (key == "WIDTH") {
                width = v;
                width_line = ln;
            } else {
                if (v == 0) bad("must be at least 1");
                height = v;
            }
            continue;
        }
        if (key == "POINTS") {
            std::uint64_t v = 0;
            const std::string_view value = one_value();
            if (!parse_integer(value, v))
                bad("expected a non-negative integer, got " + shown(value));
            points = v;
            points_line = ln;
            continue;
        }
        if (key == "VIEWPOINT") {
            double v = 0.0;
            if (values.size() != 7) bad("expected 7 values (tx ty tz qw qx qy qz)");
            for (const auto value : values) {
                if (!parse_double(value, v)) bad("not a number: " + shown(value));
            }
            continue;
        }
        if (key == "DATA") {
            const std::string_view value = one_value();
            if (value == "ascii") {
                h.data = PcdData::kAscii;
            } else if (value == "binary") {
                h.data = PcdData::kBinary;
            } else if (value == "binary_compressed") {
                h.data = PcdData::kBinaryCompressed;
            } else {
                fail(name, ln,
                     "unknown DATA type " + shown(value) +
                         " (expected ascii, binary or binary_compressed)");
            }
            if (!have_fields) bad("no FIELDS line before DATA");
            h.data_pos = cursor.pos();
            h.data_line = ln;

            // Sizes: PCL's rules for files without WIDTH, HEIGHT or POINTS.
            if (!points && !width) bad("no POINTS and no WIDTH before DATA");
            if (!width) {
                if (height && *height != 1) bad("HEIGHT given without WIDTH");
                if (*points > std::numeric_limits<std::uint32_t>::max()) {
                    fail(name, points_line, "bad header: POINTS: too many points for WIDTH");
                }
                width = static_cast<std::uint32_t>(*points);
                width_line = points_line;
            }
            h.width = *width;
            h.height = height.value_or(1);
            const std::uint64_t grid = std::uint64_t{h.width} * h.height;
            h.points = points.value_or(grid);
            if (h.points != grid) {
                fail(name, points_line != 0 ? points_line : width_line,
                     "bad header: POINTS " + str(h.points) + " does not equal WIDTH x HEIGHT = " +
                         str(h.width) + " x " + str(h.height));
            }

            // Field types and the ones we read.
            for (const auto& f : h.fields) {
                if (!pcd_scalar(f.type, f.size)) {
                    fail(name, h.type_line != 0 ? h.type_line : h.fields_line,
                         "bad header: TYPE: field " + shown(f.name) + " has TYPE " +
                             std::string(1, f.type) + " with SIZE " + str(f.size));
                }
            }
            for (const char* wanted : {"x", "y", "z", "label"}) {
                const auto it = std::find_if(h.fields.begin(), h.fields.end(),
                                             [&](const PcdField& f) { return f.name == wanted; });
                if (it == h.fields.end()) {
                    if (std::string_view(wanted) == "label") continue;
                    fail(name, h.fields_line,
                         "bad header: FIELDS: no field named " + shown(wanted));
                }
                const auto index = static_cast<std::size_t>(it - h.fields.begin());
                switch (wanted[0]) {
                    case 'x':
                        h.x = index;
                        break;
                    case 'y':
                        h.y = index;
                        break;
                    case 'z':
                        h.z = index;
                        break;
                    default:
                        h.label = index;
                }
                if (it->count != 1) {
                    fail(name, h.fields_line,
                         "bad header: COUNT: field " + shown(wanted) + " has COUNT " +
                             str(it->count) + ", expected 1");
                }
            }
            return h;
        }
        fail(name, ln, "bad header: unknown keyword " + shown(key));
    }
    fail(name, cursor.line(), "bad header: no DATA line");
}

}  // namespace esf::detail
