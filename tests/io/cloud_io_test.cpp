// Cloud files on disk (src/io/cloud_io.cpp, src/io/cloud_io_detail.cpp): the format by extension,
// path errors, hostile files (FIFOs, devices, directories, absurd counts), atomic writes.

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <chrono>
#include <future>
#include <memory>
#include <thread>

#include "support/cloud_io_test_util.hpp"
#include "support/test_data.hpp"

namespace {

using namespace esf::test;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// ---------------------------------------------------------------------------------------------
// Files: format by extension, path errors, atomic writes

TEST(CloudFormat, ByExtensionIgnoringCase) {
    EXPECT_EQ(esf::cloud_format_from_path("a/b.PCD"), esf::CloudFormat::kPcd);
    EXPECT_EQ(esf::cloud_format_from_path("b.Ply"), esf::CloudFormat::kPly);
    EXPECT_EQ(esf::cloud_format_from_path("c.xyz"), esf::CloudFormat::kXyz);
    EXPECT_EQ(esf::cloud_format_from_path("d.TXT"), esf::CloudFormat::kXyz);
    EXPECT_EQ(esf::cloud_format_from_path("e.pts"), esf::CloudFormat::kXyz);
    EXPECT_EQ(io_error([] { esf::cloud_format_from_path("mesh.obj"); }),
              "mesh.obj: unknown point cloud format (expected .pcd, .ply, .xyz, .txt or .pts)");
    EXPECT_THAT(io_error([] { esf::read_cloud("noext"); }),
                StartsWith("noext: unknown point cloud format"));
}

TEST(CloudFiles, ReadCloudDispatchesOnExtension) {
    TempDir dir;
    const esf::PointCloud cloud = sample_cloud(50, false);
    esf::write_pcd(dir.file("a.PCD"), cloud);
    expect_same_points(esf::read_cloud(dir.file("a.PCD")).points, cloud.points);
    write_text(dir.file("b.ply"),
               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
               "property float z\nend_header\n4 5 6\n");
    EXPECT_EQ(esf::read_cloud(dir.file("b.ply")).points.at(0), Eigen::Vector3f(4, 5, 6));
    write_text(dir.file("c.pts"), "1 2 3\n");
    EXPECT_EQ(esf::read_cloud(dir.file("c.pts")).points.at(0), Eigen::Vector3f(1, 2, 3));
}

TEST(CloudFiles, MissingEmptyAndDirectory) {
    TempDir dir;
    const std::string missing = dir.file("missing.pcd");
    EXPECT_EQ(io_error([&] { esf::read_cloud(missing); }), missing + ": no such file");
    for (const std::string name : {"empty.pcd", "empty.ply", "empty.xyz"}) {
        write_text(dir.file(name), "");
        EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file(name)); }),
                  dir.file(name) + ": empty file");
    }
    fs::create_directory(dir.file("folder.pcd"));
    EXPECT_EQ(io_error([&] { esf::read_pcd(dir.file("folder.pcd")); }),
              dir.file("folder.pcd") + ": is a directory, not a file");
}

/// Runs `read` on another thread and returns its IoError message; fails the test when the call
/// blocks for more than ten seconds (then the thread is left behind: the test process ends soon).
template <class F>
std::string io_error_without_blocking(F read) {
    auto done = std::make_shared<std::promise<std::string>>();
    std::future<std::string> message = done->get_future();
    std::thread([done, read] { done->set_value(io_error(read)); }).detach();
    if (message.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
        ADD_FAILURE() << "the reader blocked";
        return {};
    }
    return message.get();
}

TEST(HostileFiles, FifoIsRefusedWithoutBlocking) {
    TempDir dir;
    // A FIFO with no writer: opening it for reading blocks unless the reader refuses it first.
    for (const std::string name : {"x.pcd", "x.ply", "x.xyz"}) {
        const std::string path = dir.file(name);
        ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
        EXPECT_EQ(io_error_without_blocking([path] { esf::read_cloud(path); }),
                  path + ": is a FIFO, not a regular file");
    }
}

TEST(HostileFiles, DeviceAndDirectoryAreRefused) {
    TempDir dir;
    // /dev/zero never ends and /dev/null is empty; both are character devices.
    for (const std::string device : {"/dev/zero", "/dev/null"}) {
        if (!fs::exists(device)) GTEST_SKIP() << device << " missing";
        const std::string link = dir.file(fs::path(device).filename().string() + ".pcd");
        fs::create_symlink(device, link);
        EXPECT_EQ(io_error_without_blocking([link] { esf::read_cloud(link); }),
                  link + ": is a character device, not a regular file");
    }
    fs::create_directory(dir.file("folder.ply"));
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("folder.ply")); }),
              dir.file("folder.ply") + ": is a directory, not a file");
    fs::create_symlink(dir.file("nowhere.pcd"), dir.file("dangling.pcd"));
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("dangling.pcd")); }),
              dir.file("dangling.pcd") + ": no such file");
}

TEST(HostileFiles, SmallFilesAnnouncingABillionPointsFailBeforeAllocating) {
    TempDir dir;
    // Each file is about 50 to 150 bytes and announces 10^9 points: the count is checked against
    // the bytes present (binary: exactly; text: two bytes per value) before any allocation.
    const std::string pcd_binary =
        "FIELDS x y z\nWIDTH 1000000000\nPOINTS 1000000000\nDATA binary\n" + std::string(12, 'a');
    write_text(dir.file("binary.pcd"), pcd_binary);
    EXPECT_EQ(
        io_error([&] { esf::read_cloud(dir.file("binary.pcd")); }),
        dir.file("binary.pcd") + ": truncated: expected 12000000000 bytes of binary data, got 12");
    write_text(dir.file("ascii.pcd"), "FIELDS x y z\nPOINTS 1000000000\nDATA ascii\n1 2 3\n");
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("ascii.pcd")); }),
              dir.file("ascii.pcd") +
                  ": truncated: expected 1000000000 points of ascii data, but only 6 bytes follow "
                  "the header");
    write_text(dir.file("packed.pcd"), "FIELDS x y z\nPOINTS 1000000000\nDATA binary_compressed\n" +
                                           compressed_body(lzf_literals("abcd"), 4));
    EXPECT_THAT(io_error([&] { esf::read_cloud(dir.file("packed.pcd")); }),
                StartsWith(dir.file("packed.pcd") + ": corrupt binary_compressed data"));
    const std::string ply_header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n";
    write_text(dir.file("binary.ply"), ply_header + std::string(12, 'a'));
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("binary.ply")); }),
              dir.file("binary.ply") +
                  ": truncated: expected 12000000000 bytes of binary data, got 12 (element "
                  "'vertex')");
    std::string ascii_ply = ply_header + "1 2 3\n";
    ascii_ply.replace(ascii_ply.find("binary_little_endian"), 20, "ascii");
    write_text(dir.file("ascii.ply"), ascii_ply);
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("ascii.ply")); }),
              dir.file("ascii.ply") +
                  ":3: truncated: expected 1000000000 vertices, but only 6 bytes follow the "
                  "header");
}

TEST(HostileFiles, TruncatedFilesOnDisk) {
    TempDir dir;
    const std::string full = pcd_bytes(sample_cloud(100, true), esf::PcdEncoding::kBinary);
    write_text(dir.file("cut.pcd"), full.substr(0, full.size() - 7));
    EXPECT_EQ(io_error([&] { esf::read_cloud(dir.file("cut.pcd")); }),
              dir.file("cut.pcd") + ": truncated: expected 1600 bytes of binary data, got 1593");
    const std::string ascii = pcd_bytes(sample_cloud(10, false), esf::PcdEncoding::kAscii);
    write_text(dir.file("cut_ascii.pcd"), ascii.substr(0, ascii.rfind('\n', ascii.size() - 2) + 1));
    EXPECT_THAT(io_error([&] { esf::read_cloud(dir.file("cut_ascii.pcd")); }),
                AllOf(StartsWith(dir.file("cut_ascii.pcd") + ":"),
                      HasSubstr("truncated: expected 10 points of ascii data, got 9")));
}

TEST(CloudFiles, ErrorsInFilesNameThePath) {
    TempDir dir;
    write_text(dir.file("bad.pcd"), xyz_header(2, "ascii") + "1 2 3\nx 5 6\n");
    EXPECT_EQ(io_error([&] { esf::read_pcd(dir.file("bad.pcd")); }),
              dir.file("bad.pcd") + ":12: not a number: 'x' (field 'x')");
}

TEST(CloudFiles, WritePcdLeavesNoTemporaryFile) {
    TempDir dir;
    const std::string path = dir.file("cloud.pcd");
    for (const auto encoding : {esf::PcdEncoding::kBinary, esf::PcdEncoding::kAscii,
                                esf::PcdEncoding::kBinaryCompressed}) {
        const esf::PointCloud cloud = sample_cloud(20 + static_cast<std::size_t>(encoding), true);
        esf::write_pcd(path, cloud, encoding);  // the second and third replace the first
        EXPECT_EQ(dir.entries(), std::vector<std::string>{"cloud.pcd"});
        const esf::PointCloud back = esf::read_pcd(path);
        EXPECT_EQ(back.points.size(), cloud.points.size());
        EXPECT_EQ(back.labels, cloud.labels);
    }
    // Failures leave nothing behind either.
    esf::PointCloud bad = sample_cloud(5, false);
    bad.labels = {1};
    EXPECT_THROW(esf::write_pcd(dir.file("bad.pcd"), bad), std::invalid_argument);
    const std::string nowhere = dir.file("no/such/dir/cloud.pcd");
    EXPECT_THAT(io_error([&] { esf::write_pcd(nowhere, sample_cloud(5, false)); }),
                AllOf(StartsWith(nowhere + ": cannot create temporary file"),
                      HasSubstr("No such file or directory")));
    fs::create_directory(dir.file("taken.pcd"));
    EXPECT_THAT(io_error([&] { esf::write_pcd(dir.file("taken.pcd"), sample_cloud(5, false)); }),
                StartsWith(dir.file("taken.pcd") + ": cannot replace the file"));
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"cloud.pcd", "taken.pcd"}));
}

TEST(CloudFiles, WriteXyzReplacesAtomicallyAndReadsBack) {
    TempDir dir;
    const std::string path = dir.file("cloud.xyz");
    const esf::PointCloud cloud = sample_cloud(30, true);
    esf::write_xyz(path, cloud);
    esf::write_xyz(path, cloud);  // replaces the first
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"cloud.xyz"});
    const esf::PointCloud back = esf::read_cloud(path);
    expect_same_points(back.points, cloud.points);
    EXPECT_TRUE(back.labels.empty());
    const std::string nowhere = dir.file("no/such/dir/cloud.xyz");
    EXPECT_THAT(io_error([&] { esf::write_xyz(nowhere, cloud); }),
                StartsWith(nowhere + ": cannot create temporary file"));
}

// ---------------------------------------------------------------------------------------------
// read_finite_points: the finite points of read_cloud(), by its own paths

/// A cloud whose non-finite coordinates (NaN, +-inf, in x, y or z alone, in runs that fill whole
/// blocks of 16 and scattered) are placed at random; its finite points, by definition.
esf::PointCloud cloud_with_gaps(std::size_t n, std::mt19937& gen, esf::Points& finite) {
    esf::PointCloud cloud = sample_cloud(n, true);
    const float bad[4] = {kNaN, std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::signaling_NaN()};
    std::uniform_int_distribution<int> roll(0, 9), which(0, 3), axis(0, 2);
    finite.clear();
    for (std::size_t i = 0; i < n; ++i) {
        if ((i / 48) % 3 == 1 || roll(gen) < 3) cloud.points[i][axis(gen)] = bad[which(gen)];
        const Eigen::Vector3f& p = cloud.points[i];
        if (std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()))
            finite.push_back(p);
    }
    return cloud;
}

/// A binary little-endian PLY of the points, with an extra property between y and z.
std::string ply_binary(const esf::Points& points) {
    Bytes b;
    b.text("ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(points.size()) +
           "\nproperty float x\nproperty float y\nproperty uchar red\nproperty float z\n"
           "end_header\n");
    for (const auto& p : points) b.put(p.x()).put(p.y()).put(std::uint8_t{7}).put(p.z());
    return b.str();
}

TEST(ReadFinitePoints, TheFinitePointsOfEveryFormatInOrder) {
    TempDir dir;
    std::mt19937 gen(5);
    // Reused from call to call, starting larger than any cloud here: replaced, never appended to.
    esf::Points finite(5000, Eigen::Vector3f::Constant(9.0f));
    for (const std::size_t n : {1u, 15u, 16u, 17u, 100u, 1000u, 4099u}) {
        esf::Points expected;
        const esf::PointCloud cloud = cloud_with_gaps(n, gen, expected);
        esf::PointCloud unlabelled = cloud;
        unlabelled.labels.clear();
        std::vector<std::string> files;
        const auto write = [&](const std::string& name, const std::string& bytes) {
            write_text(dir.file(name), bytes);
            files.push_back(dir.file(name));
        };
        for (const auto encoding : {esf::PcdEncoding::kAscii, esf::PcdEncoding::kBinary,
                                    esf::PcdEncoding::kBinaryCompressed}) {
            const std::string e = std::to_string(static_cast<int>(encoding));
            write("labelled" + e + ".pcd", pcd_bytes(cloud, encoding));
            write("plain" + e + ".pcd", pcd_bytes(unlabelled, encoding));  // binary: read direct
        }
        write("binary.ply", ply_binary(cloud.points));
        esf::write_xyz(dir.file("text.xyz"), cloud);
        files.push_back(dir.file("text.xyz"));
        for (const std::string& file : files) {
            SCOPED_TRACE(file + ", " + std::to_string(n) + " points");
            EXPECT_EQ(esf::read_finite_points(file, finite), n - expected.size());
            expect_same_points(finite, expected);
            expect_same_points(esf::drop_non_finite(esf::read_cloud(file).points).points, expected);
        }
    }
}

TEST(ReadFinitePoints, NoFinitePointsAndNoPoints) {
    TempDir dir;
    esf::PointCloud cloud;
    cloud.points.assign(37, Eigen::Vector3f(kNaN, 0.0f, 1.0f));
    cloud.width = 37;
    esf::Points finite(3, Eigen::Vector3f::Ones());
    for (const auto encoding : {esf::PcdEncoding::kBinary, esf::PcdEncoding::kBinaryCompressed}) {
        write_text(dir.file("gone.pcd"), pcd_bytes(cloud, encoding));
        EXPECT_EQ(esf::read_finite_points(dir.file("gone.pcd"), finite), 37u);
        EXPECT_TRUE(finite.empty());
    }
    write_text(dir.file("none.pcd"), xyz_header(0, "binary_compressed") + compressed_body("", 0));
    finite.assign(3, Eigen::Vector3f::Ones());
    EXPECT_EQ(esf::read_finite_points(dir.file("none.pcd"), finite), 0u);
    EXPECT_TRUE(finite.empty());
}

// Not keeping the labels does not skip their check: the same error as read_cloud.
TEST(ReadFinitePoints, TheSameErrorsAsReadCloud) {
    TempDir dir;
    std::mt19937 gen(9);
    esf::Points expected;
    const esf::PointCloud cloud = cloud_with_gaps(300, gen, expected);
    const std::string compressed = pcd_bytes(cloud, esf::PcdEncoding::kBinaryCompressed);
    std::vector<std::string> files;
    const auto write = [&](const std::string& name, const std::string& bytes) {
        write_text(dir.file(name), bytes);
        files.push_back(dir.file(name));
    };
    write("cut.pcd", compressed.substr(0, compressed.size() - 9));
    std::string damaged = compressed;
    const std::string data_line = "DATA binary_compressed\n";
    // The first token a back reference: before the start of the output.
    damaged[damaged.find(data_line) + data_line.size() + 8] = static_cast<char>(0x20);
    write("damaged.pcd", damaged);
    // Float labels, one of them not an integer, in a binary_compressed and a binary file.
    std::string raw;
    for (int axis = 0; axis < 4; ++axis)
        for (int i = 0; i < 20; ++i) {
            const float v = axis < 3 ? static_cast<float>(i + axis) : (i == 13 ? 1.5f : 2.0f);
            raw.append(reinterpret_cast<const char*>(&v), 4);
        }
    const std::string float_labels =
        "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 20\nPOINTS 20\n";
    write("labels.pcd", float_labels + "DATA binary_compressed\n" +
                            compressed_body(lzf_literals(raw), static_cast<std::uint32_t>(80 * 4)));
    std::string aos;
    for (int i = 0; i < 20; ++i)
        for (int axis = 0; axis < 4; ++axis)
            aos.append(raw, static_cast<std::size_t>(axis * 80 + i * 4), 4);
    write("labels_binary.pcd", float_labels + "DATA binary\n" + aos);
    write("bad.ply",
          "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
          "property float z\nend_header\n1 2 3\n");
    write("bad.xyz", "1 2 3\n4 five 6\n");
    esf::Points finite;
    for (const std::string& file : files) {
        const std::string message = io_error([&] { esf::read_cloud(file); });
        EXPECT_FALSE(message.empty()) << file;
        EXPECT_EQ(io_error([&] { esf::read_finite_points(file, finite); }), message);
    }
    EXPECT_THAT(io_error([&] { esf::read_cloud(dir.file("labels.pcd")); }),
                HasSubstr("point 13: label is not an integer"));
}

// Every shared real cloud (organised scenes with gaps, segmented views): the same finite points.
TEST(ReadFinitePoints, EverySharedRealCloud) {
    ESF_REQUIRE_DATA("real");
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(esf::test::data_file("real")))
        if (e.is_regular_file() && e.path().extension() == ".pcd") files.push_back(e.path());
    ASSERT_FALSE(files.empty());
    std::sort(files.begin(), files.end());
    esf::Points finite;
    std::size_t with_gaps = 0;
    for (const auto& file : files) {
        SCOPED_TRACE(file.string());
        const esf::Points all = esf::read_cloud(file.string()).points;
        esf::Points expected;
        for (const auto& p : all)
            if (std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()))
                expected.push_back(p);
        const std::size_t dropped = esf::read_finite_points(file.string(), finite);
        EXPECT_EQ(dropped, all.size() - expected.size());
        expect_same_points(finite, expected);
        with_gaps += dropped > 0;
    }
    EXPECT_GT(with_gaps, 0u);  // the scenes' missing depths
}

}  // namespace
