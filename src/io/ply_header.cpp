#include "io/ply_header.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "core/number_text.hpp"

namespace esf::detail {

namespace {

std::optional<Scalar> ply_scalar(std::string_view t) {
    if (t == "char" || t == "int8") return Scalar::kI8;
    if (t == "uchar" || t == "uint8") return Scalar::kU8;
    if (t == "short" || t == "int16") return Scalar::kI16;
    if (t == "ushort" || t == "uint16") return Scalar::kU16;
    if (t == "int" || t == "int32") return Scalar::kI32;
    if (t == "uint" || t == "uint32") return Scalar::kU32;
    if (t == "float" || t == "float32") return Scalar::kF32;
    if (t == "double" || t == "float64") return Scalar::kF64;
    return std::nullopt;
}

}  // namespace

bool PlyElement::has_list() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& p) { return p.is_list; });
}

std::uint64_t PlyElement::stride() const {
    std::uint64_t s = 0;
    for (const auto& p : properties) s += scalar_size(p.type);
    return s;
}

PlyHeader read_ply_header(std::string_view data) {
    PlyHeader h;
    const auto problem = [&h](std::size_t line, const std::string& why) {
        if (!h.problem.empty()) return;
        h.problem_line = line;
        h.problem = why;
    };
    LineCursor cursor(data, 0, 0);
    std::vector<std::string_view> tok;
    std::string_view line;
    if (cursor.next(line)) split(line, kSpace, tok);
    h.is_ply = tok.size() == 1 && (tok[0] == "ply" || tok[0] == "PLY");
    if (!h.is_ply || tok[0] != "ply") problem(1, "not a PLY file (no 'ply' line)");
    if (!h.is_ply) return h;
    bool have_format = false;
    while (cursor.next(line)) {
        const std::size_t ln = cursor.line();
        split(line, kSpace, tok);
        if (tok.empty()) continue;
        const std::string key(tok[0]);
        const auto bad = [&](const std::string& why) {
            problem(ln, "bad header: " + key + ": " + why);
        };
        if (key == "comment" || key == "obj_info") continue;
        if (key == "format") {
            if (tok.size() != 3) bad("expected 'format <type> 1.0'");
            const std::string_view format = tok.size() > 1 ? tok[1] : std::string_view();
            if (format == "ascii") {
                h.format = PlyFormat::kAscii;
            } else if (format == "binary_little_endian") {
                h.format = PlyFormat::kBinaryLittle;
            } else if (format == "binary_big_endian") {
                h.format = PlyFormat::kBinaryBig;
            } else {
                bad("unknown format " + shown(format));
                h.format =
                    format.starts_with("binary") ? PlyFormat::kBinaryLittle : PlyFormat::kAscii;
            }
            have_format = true;
            continue;
        }
        if (key == "element") {
            if (tok.size() != 3) bad("expected 'element <name> <count>'");
            PlyElement e;
            e.name = tok.size() > 1 ? std::string(tok[1]) : std::string();
            e.line = ln;
            e.written_count = std::numeric_limits<double>::quiet_NaN();
            if (tok.size() > 2 && parse_integer(tok[2], e.count)) {
                e.written_count = static_cast<double>(e.count);
            } else {
                if (tok.size() > 2) {
                    bad("count is not a non-negative integer: " + shown(tok[2]));
                    double number = 0.0;
                    if (parse_double(tok[2], number)) e.written_count = number;
                }
            }
            h.elements.push_back(std::move(e));
            continue;
        }
        if (key == "property") {
            if (h.elements.empty()) {
                bad("comes before any element");
                continue;
            }
            PlyProperty p;
            if (tok.size() >= 2 && tok[1] == "list") {
                if (tok.size() != 5)
                    bad("expected 'property list <count type> <item type> <name>'");
                const auto count_type = tok.size() > 2 ? ply_scalar(tok[2]) : std::nullopt;
                const auto type = tok.size() > 3 ? ply_scalar(tok[3]) : std::nullopt;
                if (tok.size() > 2 &&
                    (!count_type || *count_type == Scalar::kF32 || *count_type == Scalar::kF64))
                    bad("list count type must be an integer type, got " + shown(tok[2]));
                if (tok.size() > 3 && !type) bad("unknown type " + shown(tok[3]));
                p.is_list = true;
                p.known_type = count_type && type;
                if (count_type) p.count_type = *count_type;
                if (type) p.type = *type;
                if (tok.size() > 4) p.name = std::string(tok[4]);
            } else {
                if (tok.size() != 3) bad("expected 'property <type> <name>'");
                const auto type = tok.size() > 1 ? ply_scalar(tok[1]) : std::nullopt;
                if (tok.size() > 1 && !type) bad("unknown type " + shown(tok[1]));
                p.known_type = type.has_value();
                if (type) p.type = *type;
                if (tok.size() > 2) p.name = std::string(tok[2]);
            }
            h.elements.back().properties.push_back(std::move(p));
            continue;
        }
        if (key == "end_header") {
            if (!have_format) bad("no format line before end_header");
            h.ended = true;
            h.data_pos = cursor.pos();
            h.data_line = ln;
            return h;
        }
        problem(ln, "bad header: unknown keyword " + shown(key));
    }
    problem(cursor.line(), "bad header: no end_header line");
    return h;
}

PlyHeader parse_ply_header(std::string_view data, const std::string& name) {
    PlyHeader h = read_ply_header(data);
    if (!h.problem.empty()) fail(name, h.problem_line, h.problem);
    return h;
}

}  // namespace esf::detail
