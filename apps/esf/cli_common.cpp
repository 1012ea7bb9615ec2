#include "cli_common.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>

namespace esf::cli {

namespace {
double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}
}  // namespace

bool stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(stderr_is_terminal()),
      start_(now_seconds()) {}

Progress::~Progress() { finish(); }

void Progress::update(std::size_t done, const std::string& detail) {
    if (!enabled_ || finished_) return;
    const double t = now_seconds();
    if (done < total_ && t - last_draw_ < 0.1) return;
    last_draw_ = t;
    const double elapsed = t - start_;
    const double fraction = total_ ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r%s [%s] %zu/%zu %s ETA %.0fs   ", label_.c_str(), bar.c_str(), done,
                 total_, detail.c_str(), eta);
    std::fflush(stderr);
}

void Progress::finish() {
    if (!enabled_ || finished_) return;
    finished_ = true;
    std::fprintf(stderr, "\n");
}

}  // namespace esf::cli
