#pragma once
// Internal: runs a helper executable of esf (esf_baseline_child, esf_mesh_import) as a separate
// process, so that a crash, abort or hang of the code it runs (PCL's OURCVFHEstimation, Assimp)
// ends that process only. The helper is started with posix_spawn (never fork(): the caller may
// have worker threads), with an empty environment and its stderr on /dev/null; the request goes
// to its stdin and its reply is read from its stdout.

#include <optional>
#include <string>
#include <vector>

namespace esf::detail {

/// Bounds on a helper's run.
struct ChildLimits {
    /// Wall time from the start until the helper has exited; past it the helper is killed with
    /// SIGKILL. None: no bound.
    std::optional<double> seconds;
    /// Most reply bytes kept; a helper that writes more is killed with SIGKILL.
    std::size_t max_reply_bytes = std::size_t{1} << 32;
};

/// How a helper's run ended, and what it wrote to stdout.
struct ChildResult {
    enum class End {
        kExited,         ///< exited; `code` is its exit status
        kSignalled,      ///< killed by signal `code`
        kTimedOut,       ///< still running at the deadline: killed
        kReplyTooLarge,  ///< wrote more than max_reply_bytes: killed
    };
    End end = End::kExited;
    int code = 0;
    std::string reply;
};

/// Starts `helper` with the arguments `args` (argv[1..]), writes `request` to its stdin, reads
/// its stdout to the end and waits for it. Throws std::runtime_error("cannot start HELPER: ...")
/// when the process cannot be started (pipes, posix_spawn). SIGPIPE from a helper that exits
/// without reading its request is kept from the calling thread.
ChildResult run_child(const std::string& helper, const std::vector<std::string>& args,
                      const std::string& request, const ChildLimits& limits);

/// "signal N" or "exit status N", for messages.
std::string describe_end(const ChildResult& result);

/// The helper's side: writes all of `bytes` to its stdout (retrying after EINTR); false when the
/// parent stopped reading.
bool write_reply(const std::string& bytes);

}  // namespace esf::detail
