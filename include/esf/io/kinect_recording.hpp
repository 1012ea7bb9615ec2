#pragma once
// Kinect recordings in the format of libfreenect's fakenect-record, which fakenect plays back
// in place of a device:
//
//   DIR/INDEX.txt                  one file name a line, in the order they are served
//   DIR/d-TIME-TIMESTAMP.pgm       depth: the line "P5 640 480 65535", then 640 x 480 raw
//                                  11-bit values, 16 bits little-endian each (the device's own
//                                  byte order, not PGM's), 2047 = no reading
//   DIR/r-TIME-TIMESTAMP.ppm       colour: the line "P6 640 480 255", then 640 x 480 x 3 bytes
//   DIR/a-TIME-TIMESTAMP.dump      accelerometer state (read past, never written here)
//
// TIME is seconds with six decimals (fakenect waits the difference between two lines' TIMEs
// before serving the second), TIMESTAMP the device's 32-bit frame clock. The writer puts each
// frame's colour line before its depth line, so that a depth frame comes with the colour taken
// with it; the reader pairs each depth frame with the last colour frame before it.
//
// Readers of outside bytes: every header, name and size is checked before use; a bad file is
// one esf::IoError naming it (and the line of INDEX.txt).

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace esf {

/// One frame of a Kinect: raw depth and optional colour.
struct KinectFrame {
    double time = 0.0;                 ///< seconds, the recording's clock
    std::uint32_t timestamp = 0;       ///< the device's frame clock
    std::vector<std::uint16_t> depth;  ///< kKinectFramePixels raw 11-bit values, row-major
    std::vector<std::uint8_t> rgb;     ///< empty or kKinectFramePixels x 3 bytes (R, G, B)
};

/// The depth file of a frame. Throws esf::IoError naming `name` for a header other than
/// "P5 640 480 65535" on one line, a short body, or a value above 2047 (naming the pixel).
std::vector<std::uint16_t> read_kinect_depth_pgm(std::istream& in, const std::string& name);
std::vector<std::uint16_t> read_kinect_depth_pgm(const std::string& path);
/// The colour file of a frame. Throws esf::IoError naming `name` for a header other than
/// "P6 640 480 255" on one line or a short body.
std::vector<std::uint8_t> read_kinect_rgb_ppm(std::istream& in, const std::string& name);
std::vector<std::uint8_t> read_kinect_rgb_ppm(const std::string& path);

/// Throw std::invalid_argument for a frame of the wrong size or with a value above 2047.
void write_kinect_depth_pgm(std::ostream& out, std::span<const std::uint16_t> depth);
void write_kinect_rgb_ppm(std::ostream& out, std::span<const std::uint8_t> rgb);

/// One line of INDEX.txt.
struct KinectRecordingEntry {
    char type = 'd';  ///< 'd' depth, 'r' colour, 'a' accelerometer
    double time = 0.0;
    std::uint32_t timestamp = 0;
    std::string file;  ///< the name as listed, relative to the folder
};

/// Parses INDEX.txt. Throws esf::IoError naming `name` and the line for a name that is not
/// TYPE-TIME-TIMESTAMP.EXT with TYPE d, r or a, that holds a '/', or a line longer than 255
/// characters.
std::vector<KinectRecordingEntry> parse_kinect_recording_index(std::istream& in,
                                                               const std::string& name);

/// Writes a recording frame by frame; finish() writes INDEX.txt, so that a recording without it
/// was not finished. Frames are written atomically, each under the name of its time.
class KinectRecordingWriter {
  public:
    /// Creates `folder` when missing. Throws esf::IoError when it cannot.
    explicit KinectRecordingWriter(std::string folder);
    /// Writes the frame (colour first when present). Throws std::invalid_argument for a bad
    /// frame or a time not after the previous frame's, esf::IoError for a file not written.
    void add(const KinectFrame& frame);
    /// Writes INDEX.txt and returns its path.
    std::string finish();
    std::size_t frames() const { return frames_; }

  private:
    std::string folder_;
    std::string index_;
    std::size_t frames_ = 0;
    double last_time_ = 0.0;
};

/// Reads a recording's frames in order without pacing (what fakenect serves, minus the waits).
class KinectRecordingReader {
  public:
    /// Reads and checks INDEX.txt and that every listed file is a regular file. Throws
    /// esf::IoError naming the folder or file.
    explicit KinectRecordingReader(std::string folder);
    /// The next depth frame with the last colour frame listed before it (empty when none), or
    /// nothing at the end. Throws esf::IoError naming a bad file.
    std::optional<KinectFrame> next();
    std::size_t depth_frames() const;  ///< depth lines in the index
    const std::vector<KinectRecordingEntry>& entries() const { return entries_; }
    const std::string& folder() const { return folder_; }

  private:
    std::string folder_;
    std::vector<KinectRecordingEntry> entries_;
    std::size_t next_ = 0;
    std::vector<std::uint8_t> rgb_;
};

}  // namespace esf
