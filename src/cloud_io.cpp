#include "esf/cloud_io.hpp"

#include <fcntl.h>
#include <pcl/io/lzf.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "esf/error.hpp"

namespace esf {
namespace {

// ---------------------------------------------------------------------------------------------
// Shared helpers: messages, whole-file loading, lines, tokens, numbers, typed binary values.

[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& reason) {
    throw IoError(file_message(name, line, reason));
}

/// A token as shown in a message: quoted, at most 40 characters, non-printable bytes as '?'.
std::string shown(std::string_view token) {
    constexpr std::size_t kMaxShown = 40;
    std::string out = "'";
    for (std::size_t i = 0; i < token.size() && i < kMaxShown; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
    }
    if (token.size() > kMaxShown) out += "...";
    return out + "'";
}

std::string str(std::uint64_t value) { return std::to_string(value); }

std::string errno_text(int error) {
    return std::error_code(error, std::generic_category()).message();
}

std::uint64_t checked_mul(std::uint64_t a, std::uint64_t b, const std::string& name) {
    std::uint64_t product = 0;
    if (__builtin_mul_overflow(a, b, &product)) fail(name, 0, "absurd size: data size overflows");
    return product;
}

std::uint64_t checked_add(std::uint64_t a, std::uint64_t b, const std::string& name) {
    std::uint64_t sum = 0;
    if (__builtin_add_overflow(a, b, &sum)) fail(name, 0, "absurd size: data size overflows");
    return sum;
}

/// Everything left in `in`: one read when the stream can tell its size, chunks otherwise.
std::string read_all(std::istream& in, const std::string& name) {
    std::string data;
    const std::istream::pos_type start = in.tellg();
    if (start != std::istream::pos_type(-1) && in.seekg(0, std::ios::end)) {
        const std::istream::pos_type end = in.tellg();
        in.seekg(start);
        if (end != std::istream::pos_type(-1) && end >= start && in) {
            data.resize(static_cast<std::size_t>(end - start));
            in.read(data.data(), static_cast<std::streamsize>(data.size()));
            data.resize(static_cast<std::size_t>(in.gcount()));
            if (in.bad()) fail(name, 0, "read error");
            return data;
        }
    }
    in.clear();
    if (start != std::istream::pos_type(-1)) in.seekg(start);
    std::array<char, 1 << 16> chunk{};
    while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
        data.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    }
    if (in.bad()) fail(name, 0, "read error");
    return data;
}

std::string load_file(const std::string& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status)) fail(path, 0, "no such file");
    if (std::filesystem::is_directory(status)) fail(path, 0, "is a directory, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, 0, "cannot open for reading: " + errno_text(errno));
    return read_all(in, path);
}

/// Walks `data` line by line from byte `pos`; lines lose their '\n' and a trailing '\r'.
class LineCursor {
  public:
    LineCursor(std::string_view data, std::size_t pos, std::size_t line_before)
        : data_(data), pos_(pos), line_(line_before) {}

    bool next(std::string_view& line) {
        if (pos_ >= data_.size()) return false;
        const std::size_t end = data_.find('\n', pos_);
        const std::size_t stop = end == std::string_view::npos ? data_.size() : end;
        line = data_.substr(pos_, stop - pos_);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos_ = end == std::string_view::npos ? data_.size() : end + 1;
        ++line_;
        return true;
    }
    /// 1-based number of the line last returned.
    std::size_t line() const { return line_; }
    /// First byte after the line last returned.
    std::size_t pos() const { return pos_; }

  private:
    std::string_view data_;
    std::size_t pos_;
    std::size_t line_;
};

constexpr std::string_view kSpace = " \t\r\v\f";

void split(std::string_view line, std::string_view separators, std::vector<std::string_view>& out) {
    out.clear();
    std::size_t i = 0;
    while ((i = line.find_first_not_of(separators, i)) != std::string_view::npos) {
        std::size_t j = line.find_first_of(separators, i);
        if (j == std::string_view::npos) j = line.size();
        out.push_back(line.substr(i, j - i));
        i = j;
    }
}

/// Whole-token number parse ("nan", "inf", "1e-3", a leading '+'); false on anything else.
template <class T>
bool parse(std::string_view token, T& value) {
    if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
        token.remove_prefix(1);
    }
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, value);
    return ec == std::errc() && ptr == end;
}

enum class Scalar { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64 };

std::size_t scalar_size(Scalar s) {
    switch (s) {
        case Scalar::kI8:
        case Scalar::kU8:
            return 1;
        case Scalar::kI16:
        case Scalar::kU16:
            return 2;
        case Scalar::kI32:
        case Scalar::kU32:
        case Scalar::kF32:
            return 4;
        default:
            return 8;
    }
}

/// Calls f(T{}) with the C++ type of `s`.
template <class F>
decltype(auto) visit_scalar(Scalar s, F&& f) {
    switch (s) {
        case Scalar::kI8:
            return f(std::int8_t{});
        case Scalar::kU8:
            return f(std::uint8_t{});
        case Scalar::kI16:
            return f(std::int16_t{});
        case Scalar::kU16:
            return f(std::uint16_t{});
        case Scalar::kI32:
            return f(std::int32_t{});
        case Scalar::kU32:
            return f(std::uint32_t{});
        case Scalar::kI64:
            return f(std::int64_t{});
        case Scalar::kU64:
            return f(std::uint64_t{});
        case Scalar::kF32:
            return f(float{});
        default:
            return f(double{});
    }
}

template <class T>
T load(const char* p, bool swap) {
    T value;
    if (swap) {
        std::array<char, sizeof(T)> bytes{};
        std::memcpy(bytes.data(), p, sizeof(T));
        std::reverse(bytes.begin(), bytes.end());
        std::memcpy(&value, bytes.data(), sizeof(T));
    } else {
        std::memcpy(&value, p, sizeof(T));
    }
    return value;
}

/// A label must be a non-negative integer below 2^32 (PCL stores it as uint32).
template <class T>
bool to_label(T value, std::uint32_t& label) {
    if constexpr (std::is_floating_point_v<T>) {
        if (!(value >= T(0) && value < T(4294967296.0)) || std::trunc(value) != value) return false;
    } else {
        if constexpr (std::is_signed_v<T>) {
            if (value < 0) return false;
        }
        if constexpr (sizeof(T) > 4) {
            if (static_cast<std::uint64_t>(value) > 0xffffffffULL) return false;
        }
    }
    label = static_cast<std::uint32_t>(value);
    return true;
}

/// points[i][axis] = the value of type `type` at src + i * stride, for every point.
void read_axis(const char* src, std::size_t stride, Scalar type, bool swap, Points& points,
               int axis) {
    visit_scalar(type, [&](auto tag) {
        using T = decltype(tag);
        for (std::size_t i = 0; i < points.size(); ++i) {
            points[i][axis] = static_cast<float>(load<T>(src + i * stride, swap));
        }
    });
}

void read_labels(const char* src, std::size_t stride, Scalar type, bool swap,
                 std::vector<std::uint32_t>& labels, const std::string& name) {
    visit_scalar(type, [&](auto tag) {
        using T = decltype(tag);
        for (std::size_t i = 0; i < labels.size(); ++i) {
            if (!to_label(load<T>(src + i * stride, swap), labels[i])) {
                fail(name, 0, "point " + str(i) + ": label is not an integer in [0, 2^32)");
            }
        }
    });
}

/// Parses an ascii value of a field of type `type` into a coordinate.
bool parse_coordinate(std::string_view token, Scalar type, float& value) {
    if (type == Scalar::kF32) return parse(token, value);
    double wide = 0.0;
    if (!parse(token, wide)) return false;
    value = static_cast<float>(wide);
    return true;
}

bool parse_label(std::string_view token, std::uint32_t& label) {
    double value = 0.0;
    return parse(token, value) && to_label(value, label);
}

constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

// ---------------------------------------------------------------------------------------------
// LZF, the compression of PCD binary_compressed (liblzf's format, as in pcl/io/lzf.h).

/// Longest output of one LZF token per input byte: a 3-byte back reference yields 264 bytes.
constexpr std::uint64_t kLzfMaxRatio = 88;

/// Decodes an LZF block into out[0, out_len); returns the bytes written. Bounds are checked on
/// every token, so corrupt input throws instead of reading or writing out of range.
std::size_t lzf_decompress(const unsigned char* in, std::size_t in_len, unsigned char* out,
                           std::size_t out_len, const std::string& name) {
    const unsigned char* ip = in;
    const unsigned char* const in_end = in + in_len;
    unsigned char* op = out;
    unsigned char* const out_end = out + out_len;
    auto corrupt = [&](const char* why) {
        fail(name, 0,
             std::string("corrupt LZF data in binary_compressed block: ") + why +
                 " (compressed byte " + str(static_cast<std::uint64_t>(ip - in)) + ")");
    };
    while (ip < in_end) {
        const std::size_t ctrl = *ip++;
        if (ctrl < 32) {  // literal run of ctrl + 1 bytes
            const std::size_t len = ctrl + 1;
            if (static_cast<std::size_t>(in_end - ip) < len) corrupt("literal run past the end");
            if (static_cast<std::size_t>(out_end - op) < len) corrupt("output exceeds stated size");
            std::memcpy(op, ip, len);
            op += len;
            ip += len;
            continue;
        }
        std::size_t len = ctrl >> 5;  // back reference of len + 2 bytes
        if (ip >= in_end) corrupt("back reference cut off");
        if (len == 7) {
            len += *ip++;
            if (ip >= in_end) corrupt("back reference cut off");
        }
        const std::size_t distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
        len += 2;
        if (distance > static_cast<std::size_t>(op - out)) {
            corrupt("back reference before the start of the output");
        }
        if (static_cast<std::size_t>(out_end - op) < len) corrupt("output exceeds stated size");
        const unsigned char* ref = op - distance;
        if (distance >= len) {
            std::memcpy(op, ref, len);
            op += len;
        } else {
            for (std::size_t k = 0; k < len; ++k) *op++ = *ref++;
        }
    }
    return static_cast<std::size_t>(op - out);
}

// ---------------------------------------------------------------------------------------------
// PCD

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

struct PcdField {
    std::string name;
    std::uint64_t size = 4;  // bytes per value
    char type = 'F';
    std::uint64_t count = 1;  // values per point
    std::uint64_t bytes() const { return size * count; }
    bool padding() const { return name == "_"; }
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
};

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

/// Reads the header up to and including the DATA line, checks it and settles width, height and
/// points the way PCL does for older files (no WIDTH/HEIGHT: width = POINTS, height = 1).
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
                if (!parse(values[i], v) || v == 0) {
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
            if (!parse(value, v)) bad("expected an integer in [0, 2^32), got " + shown(value));
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
            if (!parse(value, v)) bad("expected a non-negative integer, got " + shown(value));
            points = v;
            points_line = ln;
            continue;
        }
        if (key == "VIEWPOINT") {
            double v = 0.0;
            if (values.size() != 7) bad("expected 7 values (tx ty tz qw qx qy qz)");
            for (const auto value : values) {
                if (!parse(value, v)) bad("not a number: " + shown(value));
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

/// Index of the first field called `name` (fields x, y, z exist: the header checked them).
std::optional<std::size_t> find_field(const std::vector<PcdField>& fields, std::string_view name) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i].name == name) return i;
    }
    return std::nullopt;
}

struct PcdColumns {
    std::array<std::size_t, 3> xyz{};
    std::optional<std::size_t> label;
};

PcdColumns pcd_columns(const PcdHeader& h) {
    PcdColumns c;
    c.xyz = {*find_field(h.fields, "x"), *find_field(h.fields, "y"), *find_field(h.fields, "z")};
    c.label = find_field(h.fields, "label");
    return c;
}

Scalar field_scalar(const PcdField& f) { return *pcd_scalar(f.type, f.size); }

void read_pcd_ascii(std::string_view data, const PcdHeader& h, const std::string& name,
                    PointCloud& cloud) {
    const PcdColumns cols = pcd_columns(h);
    // Token index of each field: every value (padding '_' included) is one token.
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
    if (cols.label) cloud.labels.resize(n);

    LineCursor cursor(data, h.data_pos, h.data_line);
    std::vector<std::string_view> tok;
    std::string_view line;
    std::uint64_t i = 0;
    while (cursor.next(line)) {
        split(line, kSpace, tok);
        if (tok.empty()) continue;
        const std::size_t ln = cursor.line();
        if (i == n) fail(name, ln, "more data lines than POINTS (" + str(n) + ")");
        if (tok.size() < values) {
            fail(name, ln, "expected " + str(values) + " values, got " + str(tok.size()));
        }
        for (int axis = 0; axis < 3; ++axis) {
            const std::size_t f = cols.xyz[static_cast<std::size_t>(axis)];
            const std::string_view token = tok[first_token[f]];
            if (!parse_coordinate(token, field_scalar(h.fields[f]), cloud.points[i][axis])) {
                fail(name, ln,
                     "not a number: " + shown(token) + " (field " + shown(h.fields[f].name) + ")");
            }
        }
        if (cols.label) {
            const std::string_view token = tok[first_token[*cols.label]];
            if (!parse_label(token, cloud.labels[i])) {
                fail(name, ln, "label is not an integer in [0, 2^32): " + shown(token));
            }
        }
        ++i;
    }
    if (i < n) {
        fail(name, cursor.line(),
             "truncated: expected " + str(n) + " points of ascii data, got " + str(i));
    }
}

/// Reads x, y, z (and label) from fields laid out one after another: AoS (binary, stride =
/// point size) or SoA (decompressed binary_compressed, one block per field).
void read_pcd_columns(const char* base, const PcdHeader& h, const std::vector<std::uint64_t>& start,
                      const std::vector<std::uint64_t>& stride, const std::string& name,
                      PointCloud& cloud) {
    const PcdColumns cols = pcd_columns(h);
    const bool swap = !kLittleEndianHost;
    cloud.points.resize(h.points);
    for (int axis = 0; axis < 3; ++axis) {
        const std::size_t f = cols.xyz[static_cast<std::size_t>(axis)];
        read_axis(base + start[f], stride[f], field_scalar(h.fields[f]), swap, cloud.points, axis);
    }
    if (cols.label) {
        cloud.labels.resize(h.points);
        const std::size_t f = *cols.label;
        read_labels(base + start[f], stride[f], field_scalar(h.fields[f]), swap, cloud.labels,
                    name);
    }
}

void read_pcd_binary(std::string_view data, const PcdHeader& h, const std::string& name,
                     PointCloud& cloud) {
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
    if (available < need) {
        fail(name, 0,
             "truncated: expected " + str(need) + " bytes of binary data, got " + str(available));
    }
    read_pcd_columns(data.data() + h.data_pos, h, start, stride, name, cloud);
}

void read_pcd_compressed(std::string_view data, const PcdHeader& h, const std::string& name,
                         PointCloud& cloud) {
    const std::uint64_t available = data.size() - h.data_pos;
    const char* base = data.data() + h.data_pos;
    if (available < 8) {
        fail(name, 0, "truncated: expected 8 bytes of binary data, got " + str(available));
    }
    const std::uint64_t compressed = load<std::uint32_t>(base, !kLittleEndianHost);
    const std::uint64_t uncompressed = load<std::uint32_t>(base + 4, !kLittleEndianHost);
    if (available - 8 < compressed) {
        fail(name, 0,
             "truncated: expected " + str(compressed + 8) + " bytes of binary data, got " +
                 str(available));
    }
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
    const std::size_t size = static_cast<std::size_t>(uncompressed);
    auto buffer = std::make_unique_for_overwrite<char[]>(std::max<std::size_t>(size, 1));
    const std::size_t produced = lzf_decompress(
        reinterpret_cast<const unsigned char*>(base + 8), static_cast<std::size_t>(compressed),
        reinterpret_cast<unsigned char*>(buffer.get()), size, name);
    if (produced != size) {
        fail(name, 0,
             "corrupt binary_compressed data: decompressed to " + str(produced) +
                 " bytes, expected " + str(uncompressed));
    }
    std::vector<std::uint64_t> start(h.fields.size()), stride(h.fields.size());
    std::uint64_t offset = 0;
    for (std::size_t f = 0; f < h.fields.size(); ++f) {
        stride[f] = h.fields[f].bytes();
        start[f] = offset;
        if (keep_padding || !h.fields[f].padding()) offset += h.points * stride[f];
    }
    read_pcd_columns(buffer.get(), h, start, stride, name, cloud);
}

PointCloud parse_pcd(std::string_view data, const std::string& name) {
    if (data.empty()) fail(name, 0, "empty file");
    const PcdHeader h = parse_pcd_header(data, name);
    PointCloud cloud;
    cloud.width = h.width;
    cloud.height = h.height;
    switch (h.data) {
        case PcdData::kAscii:
            read_pcd_ascii(data, h, name, cloud);
            break;
        case PcdData::kBinary:
            read_pcd_binary(data, h, name, cloud);
            break;
        case PcdData::kBinaryCompressed:
            read_pcd_compressed(data, h, name, cloud);
            break;
    }
    return cloud;
}

// ---------------------------------------------------------------------------------------------
// PLY (point clouds: the vertex element's x, y, z and an optional label)

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

struct PlyProperty {
    std::string name;
    Scalar type = Scalar::kF32;
    bool is_list = false;
    Scalar count_type = Scalar::kU8;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    std::size_t line = 0;

    bool has_list() const {
        return std::any_of(properties.begin(), properties.end(),
                           [](const PlyProperty& p) { return p.is_list; });
    }
    /// Bytes per item in binary; only meaningful without list properties.
    std::uint64_t stride() const {
        std::uint64_t s = 0;
        for (const auto& p : properties) s += scalar_size(p.type);
        return s;
    }
};

struct PlyHeader {
    PlyFormat format = PlyFormat::kAscii;
    std::vector<PlyElement> elements;
    std::size_t data_pos = 0;
    std::size_t data_line = 0;  // line number of end_header
};

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

PlyHeader parse_ply_header(std::string_view data, const std::string& name) {
    PlyHeader h;
    LineCursor cursor(data, 0, 0);
    std::vector<std::string_view> tok;
    std::string_view line;
    if (!cursor.next(line)) fail(name, 1, "not a PLY file (no 'ply' line)");
    split(line, kSpace, tok);
    if (tok.size() != 1 || tok[0] != "ply") fail(name, 1, "not a PLY file (no 'ply' line)");
    bool have_format = false;
    while (cursor.next(line)) {
        const std::size_t ln = cursor.line();
        split(line, kSpace, tok);
        if (tok.empty()) continue;
        const std::string key(tok[0]);
        auto bad = [&](const std::string& why) {
            fail(name, ln, "bad header: " + key + ": " + why);
        };
        if (key == "comment" || key == "obj_info") continue;
        if (key == "format") {
            if (tok.size() != 3) bad("expected 'format <type> 1.0'");
            if (tok[1] == "ascii") {
                h.format = PlyFormat::kAscii;
            } else if (tok[1] == "binary_little_endian") {
                h.format = PlyFormat::kBinaryLittle;
            } else if (tok[1] == "binary_big_endian") {
                h.format = PlyFormat::kBinaryBig;
            } else {
                bad("unknown format " + shown(tok[1]));
            }
            have_format = true;
            continue;
        }
        if (key == "element") {
            std::uint64_t count = 0;
            if (tok.size() != 3) bad("expected 'element <name> <count>'");
            if (!parse(tok[2], count)) bad("count is not a non-negative integer: " + shown(tok[2]));
            h.elements.push_back(PlyElement{
                .name = std::string(tok[1]), .count = count, .properties = {}, .line = ln});
            continue;
        }
        if (key == "property") {
            if (h.elements.empty()) bad("comes before any element");
            PlyProperty p;
            if (tok.size() >= 2 && tok[1] == "list") {
                if (tok.size() != 5)
                    bad("expected 'property list <count type> <item type> <name>'");
                const auto count_type = ply_scalar(tok[2]);
                const auto type = ply_scalar(tok[3]);
                if (!count_type || *count_type == Scalar::kF32 || *count_type == Scalar::kF64) {
                    bad("list count type must be an integer type, got " + shown(tok[2]));
                }
                if (!type) bad("unknown type " + shown(tok[3]));
                p = PlyProperty{std::string(tok[4]), *type, true, *count_type};
            } else {
                if (tok.size() != 3) bad("expected 'property <type> <name>'");
                const auto type = ply_scalar(tok[1]);
                if (!type) bad("unknown type " + shown(tok[1]));
                p = PlyProperty{.name = std::string(tok[2]), .type = *type};
            }
            h.elements.back().properties.push_back(p);
            continue;
        }
        if (key == "end_header") {
            if (!have_format) bad("no format line before end_header");
            h.data_pos = cursor.pos();
            h.data_line = ln;
            return h;
        }
        fail(name, ln, "bad header: unknown keyword " + shown(key));
    }
    fail(name, cursor.line(), "bad header: no end_header line");
}

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
            // Fixed stride: check the whole block once, then read column by column.
            const std::uint64_t stride = e.stride();
            require(checked_mul(e.count, stride, name_), e, std::nullopt);
            cloud.points.resize(e.count);
            std::uint64_t offset = 0;
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const char* src = data_.data() + pos_ + offset;
                const Scalar type = e.properties[k].type;
                if (roles[k] >= 0 && roles[k] < 3) {
                    read_axis(src, stride, type, swap_, cloud.points, roles[k]);
                } else if (roles[k] == 3) {
                    cloud.labels.resize(e.count);
                    read_labels(src, stride, type, swap_, cloud.labels, name_);
                }
                offset += scalar_size(type);
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
                    if (!parse(token, length)) {
                        fail(name, cursor.line(),
                             "list length is not a non-negative integer: " + shown(token) + " (" +
                                 where() + ")");
                    }
                    for (std::uint64_t j = 0; j < length; ++j) next();
                } else if (roles[k] >= 0 && roles[k] < 3) {
                    if (!parse_coordinate(token, p.type, cloud.points[i][roles[k]])) {
                        fail(name, cursor.line(),
                             "not a number: " + shown(token) + " (" + where() + ")");
                    }
                } else if (roles[k] == 3) {
                    if (!parse_label(token, cloud.labels[i])) {
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

PointCloud parse_ply(std::string_view data, const std::string& name) {
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

// ---------------------------------------------------------------------------------------------
// Plain text

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
            if (!parse(tok[static_cast<std::size_t>(axis)], p[axis])) {
                fail(name, cursor.line(),
                     "not a number: " + shown(tok[static_cast<std::size_t>(axis)]));
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

// ---------------------------------------------------------------------------------------------
// PCD writing

template <class T>
void put_le(char* out, T value) {
    std::memcpy(out, &value, sizeof(T));
    if constexpr (!kLittleEndianHost) std::reverse(out, out + sizeof(T));
}

void append_float(std::string& out, float value) {
    if (std::isnan(value)) {
        out += "nan";
        return;
    }
    std::array<char, 32> buf{};
    const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), value);
    out.append(buf.data(), result.ptr);
}

std::string encode_pcd(const PointCloud& cloud, PcdEncoding encoding) {
    const std::size_t n = cloud.points.size();
    const bool with_labels = !cloud.labels.empty();
    if (with_labels && cloud.labels.size() != n) {
        throw std::invalid_argument("write_pcd: " + str(cloud.labels.size()) + " labels for " +
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
    std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
    out += with_labels ? "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
                       : "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    out += "WIDTH " + str(width) + "\nHEIGHT " + str(height) +
           "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + str(n) + "\n";
    const std::size_t fields = with_labels ? 4 : 3;
    const std::size_t point_step = 4 * fields;

    if (encoding == PcdEncoding::kAscii) {
        out += "DATA ascii\n";
        out.reserve(out.size() + n * 12 * fields);
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3f& p = cloud.points[i];
            append_float(out, p.x());
            out += ' ';
            append_float(out, p.y());
            out += ' ';
            append_float(out, p.z());
            if (with_labels) out += ' ' + str(cloud.labels[i]);
            out += '\n';
        }
        return out;
    }
    if (encoding == PcdEncoding::kBinary) {
        out += "DATA binary\n";
        std::size_t pos = out.size();
        out.resize(pos + n * point_step);
        for (std::size_t i = 0; i < n; ++i, pos += point_step) {
            for (int axis = 0; axis < 3; ++axis) {
                put_le(out.data() + pos + 4 * static_cast<std::size_t>(axis),
                       cloud.points[i][axis]);
            }
            if (with_labels) put_le(out.data() + pos + 12, cloud.labels[i]);
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
    std::vector<char> raw(static_cast<std::size_t>(raw_size));
    for (std::size_t i = 0; i < n; ++i) {
        for (int axis = 0; axis < 3; ++axis) {
            put_le(raw.data() + 4 * (static_cast<std::size_t>(axis) * n + i),
                   cloud.points[i][axis]);
        }
        if (with_labels) put_le(raw.data() + 4 * (3 * n + i), cloud.labels[i]);
    }
    std::vector<char> packed(raw.size() + raw.size() / 16 + 64);
    unsigned int packed_size = 0;
    if (!raw.empty()) {
        packed_size = pcl::lzfCompress(raw.data(), static_cast<unsigned int>(raw.size()),
                                       packed.data(), static_cast<unsigned int>(packed.size()));
        if (packed_size == 0) throw IoError("write_pcd: LZF compression failed");
    }
    std::array<char, 8> sizes{};
    put_le(sizes.data(), static_cast<std::uint32_t>(packed_size));
    put_le(sizes.data() + 4, static_cast<std::uint32_t>(raw.size()));
    out.append(sizes.data(), sizes.size());
    out.append(packed.data(), packed_size);
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Public API

CloudFormat cloud_format_from_path(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".pcd") return CloudFormat::kPcd;
    if (ext == ".ply") return CloudFormat::kPly;
    if (ext == ".xyz" || ext == ".txt" || ext == ".pts") return CloudFormat::kXyz;
    fail(path, 0, "unknown point cloud format (expected .pcd, .ply, .xyz, .txt or .pts)");
}

PointCloud read_cloud(const std::string& path) {
    switch (cloud_format_from_path(path)) {
        case CloudFormat::kPcd:
            return read_pcd(path);
        case CloudFormat::kPly:
            return read_ply_cloud(path);
        case CloudFormat::kXyz:
            break;
    }
    return read_xyz(path);
}

PointCloud read_pcd(const std::string& path) { return parse_pcd(load_file(path), path); }

PointCloud read_pcd(std::istream& in, const std::string& name) {
    return parse_pcd(read_all(in, name), name);
}

PointCloud read_ply_cloud(const std::string& path) { return parse_ply(load_file(path), path); }

PointCloud read_ply_cloud(std::istream& in, const std::string& name) {
    return parse_ply(read_all(in, name), name);
}

PointCloud read_xyz(const std::string& path) { return parse_xyz(load_file(path), path); }

PointCloud read_xyz(std::istream& in, const std::string& name) {
    return parse_xyz(read_all(in, name), name);
}

void write_pcd(std::ostream& out, const PointCloud& cloud, PcdEncoding encoding) {
    const std::string bytes = encode_pcd(cloud, encoding);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError("write_pcd: writing to the output stream failed");
}

void write_pcd(const std::string& path, const PointCloud& cloud, PcdEncoding encoding) {
    const std::string bytes = encode_pcd(cloud, encoding);
    // A fresh temporary beside the target (O_EXCL: concurrent writers never share one), then an
    // atomic rename over the target.
    std::string tmp;
    int fd = -1;
    int error = 0;
    for (int attempt = 0; attempt < 1000 && fd < 0; ++attempt) {
        tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(attempt);
        fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        error = errno;
        if (fd < 0 && error != EEXIST) break;
    }
    if (fd < 0) fail(path, 0, "cannot create temporary file " + tmp + ": " + errno_text(error));
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t written = ::write(fd, p, left);
        if (written < 0) {
            if (errno == EINTR) continue;
            error = errno;
            ::close(fd);
            ::unlink(tmp.c_str());
            fail(path, 0, "write failed: " + errno_text(error));
        }
        p += written;
        left -= static_cast<std::size_t>(written);
    }
    if (::close(fd) != 0) {
        error = errno;
        ::unlink(tmp.c_str());
        fail(path, 0, "write failed: " + errno_text(error));
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        ::unlink(tmp.c_str());
        fail(path, 0, "cannot replace the file: " + ec.message());
    }
}

}  // namespace esf
