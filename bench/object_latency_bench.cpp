// Time to recognise one segmented object on one thread with the default pipeline: describing the
// cloud with the database's descriptor (esf-angles: ESF + surface angles), matching it (the ten
// nearest models, each by its nearest view, exact L1), and both. The clouds are the 116 real
// views of real/labels.csv, taken in turn, one per iteration. The goal is describe + match
// <= 2 ms per object on one thread. BM_Verify times the verification added to a classification
// (the candidates' meshes loaded beforehand): its goal is <= 2 ms per object; BM_VerifyTwoWay
// the same with two-way ICP (VerificationOptions::two_way).
//
//   object_latency_bench [--db PATH] [benchmark flags]
//
// --db: a training database (default $ESF_BENCH_DB). Without one, the default database of the
// shared meshes ($ESF_DATA/meshes) is trained once into the temporary folder
// (esf_bench_default.sqlite, about 20 s on 2 cores) and reused by later runs.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "esf/io/cloud_io.hpp"
#include "esf/recognition/recognizer.hpp"
#include "esf/training/database.hpp"
#include "esf/training/training.hpp"

namespace fs = std::filesystem;

namespace {

std::unique_ptr<esf::Recognizer> g_recognizer;
std::unique_ptr<esf::Recognizer> g_verifier;  // the same database, verifying
std::unique_ptr<esf::Recognizer> g_two_way;   // the same, with two-way ICP
std::vector<esf::Classification> g_classes;
std::vector<esf::Points> g_clouds;
std::vector<esf::QueryDescriptor> g_descriptors;

void BM_Describe(benchmark::State& state) {
    std::size_t i = 0;
    for (auto _ : state) {
        esf::QueryDescriptor d = g_recognizer->describe(g_clouds[i]);
        benchmark::DoNotOptimize(d.signatures.data());
        i = (i + 1) % g_clouds.size();
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Describe)->Unit(benchmark::kMillisecond);

void BM_Match(benchmark::State& state) {
    std::size_t i = 0;
    for (auto _ : state) {
        esf::Classification c = g_recognizer->classify_descriptor(g_descriptors[i].signatures);
        benchmark::DoNotOptimize(c.best_distance);
        i = (i + 1) % g_descriptors.size();
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Match)->Unit(benchmark::kMillisecond);

/// Matching as a frame's objects are matched: four described objects in one batch, one thread
/// (time per object).
void BM_MatchBatchOfFour(benchmark::State& state) {
    constexpr std::size_t kObjects = 4;
    std::size_t i = 0;
    for (auto _ : state) {
        std::vector<esf::QueryDescriptor> batch;
        for (std::size_t k = 0; k < kObjects; ++k)
            batch.push_back(g_descriptors[(i + k) % g_descriptors.size()]);
        const std::vector<esf::CloudClassification> c = g_recognizer->classify_batch(batch);
        benchmark::DoNotOptimize(c.data());
        i = (i + kObjects) % g_descriptors.size();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kObjects));
    state.counters["per_object_ms"] =
        benchmark::Counter(static_cast<double>(state.iterations() * kObjects),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_MatchBatchOfFour)->Unit(benchmark::kMillisecond);

void BM_DescribeAndMatch(benchmark::State& state) {
    std::size_t i = 0;
    for (auto _ : state) {
        esf::Classification c = g_recognizer->classify(g_clouds[i]);
        benchmark::DoNotOptimize(c.best_distance);
        i = (i + 1) % g_clouds.size();
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DescribeAndMatch)->Unit(benchmark::kMillisecond);

void verify_each(benchmark::State& state, const esf::Recognizer& verifier) {
    std::size_t i = 0;
    for (auto _ : state) {
        esf::Classification c = g_classes[i];
        verifier.verify(c, esf::Observation{g_clouds[i], nullptr});
        benchmark::DoNotOptimize(c.fit);
        i = (i + 1) % g_clouds.size();
    }
    state.SetItemsProcessed(state.iterations());
}

void BM_Verify(benchmark::State& state) { verify_each(state, *g_verifier); }
BENCHMARK(BM_Verify)->Unit(benchmark::kMillisecond);

void BM_VerifyTwoWay(benchmark::State& state) { verify_each(state, *g_two_way); }
BENCHMARK(BM_VerifyTwoWay)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
    const char* env_db = std::getenv("ESF_BENCH_DB");
    std::string db_path = env_db && *env_db ? env_db : "";
    std::vector<char*> rest = {argv[0]};
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--db" && i + 1 < argc)
            db_path = argv[++i];
        else
            rest.push_back(argv[i]);
    }
    int rest_count = static_cast<int>(rest.size());
    benchmark::Initialize(&rest_count, rest.data());

    const fs::path data = esf::bench::data_dir();
    const fs::path labels = data / "real" / "labels.csv";
    if (!fs::exists(labels) || !fs::is_directory(data / "meshes")) {
        std::fprintf(stderr, "object_latency_bench: no shared data in %s (set ESF_DATA)\n",
                     data.c_str());
        return 1;
    }
    try {
        if (db_path.empty()) {
            db_path = (fs::temp_directory_path() / "esf_bench_default.sqlite").string();
            if (!fs::exists(db_path)) {
                std::fprintf(stderr, "training the default database of %s into %s ...\n",
                             (data / "meshes").c_str(), db_path.c_str());
                const std::string partial = db_path + ".partial";
                fs::remove(partial);
                {
                    esf::Database db(partial, esf::OpenMode::kWrite);
                    esf::train((data / "meshes").string(), db);
                }
                fs::rename(partial, db_path);
            }
        }
        esf::RecognizerOptions options;
        options.threads = 1;
        options.verify = false;
        g_recognizer = std::make_unique<esf::Recognizer>(db_path, options);
        for (const esf::TestSample& s : esf::read_test_set(labels.string()).samples)
            g_clouds.push_back(esf::read_cloud(s.file).points);
        options.verify = true;  // with the stored surfaces; the meshes for an older database
        g_verifier = std::make_unique<esf::Recognizer>(db_path, options);
        if (!g_verifier->verifies()) {
            options.verification_meshes = (data / "meshes").string();
            g_verifier = std::make_unique<esf::Recognizer>(db_path, options);
        }
        options.verification.two_way = true;
        g_two_way = std::make_unique<esf::Recognizer>(db_path, options);
        for (esf::Points& cloud : g_clouds) cloud = esf::drop_non_finite(cloud).points;
        for (const esf::Points& cloud : g_clouds) {
            g_descriptors.push_back(g_recognizer->describe(cloud));
            if (!g_descriptors.back().ok())
                throw std::invalid_argument("a real view cannot be described: " +
                                            g_descriptors.back().error);
            g_classes.push_back(g_recognizer->classify_descriptor(g_descriptors.back().signatures));
            esf::Classification warm = g_classes.back();  // loads the candidates' meshes
            g_verifier->verify(warm, esf::Observation{cloud, nullptr});
            esf::Classification warm_two_way = g_classes.back();
            g_two_way->verify(warm_two_way, esf::Observation{cloud, nullptr});
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "object_latency_bench: %s\n", e.what());
        return 1;
    }
    const esf::RecognizerInfo& info = g_recognizer->info();
    std::fprintf(stderr, "database %s: %zu views of %zu models, %s; %zu real clouds, 1 thread\n",
                 db_path.c_str(), info.views, info.models, info.setup.kind.name.c_str(),
                 g_clouds.size());
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
