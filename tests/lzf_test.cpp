// LZF (src/lzf.cpp): round trips over awkward inputs, the worst-case bound, corrupt input, and
// PCL's liblzf as the oracle both ways (PCL decodes what we encode; we decode what PCL encodes).

#include "lzf.hpp"

#include <gtest/gtest.h>
#ifdef ESF_TEST_WITH_PCL  // PCL as the oracle
#include <pcl/io/lzf.h>
#endif

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace {

using Bytes = std::vector<unsigned char>;
using esf::detail::lzf_compress;
using esf::detail::lzf_compress_bound;
using esf::detail::lzf_decompress;

Bytes compress(const Bytes& raw) {
    Bytes packed(lzf_compress_bound(raw.size()));
    packed.resize(lzf_compress(raw, packed));
    return packed;
}

Bytes decompress(const Bytes& packed, std::size_t size) {
    Bytes raw(size);
    const auto decoded = lzf_decompress(packed, raw);
    EXPECT_EQ(decoded.error, nullptr) << decoded.error;
    EXPECT_EQ(decoded.produced, size);
    return raw;
}

Bytes random_bytes(std::size_t n, std::uint32_t seed) {
    std::mt19937 gen(seed);
    Bytes out(n);
    for (auto& b : out) b = static_cast<unsigned char>(gen() & 0xff);
    return out;
}

/// Inputs that exercise every token kind: empty, 1 byte, short, runs longer than the longest
/// back reference (264), repeats further than the longest distance (8192), noise.
std::vector<std::pair<std::string, Bytes>> inputs() {
    std::vector<std::pair<std::string, Bytes>> cases;
    cases.emplace_back("empty", Bytes{});
    cases.emplace_back("one byte", Bytes{42});
    cases.emplace_back("two bytes", Bytes{1, 1});
    cases.emplace_back("three equal bytes", Bytes{7, 7, 7});
    cases.emplace_back("zeros 100000", Bytes(100000, 0));
    Bytes text;
    const std::string phrase = "the ensemble of shape functions, ";
    while (text.size() < 50000) text.insert(text.end(), phrase.begin(), phrase.end());
    cases.emplace_back("repeated phrase", text);
    cases.emplace_back("random 1", random_bytes(1, 1));
    cases.emplace_back("random 31", random_bytes(31, 2));
    cases.emplace_back("random 32", random_bytes(32, 3));
    cases.emplace_back("random 33", random_bytes(33, 4));
    cases.emplace_back("random 70000", random_bytes(70000, 5));
    // A random block repeated beyond the farthest distance LZF can reach.
    Bytes far = random_bytes(9000, 6);
    const Bytes copy = far;
    far.insert(far.end(), copy.begin(), copy.end());
    cases.emplace_back("repeat at 9000", far);
    // Floats of a smooth surface, like a PCD column.
    Bytes floats(4 * 30000);
    for (std::size_t i = 0; i < 30000; ++i) {
        const float v = 0.5f + 0.001f * static_cast<float>(i % 640);
        std::memcpy(floats.data() + 4 * i, &v, 4);
    }
    cases.emplace_back("float column", floats);
    // Short repeats interleaved with noise: many literal runs cut by 3-byte matches.
    Bytes mixed = random_bytes(20000, 7);
    for (std::size_t i = 8; i + 3 < mixed.size(); i += 7) {
        std::memcpy(mixed.data() + i, mixed.data() + i - 8, 3);
    }
    cases.emplace_back("mixed", mixed);
    return cases;
}

TEST(Lzf, RoundTripsWithinTheBound) {
    for (const auto& [name, raw] : inputs()) {
        SCOPED_TRACE(name);
        const Bytes packed = compress(raw);
        EXPECT_LE(packed.size(), lzf_compress_bound(raw.size()));
        EXPECT_EQ(decompress(packed, raw.size()), raw);
    }
}

TEST(Lzf, CompressesRepetitiveInputAndBarelyGrowsNoise) {
    const Bytes zeros(100000, 0);
    EXPECT_LT(compress(zeros).size(), zeros.size() / 50);  // 264 bytes per 3-byte token
    const Bytes noise = random_bytes(70000, 5);
    const Bytes packed = compress(noise);
    EXPECT_GE(packed.size(), noise.size());  // incompressible: literal runs
    EXPECT_LE(packed.size(), noise.size() + noise.size() / 32 + 1);
    EXPECT_EQ(compress(Bytes{}).size(), 0u);
    EXPECT_EQ(compress(Bytes{42}), (Bytes{0, 42}));  // one literal run of one byte
}

TEST(Lzf, IsDeterministic) {
    const Bytes raw = inputs().back().second;
    EXPECT_EQ(compress(raw), compress(raw));
}

TEST(Lzf, RefusesAnOutputBelowTheBound) {
    const Bytes raw = random_bytes(100, 1);
    Bytes small(raw.size());
    EXPECT_THROW(lzf_compress(raw, small), std::invalid_argument);
}

TEST(Lzf, CorruptInputIsReportedNotOverrun) {
    Bytes out(16);
    // A back reference first: nothing to refer to.
    auto r = lzf_decompress(Bytes{0x20, 0x00}, out);
    EXPECT_STREQ(r.error, "back reference before the start of the output");
    // A literal run of 32 with 2 bytes present.
    r = lzf_decompress(Bytes{0x1f, 'a', 'b'}, out);
    EXPECT_STREQ(r.error, "literal run past the end");
    EXPECT_EQ(r.at, 1u);
    // More output than room.
    r = lzf_decompress(Bytes{0x00, 'a', 0xe0, 0xff, 0x00}, out);
    EXPECT_STREQ(r.error, "output exceeds stated size");
    // A long back reference cut off after its length byte.
    r = lzf_decompress(Bytes{0x00, 'a', 0xe0, 0x01}, out);
    EXPECT_STREQ(r.error, "back reference cut off");
}

TEST(Lzf, PrefixesAndGarbageStayInBounds) {
    // Every prefix of a valid block decodes to a prefix of the input or reports an error.
    const Bytes raw = inputs().back().second;
    const Bytes packed = compress(raw);
    Bytes out(raw.size());
    for (std::size_t n = 0; n <= packed.size(); n += 7) {
        const auto r = lzf_decompress({packed.data(), n}, out);
        ASSERT_LE(r.produced, raw.size());
        if (!r.error) {
            ASSERT_TRUE(
                std::equal(out.begin(), out.begin() + static_cast<long>(r.produced), raw.begin()));
        }
    }
    // Random bytes into random room: never more than the room (sanitizer builds check the rest).
    std::mt19937 gen(9);
    for (int trial = 0; trial < 3000; ++trial) {
        const Bytes garbage = random_bytes(gen() % 200, static_cast<std::uint32_t>(trial));
        Bytes room(gen() % 300);
        const auto r = lzf_decompress(garbage, room);
        ASSERT_LE(r.produced, room.size());
        ASSERT_LE(r.at, garbage.size());
    }
}

#ifdef ESF_TEST_WITH_PCL
TEST(LzfAgainstPcl, PclDecodesWhatWeEncode) {
    for (const auto& [name, raw] : inputs()) {
        if (raw.empty()) continue;  // PCL's decoder treats an empty block as an error
        SCOPED_TRACE(name);
        const Bytes packed = compress(raw);
        Bytes back(raw.size());
        const unsigned int produced =
            pcl::lzfDecompress(packed.data(), static_cast<unsigned int>(packed.size()), back.data(),
                               static_cast<unsigned int>(back.size()));
        EXPECT_EQ(produced, raw.size());
        EXPECT_EQ(back, raw);
    }
}
#endif

#ifdef ESF_TEST_WITH_PCL
TEST(LzfAgainstPcl, WeDecodeWhatPclEncodes) {
    for (const auto& [name, raw] : inputs()) {
        if (raw.size() < 4) continue;  // PCL's encoder refuses tiny inputs (returns 0)
        SCOPED_TRACE(name);
        Bytes packed(raw.size() * 2 + 64);
        const unsigned int size =
            pcl::lzfCompress(raw.data(), static_cast<unsigned int>(raw.size()), packed.data(),
                             static_cast<unsigned int>(packed.size()));
        ASSERT_GT(size, 0u);
        packed.resize(size);
        EXPECT_EQ(decompress(packed, raw.size()), raw);
    }
}
#endif

}  // namespace
