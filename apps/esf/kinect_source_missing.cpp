// esf live without libfreenect: the recording source works, the Kinect says how to get it.

#include <stdexcept>

#include "live_source.hpp"

namespace esf::cli {

bool kinect_supported() { return false; }

bool kinect_driver_is_fakenect() { return false; }

std::unique_ptr<FrameSource> open_kinect_source(int) {
    throw std::runtime_error(
        "this esf was built without libfreenect: install it (Debian: apt-get install "
        "libfreenect-dev libfreenect-bin) and build again, or read a recording with "
        "--recording DIR");
}

}  // namespace esf::cli
