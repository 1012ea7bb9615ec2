#pragma once
// What verification's candidates give for one object (the studies of the choice among them and
// of fusion rules): the object described and matched, then every candidate fitted, each fit
// complete (Recognizer::verify's `candidates`).

#include <optional>
#include <vector>

#include "esf/recognition/recognizer.hpp"

namespace esf::bench {

struct CandidateFits {
    Classification knn;              ///< the k-NN classification, before verification
    std::vector<CandidateFit> fits;  ///< CandidateFit::neighbour indexes knn.neighbours
};

/// Nothing when the points cannot be described (too few).
inline std::optional<CandidateFits> fit_candidates(const Recognizer& recognizer,
                                                   const Points& points, const PointCloud* frame) {
    const QueryDescriptor d = recognizer.describe(points);
    if (!d.ok()) return std::nullopt;
    CandidateFits out;
    out.knn = recognizer.classify_descriptor(d.signatures);
    Classification verified = out.knn;
    recognizer.verify(verified, Observation{points, frame}, nullptr, &out.fits);
    return out;
}

}  // namespace esf::bench
