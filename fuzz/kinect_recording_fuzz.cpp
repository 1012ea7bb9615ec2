// libFuzzer target: the readers of a fakenect Kinect recording. The first byte picks the reader
// ((byte & 0x7f) % 3: 0 esf::read_kinect_depth_pgm, 1 esf::read_kinect_rgb_ppm, 2
// esf::parse_kinect_recording_index); the rest is the file. With bit 0x80 set, a frame file's
// bytes after its first newline are repeated up to a whole frame's size, so that small inputs
// reach the pixel checks (a frame is 600 or 900 KB). A bad file must throw esf::IoError; what a
// reader accepts must be what kinect_recording.hpp documents (a full 640 x 480 frame, raw depth
// at most 2047, the pixels that the bytes after the header line hold, index entries named
// TYPE-TIME-... without a folder).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <istream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/io/kinect_raw.hpp"
#include "esf/io/kinect_recording.hpp"
#include "fuzz_input.hpp"

namespace {

/// The bytes after the first newline (the pixels, once the header line is accepted).
std::string_view body_of(std::string_view file) {
    const std::size_t newline = file.find('\n');
    return newline == std::string_view::npos ? std::string_view{} : file.substr(newline + 1);
}

/// `file` with the bytes after its first newline repeated up to `body` bytes (when shorter).
std::string padded(std::string_view file, std::size_t body) {
    std::string out(file);
    const std::size_t start = file.find('\n') + 1;
    if (start == 0 || start == file.size()) return out;
    const std::string_view pattern = file.substr(start);
    while (out.size() - start < body)
        out.append(pattern.substr(0, std::min(pattern.size(), body - (out.size() - start))));
    return out;
}

/// What `read` makes of `file`, or nothing when it throws esf::IoError (any other exception
/// escapes: a crash for the fuzzer).
template <class Read>
auto read_or_nothing(std::string_view file, Read read)
    -> std::optional<decltype(read(std::declval<std::istream&>()))> {
    std::istringstream in{std::string(file)};
    try {
        return read(in);
    } catch (const esf::IoError&) {
        return std::nullopt;
    }
}

void depth(std::string_view file) {
    const auto read = read_or_nothing(
        file, [](std::istream& in) { return esf::read_kinect_depth_pgm(in, "d.pgm"); });
    if (!read) return;
    const std::vector<std::uint16_t>& values = *read;
    if (values.size() != esf::kKinectFramePixels) __builtin_trap();
    const std::string_view body = body_of(file);
    if (body.size() < 2 * values.size()) __builtin_trap();
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] > esf::kKinectRawNoReading) __builtin_trap();
        const auto lo = static_cast<unsigned char>(body[2 * i]);
        const auto hi = static_cast<unsigned char>(body[2 * i + 1]);
        if (values[i] != (lo | (hi << 8))) __builtin_trap();
    }
}

void rgb(std::string_view file) {
    const auto read = read_or_nothing(
        file, [](std::istream& in) { return esf::read_kinect_rgb_ppm(in, "r.ppm"); });
    if (!read) return;
    const std::vector<std::uint8_t>& bytes = *read;
    if (bytes.size() != 3 * esf::kKinectFramePixels) __builtin_trap();
    const std::string_view body = body_of(file);
    if (body.size() < bytes.size() || std::memcmp(body.data(), bytes.data(), bytes.size()) != 0)
        __builtin_trap();
}

void index(std::string_view file) {
    const auto read = read_or_nothing(
        file, [](std::istream& in) { return esf::parse_kinect_recording_index(in, "INDEX.txt"); });
    if (!read) return;
    const std::vector<esf::KinectRecordingEntry>& entries = *read;
    if (entries.size() > file.size()) __builtin_trap();
    for (const esf::KinectRecordingEntry& e : entries) {
        if (e.type != 'd' && e.type != 'r' && e.type != 'a') __builtin_trap();
        if (e.file.size() < 2 || e.file.size() > 255 || e.file[0] != e.type || e.file[1] != '-')
            __builtin_trap();
        if (e.file.find_first_of("/\\\n") != std::string::npos) __builtin_trap();
        if (!std::isfinite(e.time)) __builtin_trap();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::string_view file = esf::fuzz::bytes_of(data + 1, size - 1);
    const bool pad = (data[0] & 0x80) != 0;
    const int reader = (data[0] & 0x7f) % 3;
    if (reader == 0)
        depth(pad ? padded(file, 2 * esf::kKinectFramePixels) : std::string(file));
    else if (reader == 1)
        rgb(pad ? padded(file, 3 * esf::kKinectFramePixels) : std::string(file));
    else
        index(file);
    return 0;
}
