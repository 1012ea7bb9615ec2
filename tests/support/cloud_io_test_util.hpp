#pragma once
// Helpers of the point-cloud I/O tests (pcd_io_test, ply_cloud_io_test, xyz_cloud_io_test,
// lzf_test, cloud_io_test): files in memory, typed bytes, awkward sample clouds, temp dirs.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/io/cloud_io.hpp"

namespace esf::test {

namespace fs = std::filesystem;

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The message of the esf::IoError that f throws (a test failure when it throws none).
template <class F>
std::string io_error(F&& f) {
    try {
        f();
    } catch (const esf::IoError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an esf::IoError";
    return {};
}

inline esf::PointCloud pcd_from(const std::string& bytes, const std::string& name = "mem.pcd") {
    std::istringstream in(bytes);
    return esf::read_pcd(in, name);
}

inline esf::PointCloud ply_from(const std::string& bytes, const std::string& name = "mem.ply") {
    std::istringstream in(bytes);
    return esf::read_ply_cloud(in, name);
}

inline esf::PointCloud xyz_from(const std::string& bytes, const std::string& name = "mem.xyz") {
    std::istringstream in(bytes);
    return esf::read_xyz(in, name);
}

inline std::string pcd_bytes(const esf::PointCloud& cloud, esf::PcdEncoding encoding) {
    std::ostringstream out;
    esf::write_pcd(out, cloud, encoding);
    return out.str();
}

inline std::uint32_t bits(float v) { return std::bit_cast<std::uint32_t>(v); }

/// Same coordinates bit for bit (NaN payloads included).
inline void expect_same_points(const esf::Points& actual, const esf::Points& expected) {
    ASSERT_EQ(actual.size(), expected.size());
    for (std::size_t i = 0; i < actual.size(); ++i) {
        for (int axis = 0; axis < 3; ++axis) {
            if (bits(actual[i][axis]) != bits(expected[i][axis])) {
                ADD_FAILURE() << "point " << i << " axis " << axis << ": " << actual[i][axis]
                              << " != " << expected[i][axis];
                return;
            }
        }
    }
}

/// Awkward values: NaN, -0, subnormal, extremes, decimals without an exact float.
inline esf::PointCloud sample_cloud(std::size_t n, bool with_labels) {
    esf::PointCloud cloud;
    std::mt19937 gen(7);
    std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
    for (std::size_t i = 0; i < n; ++i) {
        const float x = coordinate(gen), y = coordinate(gen), z = coordinate(gen);
        cloud.points.emplace_back(x, y, z);
    }
    if (n > 4) {
        cloud.points[1] = {kNaN, kNaN, kNaN};
        cloud.points[2] = {-0.0f, 1e-40f, std::numeric_limits<float>::max()};
        cloud.points[3] = {0.1f, -1e30f, std::numeric_limits<float>::denorm_min()};
        cloud.points[4] = {std::numeric_limits<float>::lowest(), 1.0f / 3.0f, 123456.789f};
    }
    cloud.width = static_cast<std::uint32_t>(n);
    cloud.height = 1;
    if (with_labels) {
        for (std::size_t i = 0; i < n; ++i) {
            cloud.labels.push_back(static_cast<std::uint32_t>(i * 2654435761u));
        }
    }
    return cloud;
}

/// Typed values appended in little- or big-endian byte order.
class Bytes {
  public:
    explicit Bytes(bool big_endian = false) : big_endian_(big_endian) {}

    template <class T>
    Bytes& put(T value) {
        char raw[sizeof(T)];
        std::memcpy(raw, &value, sizeof(T));
        if (big_endian_ != (std::endian::native == std::endian::big)) {
            std::reverse(raw, raw + sizeof(T));
        }
        data_.append(raw, sizeof(T));
        return *this;
    }
    Bytes& text(std::string_view t) {
        data_ += t;
        return *this;
    }
    const std::string& str() const { return data_; }

  private:
    bool big_endian_;
    std::string data_;
};

/// Valid LZF made of literal runs only: an encoder independent of both the reader's decoder
/// and PCL's compressor.
inline std::string lzf_literals(const std::string& raw) {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); i += 32) {
        const std::size_t len = std::min<std::size_t>(32, raw.size() - i);
        out += static_cast<char>(len - 1);
        out.append(raw, i, len);
    }
    return out;
}

/// "DATA binary_compressed" body: compressed size, uncompressed size, the LZF block.
inline std::string compressed_body(const std::string& lzf, std::uint32_t uncompressed) {
    return Bytes().put(static_cast<std::uint32_t>(lzf.size())).put(uncompressed).str() + lzf;
}

inline std::string xyz_header(std::uint64_t points, std::string_view data) {
    return "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
           std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
           std::to_string(points) + "\nDATA " + std::string(data) + "\n";
}

/// A fresh directory for one test, removed afterwards.
class TempDir {
  public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = std::string(info->test_suite_name()) + "_" + info->name();
        std::replace(name.begin(), name.end(), '/', '_');  // parameterised test names
        path_ =
            fs::temp_directory_path() / ("esf_io_test_" + std::to_string(::getpid()) + "_" + name);
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string file(const std::string& name) const { return (path_ / name).string(); }
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(path_)) {
            names.push_back(e.path().filename().string());
        }
        std::sort(names.begin(), names.end());
        return names;
    }

  private:
    fs::path path_;
};

inline void write_text(const std::string& path, const std::string& content) {
    std::ofstream out(path, std::ios::binary);
    out << content;
}

/// Every prefix of `bytes` and 3000 random mutations (1 to 3 bytes each) give a cloud or an
/// esf::IoError from `read`, nothing else.
template <class Read>
void expect_prefixes_and_flips_read_or_fail(const std::string& bytes, Read read,
                                            std::mt19937& gen) {
    auto check = [&](const std::string& input) {
        try {
            const esf::PointCloud cloud = read(input);
            EXPECT_TRUE(cloud.labels.empty() || cloud.labels.size() == cloud.points.size());
        } catch (const esf::IoError&) {
        }
    };
    for (std::size_t n = 0; n <= bytes.size(); ++n) check(bytes.substr(0, n));
    for (int trial = 0; trial < 3000; ++trial) {
        std::string mutated = bytes;
        std::uniform_int_distribution<std::size_t> where(0, mutated.size() - 1);
        const int flips = 1 + trial % 3;
        for (int k = 0; k < flips; ++k) mutated[where(gen)] = static_cast<char>(gen() & 0xff);
        check(mutated);
    }
}

}  // namespace esf::test
