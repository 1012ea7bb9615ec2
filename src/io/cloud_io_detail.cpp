#include "io/cloud_io_detail.hpp"

#include <fcntl.h>
#include <immintrin.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <istream>

#include "core/finite_points.hpp"
#include "core/simd.hpp"
#include "esf/core/error.hpp"

namespace esf::detail {

void fail(const std::string& name, std::size_t line, const std::string& reason) {
    throw IoError(file_message(name, line, reason));
}

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

// ---------------------------------------------------------------------------------------------
// Whole files

namespace {

/// "is a directory, not a file", "is a FIFO, not a regular file", ...; empty for regular files.
std::string not_regular(mode_t mode) {
    if (S_ISREG(mode)) return {};
    if (S_ISDIR(mode)) return "is a directory, not a file";
    const char* kind = S_ISFIFO(mode)   ? "a FIFO"
                       : S_ISCHR(mode)  ? "a character device"
                       : S_ISBLK(mode)  ? "a block device"
                       : S_ISSOCK(mode) ? "a socket"
                                        : "not a regular file";
    return std::string("is ") + kind + ", not a regular file";
}

}  // namespace

RegularFile::RegularFile(const std::string& path) : path_(path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int error = errno;
        if (error == ENOENT) fail(path, 0, "no such file");
        fail(path, 0, "cannot open for reading: " + errno_text(error));
    }
    if (const std::string why = not_regular(st.st_mode); !why.empty()) fail(path, 0, why);
    // Non-blocking, so that a FIFO swapped in after the stat cannot block the open either.
    fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd_ < 0) fail(path, 0, "cannot open for reading: " + errno_text(errno));
    if (::fstat(fd_, &st) != 0) {
        const int error = errno;
        ::close(fd_);
        fail(path, 0, "cannot read: " + errno_text(error));
    }
    if (const std::string why = not_regular(st.st_mode); !why.empty()) {
        ::close(fd_);
        fail(path, 0, why);
    }
    size_ = static_cast<std::size_t>(st.st_size);
}

RegularFile::~RegularFile() { ::close(fd_); }

std::size_t RegularFile::read(char* out, std::size_t n) {
    std::size_t done = 0;
    while (done < n) {
        const ssize_t got = ::read(fd_, out + done, n - done);
        if (got < 0) {
            if (errno == EINTR) continue;
            fail(path_, 0, "read error: " + errno_text(errno));
        }
        if (got == 0) break;  // the file shrank while being read: keep what is there
        done += static_cast<std::size_t>(got);
    }
    return done;
}

FileBytes read_regular_file(const std::string& path) {
    RegularFile file(path);
    FileBytes bytes;
    bytes.data = std::make_unique_for_overwrite<char[]>(std::max<std::size_t>(file.size(), 1));
    bytes.size = file.read(bytes.data.get(), file.size());
    return bytes;
}

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

// ---------------------------------------------------------------------------------------------
// Lines, tokens, typed values

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

namespace {

static_assert(sizeof(Eigen::Vector3f) == 12, "points are packed x, y, z floats");

template <bool kSwap>
void read_axis(const char* src, std::size_t stride, Scalar type, Points& points, int axis) {
    visit_scalar(type, [&](auto tag) {
        using T = decltype(tag);
        const std::size_t n = points.size();
        for (std::size_t i = 0; i < n; ++i) {
            points[i][axis] = static_cast<float>(load<T, kSwap>(src + i * stride));
        }
    });
}

}  // namespace

namespace {

/// Where each float of three 16-float output vectors (16 points x, y, z) comes from: from x or
/// y (index into x then y, as vpermt2ps takes two sources) or, where the mask bit is set, z.
struct InterleaveXyz {
    std::array<std::array<std::int32_t, 16>, 3> from_xy{}, from_z{};
    std::array<std::uint16_t, 3> z_mask{};
};

constexpr InterleaveXyz kInterleaveXyz = [] {
    InterleaveXyz t{};
    for (std::size_t v = 0; v < 3; ++v) {
        for (std::size_t k = 0; k < 16; ++k) {
            const auto g = static_cast<std::int32_t>(16 * v + k);
            const std::int32_t point = g / 3, axis = g % 3;
            t.from_xy[v][k] = axis == 1 ? 16 + point : point;
            t.from_z[v][k] = point;
            if (axis == 2) t.z_mask[v] = static_cast<std::uint16_t>(t.z_mask[v] | (1u << k));
        }
    }
    return t;
}();

/// x, y, z columns of n floats into points, 16 at a time (two permutes per 16 floats written);
/// with kFiniteOnly, only the points whose x, y and z are all finite, each column compressed to
/// them before the permutes. Writes whole blocks of 48 floats (up to 48 past what is kept);
/// returns the points written, from the first n / 16 * 16.
template <bool kFiniteOnly>
ESF_TARGET_AVX512 std::size_t interleave_xyz_avx512(const char* x, const char* y, const char* z,
                                                    std::size_t n, float* out) {
    constexpr int kNonFinite = 0x01 | 0x08 | 0x10 | 0x80;  // quiet NaN, +inf, -inf, signalling NaN
    __m512i from_xy[3], from_z[3];
    for (std::size_t v = 0; v < 3; ++v) {
        from_xy[v] = _mm512_loadu_si512(kInterleaveXyz.from_xy[v].data());
        from_z[v] = _mm512_loadu_si512(kInterleaveXyz.from_z[v].data());
    }
    const std::size_t blocks = n / 16;
    std::size_t written = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
        __m512 vx = _mm512_loadu_ps(x + 64 * b);
        __m512 vy = _mm512_loadu_ps(y + 64 * b);
        __m512 vz = _mm512_loadu_ps(z + 64 * b);
        __mmask16 keep = 0xffff;
        if constexpr (kFiniteOnly) {
            keep = static_cast<__mmask16>(~(_mm512_fpclass_ps_mask(vx, kNonFinite) |
                                            _mm512_fpclass_ps_mask(vy, kNonFinite) |
                                            _mm512_fpclass_ps_mask(vz, kNonFinite)));
            vx = _mm512_maskz_compress_ps(keep, vx);
            vy = _mm512_maskz_compress_ps(keep, vy);
            vz = _mm512_maskz_compress_ps(keep, vz);
        }
        for (std::size_t v = 0; v < 3; ++v) {
            const __m512 xy = _mm512_permutex2var_ps(vx, from_xy[v], vy);
            _mm512_storeu_ps(
                out + 3 * written + 16 * v,
                _mm512_mask_permutexvar_ps(xy, kInterleaveXyz.z_mask[v], from_z[v], vz));
        }
        written += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(keep)));
    }
    return written;
}

/// Whether x, y and z are float columns of one value each in this host's byte order (the
/// blocks of a binary_compressed PCD).
bool float_columns(const XyzColumns& c, bool swap) {
    return !swap && c.type[0] == Scalar::kF32 && c.type[1] == Scalar::kF32 &&
           c.type[2] == Scalar::kF32 && c.stride[0] == 4 && c.stride[1] == 4 && c.stride[2] == 4;
}

}  // namespace

std::size_t drop_non_finite_in_place(Points& points) {
    return keep_finite_in_place(points, best_simd_level());
}

std::size_t read_finite_xyz_columns(const XyzColumns& c, bool swap, std::size_t n, Points& finite) {
    if (!float_columns(c, swap) || !avx512_available()) {
        finite.resize(n);
        read_xyz_columns(c, swap, finite);
        return drop_non_finite_in_place(finite);
    }
    // binary_compressed PCD: x, y and z as three float columns, interleaved and filtered in one
    // pass (+ 16 points of room for the full-width stores).
    finite.resize(n + 16);
    float* out = finite.data()->data();
    std::size_t kept = interleave_xyz_avx512<true>(c.src[0], c.src[1], c.src[2], n, out);
    for (std::size_t i = n / 16 * 16; i < n; ++i) {
        float p[3];
        for (std::size_t a = 0; a < 3; ++a) std::memcpy(&p[a], c.src[a] + 4 * i, 4);
        if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
            finite[kept++] = {p[0], p[1], p[2]};
    }
    finite.resize(kept);
    return n - kept;
}

void read_xyz_columns(const XyzColumns& c, bool swap, Points& points) {
    const std::size_t n = points.size();
    if (n == 0) return;
    const bool packed_floats = !swap && c.type[0] == Scalar::kF32 && c.type[1] == Scalar::kF32 &&
                               c.type[2] == Scalar::kF32 && c.src[1] == c.src[0] + 4 &&
                               c.src[2] == c.src[0] + 8 && c.stride[0] == c.stride[1] &&
                               c.stride[0] == c.stride[2];
    if (packed_floats) {
        const std::size_t stride = c.stride[0];
        char* out = reinterpret_cast<char*>(points.data());
        if (stride == 12) {
            std::memcpy(out, c.src[0], 12 * n);
        } else {
            for (std::size_t i = 0; i < n; ++i)
                std::memcpy(out + 12 * i, c.src[0] + i * stride, 12);
        }
        return;
    }
    if (float_columns(c, swap)) {  // binary_compressed PCD: x, y and z as three columns, one pass
        float* out = points.data()->data();
        const std::size_t done =
            avx512_available() ? interleave_xyz_avx512<false>(c.src[0], c.src[1], c.src[2], n, out)
                               : 0;
        for (std::size_t i = done; i < n; ++i)
            for (std::size_t a = 0; a < 3; ++a) std::memcpy(out + 3 * i + a, c.src[a] + 4 * i, 4);
        return;
    }
    for (int axis = 0; axis < 3; ++axis) {
        const auto a = static_cast<std::size_t>(axis);
        if (swap) {
            read_axis<true>(c.src[a], c.stride[a], c.type[a], points, axis);
        } else {
            read_axis<false>(c.src[a], c.stride[a], c.type[a], points, axis);
        }
    }
}

std::size_t read_label_column(const char* src, std::size_t stride, Scalar type, bool swap,
                              std::vector<std::uint32_t>& labels) {
    return visit_scalar(type, [&](auto tag) -> std::size_t {
        using T = decltype(tag);
        if constexpr (std::is_same_v<T, std::uint32_t>) {  // every value is a label
            if (!swap && stride == sizeof(T) && !labels.empty()) {
                std::memcpy(labels.data(), src, labels.size() * sizeof(T));
                return labels.size();
            }
        }
        for (std::size_t i = 0; i < labels.size(); ++i) {
            if (!to_label(load<T>(src + i * stride, swap), labels[i])) return i;
        }
        return labels.size();
    });
}

}  // namespace esf::detail
