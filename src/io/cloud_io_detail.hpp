#pragma once
// Helpers shared by the point-cloud readers and writers (pcd_*.cpp, ply_cloud_io.cpp,
// xyz_cloud_io.cpp): messages, whole files in memory, lines and tokens, typed binary columns.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "esf/core/point_cloud.hpp"

namespace esf::detail {

// ---------------------------------------------------------------------------------------------
// Messages and sizes

/// Throws esf::IoError "name[:line]: reason".
[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& reason);

/// A token as shown in a message: quoted, at most 40 characters, non-printable bytes as '?'.
std::string shown(std::string_view token);

inline std::string str(std::uint64_t value) { return std::to_string(value); }

std::string errno_text(int error);

/// a * b and a + b, or an IoError "absurd size" naming `name` when they overflow 64 bits.
std::uint64_t checked_mul(std::uint64_t a, std::uint64_t b, const std::string& name);
std::uint64_t checked_add(std::uint64_t a, std::uint64_t b, const std::string& name);

// ---------------------------------------------------------------------------------------------
// Whole files

/// The bytes of a whole file, read once into a buffer that is never zero-filled first.
struct FileBytes {
    std::unique_ptr<char[]> data;
    std::size_t size = 0;
    std::string_view view() const { return {data.get(), size}; }
};

/// A regular file open for reading, and its size when opened: a directory, FIFO, socket or
/// device is refused (checked with stat before opening and with fstat on the descriptor, opened
/// non-blocking), so that no reader ever blocks on a pipe or reads an endless device.
class RegularFile {
  public:
    explicit RegularFile(const std::string& path);
    ~RegularFile();
    RegularFile(const RegularFile&) = delete;
    RegularFile& operator=(const RegularFile&) = delete;

    std::size_t size() const { return size_; }
    /// Reads up to `n` bytes into `out` from where the last read stopped; fewer only where the
    /// file ends (it may have shrunk since it was opened).
    std::size_t read(char* out, std::size_t n);

  private:
    std::string path_;
    int fd_ = -1;
    std::size_t size_ = 0;
};

/// Reads the whole of `path`, which must be a regular file (see RegularFile).
FileBytes read_regular_file(const std::string& path);

/// Everything left in `in`: one read when the stream can tell its size, chunks otherwise.
std::string read_all(std::istream& in, const std::string& name);

// ---------------------------------------------------------------------------------------------
// Lines and tokens

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

inline constexpr std::string_view kSpace = " \t\r\v\f";

/// The non-empty pieces of `line` between any of `separators`.
void split(std::string_view line, std::string_view separators, std::vector<std::string_view>& out);

/// Whole-token integer parse (a leading '+' allowed); false on anything else.
template <class T>
bool parse_integer(std::string_view token, T& value) {
    static_assert(std::is_integral_v<T>);
    if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
        token.remove_prefix(1);
    }
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, value);
    return ec == std::errc() && ptr == end;
}

// ---------------------------------------------------------------------------------------------
// Typed binary values

enum class Scalar { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64 };

std::size_t scalar_size(Scalar s);

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

inline constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

template <class T, bool kSwap>
T load(const char* p) {
    T value;
    if constexpr (kSwap) {
        std::array<char, sizeof(T)> bytes{};
        std::memcpy(bytes.data(), p, sizeof(T));
        std::reverse(bytes.begin(), bytes.end());
        std::memcpy(&value, bytes.data(), sizeof(T));
    } else {
        std::memcpy(&value, p, sizeof(T));
    }
    return value;
}

template <class T>
T load(const char* p, bool swap) {
    return swap ? load<T, true>(p) : load<T, false>(p);
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

/// Where x, y and z of point i lie: src[axis] + i * stride[axis], each of type type[axis].
struct XyzColumns {
    std::array<const char*, 3> src{};
    std::array<std::size_t, 3> stride{};
    std::array<Scalar, 3> type{};
};

/// points[i] = (x, y, z) of every point, in one pass. When x, y, z are float32 in file byte
/// order one after another (PCL's PointXYZ and most PLY files) each point is one 12-byte copy
/// (the whole block at once when the stride is 12); otherwise each column is converted with
/// its type chosen once, never per point. `points` must already have its size.
void read_xyz_columns(const XyzColumns& columns, bool swap, Points& points);

/// Keeps the finite points of `points`, in order, in place (the widest SIMD kernels the CPU
/// has); returns how many were dropped.
std::size_t drop_non_finite_in_place(Points& points);

/// The finite points among the first `n` of the columns (none of x, y, z NaN or infinite), in
/// order, into `finite` (replaced; its memory is reused); returns how many were dropped. Float
/// columns of one value each (binary_compressed PCD) take one pass, as in read_xyz_columns.
std::size_t read_finite_xyz_columns(const XyzColumns& columns, bool swap, std::size_t n,
                                    Points& finite);

/// read_finite_points() for a PCD file (pcd_reader.cpp).
std::size_t read_pcd_finite(const std::string& path, Points& finite);

/// labels[i] = the value of type `type` at src + i * stride; returns the index of the first
/// value that is not an integer in [0, 2^32), or labels.size() when all are.
std::size_t read_label_column(const char* src, std::size_t stride, Scalar type, bool swap,
                              std::vector<std::uint32_t>& labels);

}  // namespace esf::detail
