// libFuzzer target: esf::read_xyz on arbitrary bytes. A malformed input must throw esf::IoError;
// anything else (a crash, a sanitizer report, another exception, a huge allocation) is a bug.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "esf/core/error.hpp"
#include "esf/io/cloud_io.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(esf::fuzz::bytes_of(data, size)));
    try {
        const esf::PointCloud cloud = esf::read_xyz(in, "cloud.xyz");
        // What every reader promises: width x height points, labels absent or one per point.
        if (std::uint64_t{cloud.width} * cloud.height != cloud.points.size()) __builtin_trap();
        if (!cloud.labels.empty() && cloud.labels.size() != cloud.points.size()) __builtin_trap();
    } catch (const esf::IoError&) {
    }
    return 0;
}
