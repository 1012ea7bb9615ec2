// Kinect recordings in fakenect's format: frame files in memory, the index, and a written
// recording read back.

#include "esf/io/kinect_recording.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "../support/error_of.hpp"
#include "esf/core/error.hpp"
#include "esf/io/kinect_raw.hpp"

namespace {

std::vector<std::uint16_t> ramp_depth() {
    std::vector<std::uint16_t> depth(esf::kKinectFramePixels);
    for (std::size_t i = 0; i < depth.size(); ++i)
        depth[i] = static_cast<std::uint16_t>(i % 2048);  // every value, 2047 included
    return depth;
}

std::vector<std::uint8_t> ramp_rgb() {
    std::vector<std::uint8_t> rgb(3 * esf::kKinectFramePixels);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>(i * 7);
    return rgb;
}

std::filesystem::path temp_folder(const std::string& name) {
    const auto path = std::filesystem::temp_directory_path() /
                      ("esf_kinect_recording_test_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    return path;
}

TEST(KinectRecording, DepthFileIsFakenectsLayout) {
    std::ostringstream out;
    const std::vector<std::uint16_t> depth = ramp_depth();
    esf::write_kinect_depth_pgm(out, depth);
    const std::string bytes = out.str();
    ASSERT_EQ(bytes.size(), 17 + 2 * esf::kKinectFramePixels);
    EXPECT_EQ(bytes.substr(0, 17), "P5 640 480 65535\n");
    // Little-endian: pixel 2047 is the bytes ff 07.
    EXPECT_EQ(static_cast<unsigned char>(bytes[17 + 2 * 2047]), 0xff);
    EXPECT_EQ(static_cast<unsigned char>(bytes[17 + 2 * 2047 + 1]), 0x07);
    std::istringstream in(bytes);
    EXPECT_EQ(esf::read_kinect_depth_pgm(in, "d.pgm"), depth);
}

TEST(KinectRecording, ColourFileRoundTrip) {
    std::ostringstream out;
    const std::vector<std::uint8_t> rgb = ramp_rgb();
    esf::write_kinect_rgb_ppm(out, rgb);
    EXPECT_EQ(out.str().substr(0, 15), "P6 640 480 255\n");
    std::istringstream in(out.str());
    EXPECT_EQ(esf::read_kinect_rgb_ppm(in, "r.ppm"), rgb);
}

TEST(KinectRecording, BadFramesAreOneErrorNamingTheFile) {
    auto depth_error = [](const std::string& bytes) {
        std::istringstream in(bytes);
        return esf::test::error_of<esf::IoError>([&] { esf::read_kinect_depth_pgm(in, "d.pgm"); });
    };
    EXPECT_CONTAINS(depth_error(""), "d.pgm: no header line");
    EXPECT_CONTAINS(depth_error("P5 640 480 65535"), "no header line");
    EXPECT_CONTAINS(depth_error("P5 320 240 65535\n"), "is not 'P5 640 480 65535'");
    EXPECT_CONTAINS(depth_error("P6 640 480 65535\n"), "is not 'P5");
    EXPECT_CONTAINS(depth_error("P5 640 480 65535 7\n"), "is not 'P5");
    EXPECT_CONTAINS(depth_error("P5 640 480\n65535\n"), "is not 'P5");
    EXPECT_CONTAINS(depth_error(std::string(100, 'P')), "header line longer than 64");
    EXPECT_CONTAINS(depth_error("P5 640 480 65535\n\x01\x02"), "truncated: 2 of 614400 bytes");
    std::string big = "P5 640 480 65535\n" + std::string(2 * esf::kKinectFramePixels, '\0');
    big[17 + 2 * 641] = '\x00';
    big[17 + 2 * 641 + 1] = '\x10';  // 4096
    EXPECT_CONTAINS(depth_error(big), "raw depth 4096 at pixel (1, 1) exceeds 2047");

    std::istringstream short_rgb("P6 640 480 255\nabc");
    EXPECT_CONTAINS(
        esf::test::error_of<esf::IoError>([&] { esf::read_kinect_rgb_ppm(short_rgb, "r.ppm"); }),
        "r.ppm: truncated: 3 of 921600");
    EXPECT_CONTAINS(esf::test::error_of([&] {
                        std::ostringstream out;
                        esf::write_kinect_depth_pgm(out, std::vector<std::uint16_t>(4));
                    }),
                    "has 4 values");
}

TEST(KinectRecording, IndexLinesAreParsedAndChecked) {
    std::istringstream in(
        "r-1294102395.455289-3420483396.ppm\n"
        "d-1294102395.455601-3420483397.pgm\r\n"
        "\n"
        "a-1294102395.456000-0.dump\n");
    const auto entries = esf::parse_kinect_recording_index(in, "INDEX.txt");
    ASSERT_EQ(entries.size(), 3u);
    EXPECT_EQ(entries[0].type, 'r');
    EXPECT_DOUBLE_EQ(entries[0].time, 1294102395.455289);
    EXPECT_EQ(entries[0].timestamp, 3420483396u);
    EXPECT_EQ(entries[1].type, 'd');
    EXPECT_EQ(entries[1].file, "d-1294102395.455601-3420483397.pgm");
    EXPECT_EQ(entries[2].type, 'a');

    auto error = [](const std::string& text) {
        std::istringstream bad(text);
        return esf::test::error_of<esf::IoError>(
            [&] { esf::parse_kinect_recording_index(bad, "INDEX.txt"); });
    };
    EXPECT_CONTAINS(error("d-1.0-1.pgm\nx-1.0-1.pgm\n"), "INDEX.txt:2: 'x-1.0-1.pgm' is not");
    EXPECT_CONTAINS(error("d-../../etc/passwd\n"), "is not a file name in the recording's folder");
    EXPECT_CONTAINS(error("d-abc-1.pgm\n"), "has no TIME");
    EXPECT_CONTAINS(error("d-1.5-x.pgm\n"), "has no TIMESTAMP");
    EXPECT_CONTAINS(error("d-1.5-99999999999.pgm\n"), "TIMESTAMP out of range");
    EXPECT_CONTAINS(error("d-1.5-7\n"), "has no extension");
    EXPECT_CONTAINS(error(std::string(300, 'd')), "INDEX.txt:1: line longer than 255");
}

/// A stream of `size` copies of one character, counting how many of them were taken from it.
class RepeatedCharBuf : public std::streambuf {
  public:
    RepeatedCharBuf(char c, std::size_t size) : left_(size) { chunk_.fill(c); }
    std::size_t served() const { return served_; }

  protected:
    int_type underflow() override {
        if (left_ == 0) return traits_type::eof();
        const std::size_t n = std::min(left_, chunk_.size());
        left_ -= n;
        served_ += n;
        setg(chunk_.data(), chunk_.data(), chunk_.data() + n);
        return traits_type::to_int_type(chunk_[0]);
    }

  private:
    std::array<char, 64> chunk_{};
    std::size_t left_;
    std::size_t served_ = 0;
};

TEST(KinectRecording, LongIndexLineIsRefusedWithoutReadingItWhole) {
    // 64 MiB without a newline: the parser must stop soon after character 256, not hold the line.
    RepeatedCharBuf buf('d', std::size_t{64} << 20);
    std::istream in(&buf);
    EXPECT_CONTAINS(esf::test::error_of<esf::IoError>(
                        [&] { esf::parse_kinect_recording_index(in, "INDEX.txt"); }),
                    "INDEX.txt:1: line longer than 255");
    EXPECT_LE(buf.served(), 1024u);

    // 255 characters and "\r\n" is the longest line accepted; 256 are one too many.
    const std::string longest = "d-1.5-7.pgm" + std::string(255 - 11, 'x');
    std::istringstream ok(longest + "\r\n" + longest + "\n" + longest);
    const auto entries = esf::parse_kinect_recording_index(ok, "INDEX.txt");
    ASSERT_EQ(entries.size(), 3u);
    EXPECT_EQ(entries[2].file, longest);
    std::istringstream over("d-1.0-1.pgm\n" + longest + "x\r\n");
    EXPECT_CONTAINS(esf::test::error_of<esf::IoError>(
                        [&] { esf::parse_kinect_recording_index(over, "INDEX.txt"); }),
                    "INDEX.txt:2: line longer than 255");
}

TEST(KinectRecording, WrittenRecordingReadsBackFrameByFrame) {
    const auto folder = temp_folder("round_trip");
    esf::KinectRecordingWriter writer(folder.string());
    esf::KinectFrame first{1.0, 0, ramp_depth(), ramp_rgb()};
    esf::KinectFrame second{
        1.0 + 1.0 / 30.0, 2000000, std::vector<std::uint16_t>(esf::kKinectFramePixels, 770), {}};
    writer.add(first);
    writer.add(second);
    EXPECT_CONTAINS(esf::test::error_of([&] { writer.add(first); }), "times must increase");
    const std::string index = writer.finish();

    std::ifstream text(index);
    std::string line1, line2, line3;
    std::getline(text, line1);
    std::getline(text, line2);
    std::getline(text, line3);
    EXPECT_EQ(line1, "r-1.000000-0.ppm");  // colour before its depth frame
    EXPECT_EQ(line2, "d-1.000000-0.pgm");
    EXPECT_EQ(line3, "d-1.033333-2000000.pgm");

    esf::KinectRecordingReader reader(folder.string());
    EXPECT_EQ(reader.depth_frames(), 2u);
    auto a = reader.next();
    ASSERT_TRUE(a);
    EXPECT_EQ(a->depth, first.depth);
    EXPECT_EQ(a->rgb, first.rgb);
    EXPECT_DOUBLE_EQ(a->time, 1.0);
    auto b = reader.next();
    ASSERT_TRUE(b);
    EXPECT_EQ(b->depth, second.depth);
    EXPECT_EQ(b->rgb, first.rgb);  // the last colour before it
    EXPECT_EQ(b->timestamp, 2000000u);
    EXPECT_FALSE(reader.next());
    EXPECT_FALSE(reader.next());
    std::filesystem::remove_all(folder);
}

TEST(KinectRecording, ReaderRefusesMissingFilesByName) {
    const auto folder = temp_folder("missing");
    EXPECT_CONTAINS(esf::test::error_of<esf::IoError>(
                        [&] { esf::KinectRecordingReader reader(folder.string()); }),
                    "INDEX.txt: no such file");
    std::filesystem::create_directories(folder);
    std::ofstream(folder / "INDEX.txt") << "d-1.0-0.pgm\n";
    EXPECT_CONTAINS(esf::test::error_of<esf::IoError>(
                        [&] { esf::KinectRecordingReader reader(folder.string()); }),
                    "d-1.0-0.pgm: listed in INDEX.txt but not a regular file");
    std::ofstream(folder / "INDEX.txt") << "";
    EXPECT_CONTAINS(esf::test::error_of<esf::IoError>(
                        [&] { esf::KinectRecordingReader reader(folder.string()); }),
                    "lists no depth frame");
    std::filesystem::remove_all(folder);
}

}  // namespace
