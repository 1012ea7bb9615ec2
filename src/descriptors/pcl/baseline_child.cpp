// esf_baseline_child: runs our-cvfh for the baselines module on one cloud read from stdin and
// writes the signatures to stdout (protocol: baseline_child.hpp). Started by the module with
// posix_spawn; a crash of PCL ends this process only.

#include "descriptors/pcl/baseline_child.hpp"

#include <unistd.h>

#include <cerrno>
#include <exception>
#include <iterator>
#include <string>

#include "core/child_process.hpp"

#if defined(__SANITIZE_ADDRESS__)
// make sanitize: inside libpcl_features (not instrumented), OURCVFHEstimation's
// computeRFAndShapeDistribution frees memory it took with malloc through operator delete (both end
// in glibc's free), which ASan reports as alloc-dealloc-mismatch. This process runs only that PCL
// code and is started with an empty environment, so the exception is built in here, for it alone.
extern "C" const char* __asan_default_options() { return "alloc_dealloc_mismatch=0"; }
#endif

int main() {
    std::string request;
    char buffer[1 << 16];
    for (;;) {
        const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof buffer);
        if (n > 0) {
            request.append(buffer, static_cast<std::size_t>(n));
        } else if (n == 0) {
            break;
        } else if (errno != EINTR) {
            return 3;
        }
    }
    std::string reply;
    try {
        esf::Points points;
        esf::DescriptorOptions options;
        esf::detail::decode_child_request(request, points, options);
        reply = esf::detail::encode_child_reply(
            esf::detail::our_cvfh_signatures(points, options, "our-cvfh"));
    } catch (const std::exception& e) {
        reply = esf::detail::encode_child_error(e.what());
    }
    return esf::detail::write_reply(reply) ? 0 : 3;
}
