// TraceKernelTrials: which line tracer is fastest on this CPU, by timing the real work.

#include <algorithm>
#include <limits>

#include "descriptors/esf/esf_trace.hpp"
#include "descriptors/esf/esf_trace_kernels.hpp"

namespace esf::detail {

TraceKernelTrials::TraceKernelTrials() {
    candidates_.push_back(Kernels::kBest);  // the widest
    const Tracer widest = widest_tracer();
    if (widest == Tracer::kAvx512Popcount) candidates_.push_back(Kernels::kAvx512);
    if (widest >= Tracer::kAvx512) candidates_.push_back(Kernels::kAvx2);
    best_.assign(candidates_.size(), std::numeric_limits<double>::infinity());
    dropped_.assign(candidates_.size(), false);
    decided_ = candidates_.size() == 1;
}

Kernels TraceKernelTrials::next() const { return decided_ ? chosen_ : candidates_[turn_]; }

void TraceKernelTrials::record(Kernels kernels, double seconds, std::size_t cells) {
    if (decided_) return;
    if (warm_up_left_ > 0) {
        --warm_up_left_;
        return;
    }
    const auto k = static_cast<std::size_t>(
        std::find(candidates_.begin(), candidates_.end(), kernels) - candidates_.begin());
    if (k < best_.size())
        best_[k] =
            std::min(best_[k], seconds / static_cast<double>(std::max<std::size_t>(cells, 1)));
    // The next candidate still in the trials, or the end of the round.
    do {
        if (++turn_ == candidates_.size()) {
            end_round();
            return;
        }
    } while (dropped_[turn_]);
}

void TraceKernelTrials::end_round() {
    turn_ = 0;  // the widest is never dropped
    ++rounds_;
    bool others_left = false;
    for (std::size_t c = 1; c < candidates_.size(); ++c) {
        if (best_[c] > (1.0 + kDrop) * best_[0]) dropped_[c] = true;
        others_left = others_left || !dropped_[c];
    }
    if (rounds_ < kRounds && others_left) return;
    // The widest (candidate 0) unless another is faster by the margin.
    std::size_t choice = 0;
    for (std::size_t c = 1; c < best_.size(); ++c)
        if (!dropped_[c] && best_[c] < (1.0 - kMargin) * best_[0] && best_[c] < best_[choice])
            choice = c;
    chosen_ = candidates_[choice];
    decided_ = true;
}

}  // namespace esf::detail
