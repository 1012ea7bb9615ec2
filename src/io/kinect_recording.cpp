#include "esf/io/kinect_recording.hpp"

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "esf/core/error.hpp"
#include "esf/io/kinect_raw.hpp"

namespace esf {

namespace {

constexpr std::size_t kMaxLine = 255;
const char* const kDepthHeader = "P5 640 480 65535";
const char* const kRgbHeader = "P6 640 480 255";

/// How read_line stopped.
enum class LineEnd { kNewline, kStreamEnd, kTooLong };

/// The next line of `in` into `line`, without its newline, read one character at a time so that
/// a line of any length costs no more than `limit` + 1 characters: kTooLong when more than
/// `limit` come before a newline (`line` then holds `limit` + 1 of them).
LineEnd read_line(std::istream& in, std::string& line, std::size_t limit) {
    line.clear();
    for (;;) {
        const int c = in.get();
        if (c == std::char_traits<char>::eof()) return LineEnd::kStreamEnd;
        if (c == '\n') return LineEnd::kNewline;
        line.push_back(static_cast<char>(c));
        if (line.size() > limit) return LineEnd::kTooLong;
    }
}

/// The first line of a frame file (without its newline); fakenect skips exactly this line.
std::string header_line(std::istream& in, const std::string& name) {
    std::string line;
    switch (read_line(in, line, 64)) {
        case LineEnd::kNewline:
            return line;
        case LineEnd::kStreamEnd:
            throw IoError(file_message(name, 0,
                                       "no header line (expected a line ending in a "
                                       "newline before the pixels)"));
        case LineEnd::kTooLong:
            break;
    }
    throw IoError(file_message(name, 0, "header line longer than 64 characters"));
}

/// Checks the header's words: magic, 640, 480, maximum value, and nothing else.
void check_header(const std::string& line, const std::string& name, const char* magic,
                  long maximum) {
    std::istringstream words(line);
    std::string got_magic, extra;
    long width = 0, height = 0, max_value = 0;
    if (!(words >> got_magic >> width >> height >> max_value) || (words >> extra) ||
        got_magic != magic || width != kKinectFrameWidth || height != kKinectFrameHeight ||
        max_value != maximum)
        throw IoError(file_message(name, 0,
                                   "header '" + line.substr(0, 40) + "' is not '" + magic +
                                       " 640 480 " + std::to_string(maximum) + "'"));
}

void read_body(std::istream& in, char* data, std::size_t size, const std::string& name) {
    in.read(data, static_cast<std::streamsize>(size));
    if (static_cast<std::size_t>(in.gcount()) != size)
        throw IoError(file_message(name, 0,
                                   "truncated: " + std::to_string(in.gcount()) + " of " +
                                       std::to_string(size) + " bytes of pixels"));
}

std::ifstream open_regular(const std::string& path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
        throw IoError(file_message(
            path, 0, std::filesystem::exists(path, error) ? "not a regular file" : "no such file"));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(file_message(path, 0, "cannot be opened"));
    return in;
}

std::string entry_name(char type, double time, std::uint32_t timestamp) {
    char name[96];
    std::snprintf(name, sizeof name, "%c-%.6f-%u.%s", type, time, timestamp,
                  type == 'd' ? "pgm" : "ppm");
    return name;
}

}  // namespace

std::vector<std::uint16_t> read_kinect_depth_pgm(std::istream& in, const std::string& name) {
    check_header(header_line(in, name), name, "P5", 65535);
    std::vector<std::uint8_t> bytes(2 * kKinectFramePixels);
    read_body(in, reinterpret_cast<char*>(bytes.data()), bytes.size(), name);
    std::vector<std::uint16_t> depth(kKinectFramePixels);
    for (std::size_t i = 0; i < depth.size(); ++i) {
        depth[i] = static_cast<std::uint16_t>(bytes[2 * i] | (bytes[2 * i + 1] << 8));
        if (depth[i] > kKinectRawNoReading)
            throw IoError(file_message(name, 0,
                                       "raw depth " + std::to_string(depth[i]) + " at pixel (" +
                                           std::to_string(i % kKinectFrameWidth) + ", " +
                                           std::to_string(i / kKinectFrameWidth) +
                                           ") exceeds 2047"));
    }
    return depth;
}

std::vector<std::uint16_t> read_kinect_depth_pgm(const std::string& path) {
    std::ifstream in = open_regular(path);
    return read_kinect_depth_pgm(in, path);
}

std::vector<std::uint8_t> read_kinect_rgb_ppm(std::istream& in, const std::string& name) {
    check_header(header_line(in, name), name, "P6", 255);
    std::vector<std::uint8_t> rgb(3 * kKinectFramePixels);
    read_body(in, reinterpret_cast<char*>(rgb.data()), rgb.size(), name);
    return rgb;
}

std::vector<std::uint8_t> read_kinect_rgb_ppm(const std::string& path) {
    std::ifstream in = open_regular(path);
    return read_kinect_rgb_ppm(in, path);
}

void write_kinect_depth_pgm(std::ostream& out, std::span<const std::uint16_t> depth) {
    if (depth.size() != kKinectFramePixels)
        throw std::invalid_argument("Kinect depth frame has " + std::to_string(depth.size()) +
                                    " values, expected 640 x 480");
    std::vector<char> bytes(2 * depth.size());
    for (std::size_t i = 0; i < depth.size(); ++i) {
        if (depth[i] > kKinectRawNoReading)
            throw std::invalid_argument("raw depth " + std::to_string(depth[i]) +
                                        " exceeds 2047 at index " + std::to_string(i));
        bytes[2 * i] = static_cast<char>(depth[i] & 0xff);
        bytes[2 * i + 1] = static_cast<char>(depth[i] >> 8);
    }
    out << kDepthHeader << '\n';
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void write_kinect_rgb_ppm(std::ostream& out, std::span<const std::uint8_t> rgb) {
    if (rgb.size() != 3 * kKinectFramePixels)
        throw std::invalid_argument("Kinect colour frame has " + std::to_string(rgb.size()) +
                                    " bytes, expected 640 x 480 x 3");
    out << kRgbHeader << '\n';
    out.write(reinterpret_cast<const char*>(rgb.data()), static_cast<std::streamsize>(rgb.size()));
}

std::vector<KinectRecordingEntry> parse_kinect_recording_index(std::istream& in,
                                                               const std::string& name) {
    std::vector<KinectRecordingEntry> entries;
    std::string line;
    std::size_t number = 0;
    // kMaxLine + 1: a line of kMaxLine characters may end in "\r\n".
    while (read_line(in, line, kMaxLine + 1) != LineEnd::kStreamEnd || !line.empty()) {
        ++number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        auto bad = [&](const std::string& why) { return IoError(file_message(name, number, why)); };
        if (line.size() > kMaxLine) throw bad("line longer than 255 characters");
        if (line.find('/') != std::string::npos || line.find('\\') != std::string::npos)
            throw bad("'" + line + "' is not a file name in the recording's folder");
        KinectRecordingEntry e;
        e.type = line[0];
        if ((e.type != 'd' && e.type != 'r' && e.type != 'a') || line.size() < 2 || line[1] != '-')
            throw bad("'" + line + "' is not d-TIME-TIMESTAMP.pgm, r-... .ppm or a-... .dump");
        const char* begin = line.c_str() + 2;
        char* end = nullptr;
        e.time = std::strtod(begin, &end);
        if (end == begin || *end != '-' || !std::isfinite(e.time))
            throw bad("'" + line + "' has no TIME (seconds) after its type");
        begin = end + 1;
        if (*begin < '0' || *begin > '9') throw bad("'" + line + "' has no TIMESTAMP");
        const unsigned long long timestamp = std::strtoull(begin, &end, 10);
        if (end == begin || timestamp > 0xffffffffULL)
            throw bad("'" + line + "' has a TIMESTAMP out of range");
        e.timestamp = static_cast<std::uint32_t>(timestamp);
        if (*end != '.' && *end != '-') throw bad("'" + line + "' has no extension");
        e.file = line;
        entries.push_back(std::move(e));
    }
    return entries;
}

KinectRecordingWriter::KinectRecordingWriter(std::string folder) : folder_(std::move(folder)) {
    std::error_code error;
    std::filesystem::create_directories(folder_, error);
    if (error || !std::filesystem::is_directory(folder_))
        throw IoError(file_message(folder_, 0, "cannot create the recording's folder"));
}

void KinectRecordingWriter::add(const KinectFrame& frame) {
    if (!(std::isfinite(frame.time) && frame.time > 0.0))
        throw std::invalid_argument("Kinect frame time must be positive and finite, got " +
                                    std::to_string(frame.time));
    if (frames_ > 0 && !(frame.time > last_time_))
        throw std::invalid_argument(
            "Kinect frame times must increase: " + std::to_string(frame.time) + " after " +
            std::to_string(last_time_));
    std::ostringstream depth;
    write_kinect_depth_pgm(depth, frame.depth);
    if (!frame.rgb.empty()) {
        std::ostringstream rgb;
        write_kinect_rgb_ppm(rgb, frame.rgb);
        const std::string name = entry_name('r', frame.time, frame.timestamp);
        const std::string bytes = rgb.str();
        detail::write_file_atomically(std::filesystem::path(folder_) / name, bytes.data(),
                                      bytes.size());
        index_ += name + "\n";
    }
    const std::string name = entry_name('d', frame.time, frame.timestamp);
    const std::string bytes = depth.str();
    detail::write_file_atomically(std::filesystem::path(folder_) / name, bytes.data(),
                                  bytes.size());
    index_ += name + "\n";
    last_time_ = frame.time;
    ++frames_;
}

std::string KinectRecordingWriter::finish() {
    const std::filesystem::path path = std::filesystem::path(folder_) / "INDEX.txt";
    detail::write_file_atomically(path, index_.data(), index_.size());
    return path.string();
}

KinectRecordingReader::KinectRecordingReader(std::string folder) : folder_(std::move(folder)) {
    const std::string index = (std::filesystem::path(folder_) / "INDEX.txt").string();
    std::ifstream in = open_regular(index);
    entries_ = parse_kinect_recording_index(in, index);
    for (const KinectRecordingEntry& e : entries_) {
        const std::string path = (std::filesystem::path(folder_) / e.file).string();
        std::error_code error;
        if (!std::filesystem::is_regular_file(path, error))
            throw IoError(file_message(path, 0, "listed in INDEX.txt but not a regular file"));
    }
    if (depth_frames() == 0) throw IoError(file_message(index, 0, "lists no depth frame"));
}

std::size_t KinectRecordingReader::depth_frames() const {
    std::size_t n = 0;
    for (const KinectRecordingEntry& e : entries_) n += e.type == 'd';
    return n;
}

std::optional<KinectFrame> KinectRecordingReader::next() {
    while (next_ < entries_.size()) {
        const KinectRecordingEntry& e = entries_[next_++];
        const std::string path = (std::filesystem::path(folder_) / e.file).string();
        if (e.type == 'r') {
            rgb_ = read_kinect_rgb_ppm(path);
        } else if (e.type == 'd') {
            KinectFrame frame;
            frame.time = e.time;
            frame.timestamp = e.timestamp;
            frame.depth = read_kinect_depth_pgm(path);
            frame.rgb = rgb_;
            return frame;
        }
    }
    return std::nullopt;
}

}  // namespace esf
