// Google Benchmark of point-cloud reading in memory: one real cloud (a 640 x 480 mOSD scene with
// labels, else a generated one) encoded as PCD ascii / binary / binary_compressed and as binary
// PLY, then parsed from memory per iteration (no disk). Also the PCD writers and LZF alone:
// compressing the columns, and decoding the binary_compressed block of real scenes as stored.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_data.hpp"
#include "esf/io/cloud_io.hpp"
#include "io/lzf.hpp"

namespace {

/// The labelled scene of the shared data, or 307,200 points of a noisy wave with NaN holes.
const esf::PointCloud& sample() {
    static const esf::PointCloud cloud = [] {
        const auto file = esf::bench::data_dir() / "real/scenes/mosd_learn0.pcd";
        if (std::filesystem::exists(file)) return esf::read_pcd(file.string());
        esf::PointCloud c;
        std::mt19937 rng(3);
        std::normal_distribution<float> noise(0.0f, 0.002f);
        c.width = 640;
        c.height = 480;
        for (std::uint32_t v = 0; v < c.height; ++v) {
            for (std::uint32_t u = 0; u < c.width; ++u) {
                const float x = 0.002f * static_cast<float>(u), y = 0.002f * static_cast<float>(v);
                const float z = (u * 7 + v * 3) % 97 == 0 ? NAN : 1.0f + 0.1f * std::sin(x * 9.0f);
                c.points.emplace_back(x, y, z + noise(rng));
                c.labels.push_back((u / 64 + v / 48) % 7);
            }
        }
        return c;
    }();
    return cloud;
}

std::string encoded(esf::PcdEncoding encoding) {
    std::ostringstream out;
    esf::write_pcd(out, sample(), encoding);
    return out.str();
}

/// Binary little-endian PLY: x y z float, then label as uint.
std::string ply_bytes() {
    const esf::PointCloud& c = sample();
    std::string out = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                      std::to_string(c.points.size()) +
                      "\nproperty float x\nproperty float y\nproperty float z\n"
                      "property uint label\nend_header\n";
    for (std::size_t i = 0; i < c.points.size(); ++i) {
        char raw[16];
        std::memcpy(raw, c.points[i].data(), 12);
        std::memcpy(raw + 12, &c.labels[i], 4);
        out.append(raw, 16);
    }
    return out;
}

void read_bench(benchmark::State& state, const std::string& bytes, bool ply) {
    for (auto _ : state) {
        const esf::PointCloud cloud =
            ply ? esf::parse_ply_cloud(bytes, "mem.ply") : esf::parse_pcd(bytes, "mem.pcd");
        benchmark::DoNotOptimize(cloud.points.data());
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(sample().points.size()));
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(bytes.size()));
    state.SetLabel(std::to_string(bytes.size() / 1024) + " KiB");
}

void BM_ReadPcdBinary(benchmark::State& state) {
    read_bench(state, encoded(esf::PcdEncoding::kBinary), false);
}
BENCHMARK(BM_ReadPcdBinary)->Unit(benchmark::kMillisecond);

void BM_ReadPcdBinaryCompressed(benchmark::State& state) {
    read_bench(state, encoded(esf::PcdEncoding::kBinaryCompressed), false);
}
BENCHMARK(BM_ReadPcdBinaryCompressed)->Unit(benchmark::kMillisecond);

void BM_ReadPcdAscii(benchmark::State& state) {
    read_bench(state, encoded(esf::PcdEncoding::kAscii), false);
}
BENCHMARK(BM_ReadPcdAscii)->Unit(benchmark::kMillisecond);

void BM_ReadPlyBinary(benchmark::State& state) { read_bench(state, ply_bytes(), true); }
BENCHMARK(BM_ReadPlyBinary)->Unit(benchmark::kMillisecond);

void BM_WritePcd(benchmark::State& state) {
    const auto encoding = static_cast<esf::PcdEncoding>(state.range(0));
    std::size_t bytes = 0;
    for (auto _ : state) {
        std::ostringstream out;
        esf::write_pcd(out, sample(), encoding);
        bytes = out.str().size();
        benchmark::DoNotOptimize(bytes);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(sample().points.size()));
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(bytes));
    state.SetLabel(state.range(0) == 0 ? "ascii" : state.range(0) == 1 ? "binary" : "compressed");
}
BENCHMARK(BM_WritePcd)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_LzfCompressColumns(benchmark::State& state) {
    // The x, y, z, label blocks that binary_compressed stores.
    const esf::PointCloud& c = sample();
    const std::size_t n = c.points.size();
    std::vector<unsigned char> raw(16 * n);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t a = 0; a < 3; ++a) std::memcpy(&raw[4 * (a * n + i)], &c.points[i][a], 4);
        std::memcpy(&raw[4 * (3 * n + i)], &c.labels[i], 4);
    }
    std::vector<unsigned char> packed(esf::detail::lzf_compress_bound(raw.size()));
    std::size_t size = 0;
    for (auto _ : state) {
        size = esf::detail::lzf_compress(raw, packed);
        benchmark::DoNotOptimize(size);
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(raw.size()));
    state.SetLabel("ratio " +
                   std::to_string(static_cast<double>(raw.size()) / static_cast<double>(size)));
}
BENCHMARK(BM_LzfCompressColumns)->Unit(benchmark::kMillisecond);

/// The LZF block of a real binary_compressed scene, as the file stores it after
/// "DATA binary_compressed": compressed size, uncompressed size (uint32 each), then the stream.
struct LzfBlock {
    std::vector<unsigned char> packed;
    std::size_t size = 0;  ///< bytes it decodes to
    std::string problem;   ///< why there is no block; empty when there is one
};

LzfBlock scene_block(const std::string& name) {
    LzfBlock block;
    const auto file = esf::bench::data_dir() / "real/scenes" / name;
    std::ifstream in(file, std::ios::binary);
    if (!in) {
        block.problem = file.string() + " not found (set ESF_DATA to the shared data folder)";
        return block;
    }
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string tag = "\nDATA binary_compressed\n";
    const std::size_t at = bytes.find(tag);
    std::uint32_t sizes[2] = {0, 0};  // compressed, uncompressed
    if (at == std::string::npos || bytes.size() - at - tag.size() < sizeof sizes) {
        block.problem = file.string() + " is not binary_compressed";
        return block;
    }
    std::memcpy(sizes, bytes.data() + at + tag.size(), sizeof sizes);
    const std::size_t start = at + tag.size() + sizeof sizes;
    if (bytes.size() - start < sizes[0]) {
        block.problem = file.string() + ": LZF block cut off";
        return block;
    }
    block.packed.assign(bytes.begin() + static_cast<std::ptrdiff_t>(start),
                        bytes.begin() + static_cast<std::ptrdiff_t>(start + sizes[0]));
    block.size = sizes[1];
    return block;
}

/// lzf_decompress alone on a real scene's block (640 x 480 points); bytes/s counts the output.
void BM_LzfDecompressScene(benchmark::State& state, const std::string& name) {
    const LzfBlock block = scene_block(name);
    if (!block.problem.empty()) {
        state.SkipWithError(block.problem.c_str());
        return;
    }
    std::vector<unsigned char> out(block.size);
    const esf::detail::LzfDecoded first = esf::detail::lzf_decompress(block.packed, out);
    if (first.error || first.produced != block.size) {
        state.SkipWithError((name + ": LZF block does not decode").c_str());
        return;
    }
    for (auto _ : state) {
        const esf::detail::LzfDecoded decoded = esf::detail::lzf_decompress(block.packed, out);
        benchmark::DoNotOptimize(decoded.produced);
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(block.size));
    state.SetLabel(std::to_string(block.packed.size() / 1024) + " KiB -> " +
                   std::to_string(block.size / 1024) + " KiB");
}
/// The same block with only its first four fifths written (label, x, y, z of an mOSD scene; the
/// colour block is checked, not written), as read_pcd decodes it.
void BM_LzfDecompressSceneWithoutColours(benchmark::State& state, const std::string& name) {
    const LzfBlock block = scene_block(name);
    if (!block.problem.empty()) {
        state.SkipWithError(block.problem.c_str());
        return;
    }
    std::vector<unsigned char> out(block.size / 5 * 4);
    for (auto _ : state) {
        const esf::detail::LzfDecoded decoded =
            esf::detail::lzf_decompress(block.packed, out, block.size);
        if (decoded.error || decoded.produced != block.size) {
            state.SkipWithError((name + ": LZF block does not decode").c_str());
            return;
        }
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(block.size));
}
BENCHMARK_CAPTURE(BM_LzfDecompressSceneWithoutColours, mosd_learn0, std::string("mosd_learn0.pcd"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LzfDecompressSceneWithoutColours, mosd_learn20,
                  std::string("mosd_learn20.pcd"))
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_CAPTURE(BM_LzfDecompressScene, mosd_learn0, std::string("mosd_learn0.pcd"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LzfDecompressScene, mosd_learn20, std::string("mosd_learn20.pcd"))
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
