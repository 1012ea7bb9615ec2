// The README's library example, built with the project so that it keeps compiling:
//   classify_cloud DB CLOUD    prints the ESF descriptor's first bin and the cloud's class.

#include <cstdio>
#include <exception>

#include "esf/descriptors/esf/esf_descriptor.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: classify_cloud DB CLOUD\n");
        return 1;
    }
    try {
        esf::PointCloud cloud = esf::read_cloud(argv[2]);
        esf::EsfOptions options;  // 20,000 samples, 64^3 grid, seed 0, fast sampler
        esf::EsfResult r = esf::compute_esf(cloud.points, options);  // NaN points are dropped
        // r.descriptor: std::array<float, 640>, L1-normalised

        esf::Recognizer recognizer(argv[1]);  // esf train ... -o DB
        esf::Classification c = recognizer.classify(cloud.points);
        // c.class_name, c.confidence, c.best_model, c.best_view, c.pose (model -> camera)
        std::printf("descriptor[0] %.6f: %s (%.0f %% of the votes; model %s, view %d)\n",
                    r.descriptor[0], c.class_name.c_str(), 100.0 * c.confidence,
                    c.best_model.c_str(), c.best_view);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "classify_cloud: %s\n", e.what());
        return 2;
    }
    return 0;
}
