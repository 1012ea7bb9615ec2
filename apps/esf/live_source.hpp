#pragma once
// Where `esf live` gets its frames: a Kinect through libfreenect (or fakenect, libfreenect's
// stand-in that plays a recording back), or a recording read straight from its folder.
//
// A source hands over the newest frame; a frame that arrives while the previous one still
// waits replaces it and is counted as skipped, so a slow consumer always gets the latest frame
// and never a queue of old ones. Waiting is bounded: next() returns after `timeout` at the
// latest, so a device that stops sending cannot hang the program.

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>

#include "esf/io/kinect_recording.hpp"

namespace esf::cli {

enum class FrameWait {
    kFrame,    ///< a frame was handed over
    kTimeout,  ///< none arrived within the timeout (the source may still deliver later)
    kEnded,    ///< the recording ended: no frame will come
    kFailed,   ///< the device failed or was lost: message() says how
};

class FrameSource {
  public:
    virtual ~FrameSource() = default;
    /// Waits up to `timeout` for the next frame.
    virtual FrameWait next(KinectFrame& frame, std::chrono::milliseconds timeout) = 0;
    /// Frames replaced before they were taken.
    virtual std::size_t skipped() const = 0;
    /// Why the source failed (kFailed), for one error line.
    virtual std::string message() const = 0;
    /// "Kinect 0", "fakenect recording DIR", "recording DIR".
    virtual std::string name() const = 0;
    /// Stops the device; returns false when its driver did not stop within a second (then it
    /// is left running, detached, and the program may end regardless).
    virtual bool stop() = 0;
};

/// Frames of a recording folder as fast as they are asked for (no pacing, nothing skipped).
/// Throws esf::IoError naming a bad recording.
std::unique_ptr<FrameSource> open_recording_source(const std::string& folder);

/// Whether this build has libfreenect.
bool kinect_supported();
/// Whether the libfreenect in this process is fakenect (libfreenect-bin's playback library,
/// put first on the library path by the `fakenect` script).
bool kinect_driver_is_fakenect();
/// Opens Kinect `device` in the 11-bit raw depth mode and RGB colour, 640 x 480, and starts a
/// thread that runs the driver. Under fakenect the recording named by FAKENECT_PATH is checked
/// first (fakenect itself ends the program on a missing file). Throws std::runtime_error with one
/// line saying what is missing: no device, a device that cannot be opened, or a build without
/// libfreenect (and how to get it).
std::unique_ptr<FrameSource> open_kinect_source(int device);

}  // namespace esf::cli
