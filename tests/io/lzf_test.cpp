// LZF (src/io/lzf.cpp): round trips over awkward inputs, the worst-case bound, corrupt input, and
// PCL's liblzf as the oracle both ways (PCL decodes what we encode; we decode what PCL encodes).
// Hand-built token streams cover the decoder's fast loop and its edges: every short distance and
// length, runs and literal runs at the very ends of exact-size buffers, every truncation.

#include "io/lzf.hpp"

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

/// LZF tokens built by hand, with the bytes they decode to.
struct Stream {
    Bytes packed, raw;

    /// Literal runs (32 bytes at most each) of `bytes`.
    Stream& literal(const Bytes& bytes) {
        for (std::size_t i = 0; i < bytes.size(); i += 32) {
            const std::size_t n = std::min<std::size_t>(32, bytes.size() - i);
            packed.push_back(static_cast<unsigned char>(n - 1));
            packed.insert(packed.end(), bytes.begin() + static_cast<long>(i),
                          bytes.begin() + static_cast<long>(i + n));
        }
        raw.insert(raw.end(), bytes.begin(), bytes.end());
        return *this;
    }

    /// The tokens of a back reference of `len` (3..264) bytes at `distance` (1..8192).
    static Bytes reference_tokens(std::size_t distance, std::size_t len) {
        const std::size_t code = len - 2, offset = distance - 1;
        Bytes tokens;
        if (code < 7) {
            tokens.push_back(static_cast<unsigned char>((code << 5) | (offset >> 8)));
        } else {
            tokens.push_back(static_cast<unsigned char>((7 << 5) | (offset >> 8)));
            tokens.push_back(static_cast<unsigned char>(code - 7));
        }
        tokens.push_back(static_cast<unsigned char>(offset & 0xff));
        return tokens;
    }

    /// A back reference, decoded byte by byte.
    Stream& reference(std::size_t distance, std::size_t len) {
        const Bytes tokens = reference_tokens(distance, len);
        packed.insert(packed.end(), tokens.begin(), tokens.end());
        for (std::size_t k = 0; k < len; ++k) raw.push_back(raw[raw.size() - distance]);
        return *this;
    }
};

/// Decodes `packed` into `room` bytes followed by guard bytes, which must come back untouched
/// (a write past the end, caught in any build); then from a buffer of exactly its size into one
/// of exactly `room` bytes, so that sanitizer builds catch any read or write past either end;
/// then with the portable copies, which must agree.
std::pair<esf::detail::LzfDecoded, Bytes> decode_exact(const Bytes& packed, std::size_t room) {
    const Bytes in(packed);  // a copy holds exactly packed.size() bytes
    constexpr std::size_t kGuard = 64;
    Bytes guarded(room + kGuard, 0xa5);
    const auto first = lzf_decompress(in, {guarded.data(), room});
    const bool intact = std::all_of(guarded.begin() + static_cast<long>(room), guarded.end(),
                                    [](unsigned char b) { return b == 0xa5; });
    EXPECT_TRUE(intact) << "wrote past the end of the output";
    if (!intact) return {first, Bytes{}};  // the exact-size run would corrupt the heap

    Bytes out(room);
    const auto decoded = lzf_decompress(in, out);
    EXPECT_EQ(decoded.produced, first.produced);
    out.resize(std::min(decoded.produced, room));
    // The portable copies (always branching on the kind of token) give the same result.
    Bytes portable(room);
    const auto same = lzf_decompress(in, portable, room, esf::Kernels::kPortable);
    EXPECT_EQ(same.produced, decoded.produced);
    EXPECT_EQ(same.at, decoded.at);
    EXPECT_EQ(same.error == nullptr, decoded.error == nullptr);
    if (same.error && decoded.error) {
        EXPECT_STREQ(same.error, decoded.error);
    }
    portable.resize(std::min(same.produced, room));
    EXPECT_EQ(portable, out);
    return {decoded, out};
}

/// True when `part` is a prefix of `whole`.
bool is_prefix(const Bytes& part, const Bytes& whole) {
    return part.size() <= whole.size() && std::equal(part.begin(), part.end(), whole.begin());
}

TEST(Lzf, RoundTripsRunsOfEveryPeriodNearBothEnds) {
    // A run of period 1..20 (a back reference overlapping its own output, then references 264
    // bytes back) between random bytes, right at the start or the end of the output or with
    // room past it, so that it decodes in the fast loop, the careful one or across both.
    std::vector<std::size_t> lengths;
    for (std::size_t n = 1; n <= 40; ++n) lengths.push_back(n);
    for (std::size_t n : {63, 64, 65, 100, 263, 264, 265, 266, 300, 528, 529, 600}) {
        lengths.push_back(n);
    }
    const Bytes noise = random_bytes(1000, 11);
    for (std::size_t period = 1; period <= 20; ++period) {
        for (const std::size_t length : lengths) {
            for (const std::size_t before : {0, 1, 9, 300}) {
                for (const std::size_t after : {0, 1, 5, 33, 300}) {
                    Bytes raw(noise.begin(), noise.begin() + static_cast<long>(before));
                    for (std::size_t k = 0; k < length; ++k) {
                        raw.push_back(static_cast<unsigned char>(200 + k % period));
                    }
                    raw.insert(raw.end(), noise.end() - static_cast<long>(after), noise.end());
                    const auto [decoded, out] = decode_exact(compress(raw), raw.size());
                    ASSERT_EQ(decoded.error, nullptr)
                        << "period " << period << ", length " << length << ", " << before
                        << " bytes before, " << after << " after: " << decoded.error;
                    ASSERT_EQ(out, raw) << "period " << period << ", length " << length << ", "
                                        << before << " bytes before, " << after << " after";
                }
            }
        }
    }
}

TEST(Lzf, DecodesBackReferencesOfEveryDistanceAndLength) {
    // Every distance 1..40 and length 3..264, built by hand, with 0..300 bytes of output after
    // the reference: at the very end of an exact-size output, or inside the fast loop.
    const Bytes noise = random_bytes(340, 12);
    const Bytes prefix(noise.begin(), noise.begin() + 40);
    for (std::size_t distance = 1; distance <= 40; ++distance) {
        for (std::size_t len = 3; len <= 264; ++len) {
            for (const std::size_t after : {0, 1, 15, 16, 17, 300}) {
                Stream s;
                s.literal(prefix).reference(distance, len);
                s.literal(Bytes(noise.end() - static_cast<long>(after), noise.end()));
                const auto [decoded, out] = decode_exact(s.packed, s.raw.size());
                ASSERT_EQ(decoded.error, nullptr) << "distance " << distance << ", length " << len
                                                  << ", " << after << " after: " << decoded.error;
                ASSERT_EQ(out, s.raw)
                    << "distance " << distance << ", length " << len << ", " << after << " after";
            }
        }
    }
}

TEST(Lzf, DecodesEveryDistanceAndLengthPastTheFarthestDistance) {
    // The same once 8192 bytes are out, where every distance is valid and the AVX2 decoder takes
    // literal runs and references of up to 32 bytes on one path: each reference between literal
    // runs of every length, and right after another reference (bytes just stored).
    const Bytes noise = random_bytes(9000, 21);
    std::vector<std::size_t> distances;
    for (std::size_t d = 1; d <= 48; ++d) distances.push_back(d);
    for (const std::size_t d : {63, 64, 65, 100, 1000, 8191, 8192}) distances.push_back(d);
    std::mt19937 gen(22);
    for (const std::size_t distance : distances) {
        Stream s;
        s.literal(noise);
        for (std::size_t len = 3; len <= 264; ++len) {
            s.reference(distance, len);
            if (len % 3 == 0) s.reference(1 + gen() % 40, 3 + gen() % 30);
            s.literal(random_bytes(1 + len % 32, static_cast<std::uint32_t>(len)));
        }
        for (const std::size_t extra : {0, 1, 17, 300}) {
            const auto [decoded, out] = decode_exact(s.packed, s.raw.size() + extra);
            ASSERT_EQ(decoded.error, nullptr) << "distance " << distance << ": " << decoded.error;
            ASSERT_EQ(out, s.raw) << "distance " << distance << ", room + " << extra;
        }
    }
}

TEST(Lzf, LongRandomTokenStreamsDecode) {
    // Thousands of random tokens (the fast loops' every path, in every order) after the first
    // 8192 bytes, against the bytes they were built from.
    std::mt19937 gen(23);
    for (int trial = 0; trial < 40; ++trial) {
        Stream s;
        s.literal(random_bytes(8192 + gen() % 100, static_cast<std::uint32_t>(gen())));
        for (std::size_t k = 0; k < 3000; ++k) {
            const unsigned kind = gen() % 4;
            if (kind == 0) {
                s.literal(random_bytes(1 + gen() % 32, static_cast<std::uint32_t>(gen())));
            } else {
                const std::size_t distance = 1 + gen() % (kind == 1 ? 16 : kind == 2 ? 64 : 8192);
                const std::size_t len = 3 + gen() % (gen() % 4 == 0 ? 262 : 30);
                s.reference(distance, len);
            }
        }
        const auto [decoded, out] = decode_exact(s.packed, s.raw.size());
        ASSERT_EQ(decoded.error, nullptr) << "trial " << trial;
        ASSERT_EQ(out, s.raw) << "trial " << trial;
    }
}

TEST(Lzf, DecodesLiteralRunsOfEveryLengthAtTheVeryEnd) {
    // A last literal run of 1..32 bytes ending both the input and the exact-size output, after
    // 0..320 bytes of output (and a back reference), so that the switch from the fast loop to
    // the careful one falls before, on and after it.
    const Bytes noise = random_bytes(400, 13);
    for (std::size_t before = 0; before <= 320; ++before) {
        for (std::size_t n = 1; n <= 32; ++n) {
            Stream s;
            s.literal(Bytes(noise.begin(), noise.begin() + static_cast<long>(before)));
            if (before >= 8) s.reference(8, 5);
            s.literal(Bytes(noise.end() - static_cast<long>(n), noise.end()));
            const auto [decoded, out] = decode_exact(s.packed, s.raw.size());
            ASSERT_EQ(decoded.error, nullptr) << before << " bytes before a run of " << n;
            ASSERT_EQ(out, s.raw) << before << " bytes before a run of " << n;
        }
    }
}

/// A block of every kind of token, decoded in the fast loop but for its last tokens.
Stream every_token() {
    const Bytes noise = random_bytes(2000, 14);
    Stream s;
    std::size_t used = 0;
    auto literal = [&](std::size_t n) {
        s.literal(Bytes(noise.begin() + static_cast<long>(used),
                        noise.begin() + static_cast<long>(used + n)));
        used += n;
    };
    literal(40);
    for (const std::size_t distance : {1, 3, 4, 8, 12, 16, 20, 40, 300}) {
        for (const std::size_t len : {3, 4, 8, 9, 16, 17, 33, 100, 264}) {
            s.reference(distance, len);
            literal(1 + (distance + len) % 32);
        }
    }
    literal(32);
    s.reference(5, 3);
    return s;
}

TEST(Lzf, EveryTruncationIsAnErrorOrAPrefix) {
    const Stream s = every_token();
    ASSERT_GT(s.raw.size(), 5000u);
    // The input cut at every byte: a clean prefix of the output, or an error with a correct
    // prefix before it.
    for (std::size_t n = 0; n <= s.packed.size(); ++n) {
        const Bytes cut(s.packed.begin(), s.packed.begin() + static_cast<long>(n));
        const auto [decoded, out] = decode_exact(cut, s.raw.size());
        ASSERT_LE(decoded.produced, s.raw.size()) << n;
        ASSERT_LE(decoded.at, n) << n;
        ASSERT_TRUE(is_prefix(out, s.raw)) << "input cut to " << n << " bytes";
        if (n == s.packed.size()) {
            ASSERT_EQ(decoded.error, nullptr);
            ASSERT_EQ(out, s.raw);
        }
    }
    // The output cut at every byte: an error once a token no longer fits.
    for (std::size_t room = 0; room < s.raw.size(); ++room) {
        const auto [decoded, out] = decode_exact(s.packed, room);
        ASSERT_STREQ(decoded.error, "output exceeds stated size") << "room " << room;
        ASSERT_LE(decoded.produced, room);
        ASSERT_TRUE(is_prefix(out, s.raw)) << "room " << room;
    }
}

TEST(Lzf, BackReferencesBeforeTheStartAreReportedInTheFastLoop) {
    // With plenty of room on both sides, a reference one byte too far (or more) is caught, short
    // form or long, and one to the very first byte is not.
    const Bytes noise = random_bytes(100, 15);
    Stream head, tail;
    head.literal(Bytes(noise.begin(), noise.begin() + 10));  // 11 bytes of input
    tail.literal(Bytes(noise.begin() + 10, noise.end()));
    for (const std::size_t len : {3, 8, 9, 264}) {
        for (const std::size_t distance : {1, 10, 11, 12, 100, 8192}) {
            const Bytes reference = Stream::reference_tokens(distance, len);
            Bytes packed = head.packed;
            packed.insert(packed.end(), reference.begin(), reference.end());
            packed.insert(packed.end(), tail.packed.begin(), tail.packed.end());
            const auto [decoded, out] = decode_exact(packed, 4096);
            if (distance <= 10) {
                Stream valid = head;
                valid.reference(distance, len).literal(tail.raw);
                EXPECT_EQ(decoded.error, nullptr);
                EXPECT_EQ(out, valid.raw);
            } else {
                EXPECT_STREQ(decoded.error, "back reference before the start of the output")
                    << "distance " << distance << ", length " << len;
                EXPECT_EQ(decoded.at, head.packed.size() + reference.size());
                EXPECT_EQ(decoded.produced, 10u);
            }
        }
    }
}

TEST(Lzf, RandomTokensDecodeAndDamagedOnesStayInBounds) {
    // Streams of random tokens (literal runs, back references near and far, short and long)
    // decode to what they were built from; with a few bytes changed and into a room of any size,
    // they decode without going past either end (sanitizer builds check every access).
    std::mt19937 gen(16);
    for (int trial = 0; trial < 500; ++trial) {
        Stream s;
        const std::size_t tokens = 1 + gen() % 200;
        for (std::size_t k = 0; k < tokens; ++k) {
            if (s.raw.empty() || gen() % 3 == 0) {
                s.literal(random_bytes(1 + gen() % 32, static_cast<std::uint32_t>(gen())));
                continue;
            }
            const std::size_t reach = std::min<std::size_t>(s.raw.size(), 8192);
            const std::size_t distance =
                1 + gen() % (gen() % 2 ? std::min<std::size_t>(reach, 20) : reach);
            const std::size_t len = 3 + gen() % (gen() % 2 ? 14 : 262);
            s.reference(distance, len);
        }
        const auto [decoded, out] = decode_exact(s.packed, s.raw.size());
        ASSERT_EQ(decoded.error, nullptr) << "trial " << trial;
        ASSERT_EQ(out, s.raw) << "trial " << trial;

        Bytes damaged = s.packed;
        for (int k = 0; k < 3; ++k) {
            damaged[gen() % damaged.size()] = static_cast<unsigned char>(gen());
        }
        const std::size_t room = gen() % (s.raw.size() + 300);
        const auto [damaged_decoded, damaged_out] = decode_exact(damaged, room);
        ASSERT_LE(damaged_decoded.produced, room) << "trial " << trial;
        ASSERT_LE(damaged_decoded.at, damaged.size()) << "trial " << trial;
    }
}

/// Random tokens of every kind, `tokens` of them: literal runs, back references near and far,
/// short and long.
Stream random_stream(std::size_t tokens, std::mt19937& gen) {
    Stream s;
    for (std::size_t k = 0; k < tokens; ++k) {
        if (s.raw.empty() || gen() % 3 == 0) {
            Bytes bytes(1 + gen() % 32);
            for (auto& b : bytes) b = static_cast<unsigned char>(gen());
            s.literal(bytes);
            continue;
        }
        const std::size_t reach = std::min<std::size_t>(s.raw.size(), 8192);
        const std::size_t distance =
            1 + gen() % (gen() % 2 ? std::min<std::size_t>(reach, 20) : reach);
        s.reference(distance, 3 + gen() % (gen() % 2 ? 14 : 262));
    }
    return s;
}

/// Decodes the first `wanted` bytes of a block of `size` bytes, the output exactly `wanted`
/// bytes long (sanitizer builds catch a write past it).
std::pair<esf::detail::LzfDecoded, Bytes> decode_first(const Bytes& packed, std::size_t wanted,
                                                       std::size_t size) {
    const Bytes in(packed);
    Bytes out(wanted);
    const auto decoded = lzf_decompress(in, out, size);
    return {decoded, out};
}

void expect_same_result(const esf::detail::LzfDecoded& a, const esf::detail::LzfDecoded& b) {
    EXPECT_STREQ(a.error, b.error);
    EXPECT_EQ(a.at, b.at);
    EXPECT_EQ(a.produced, b.produced);
}

TEST(Lzf, DecodingTheFirstBytesChecksTheRestAsDecodingAllWould) {
    // Blocks long enough that the tokens after the bytes wanted are walked in pieces (more than
    // 64 KiB of them after 8 KiB of output), and short ones: the first bytes are the block's,
    // and the result is the whole block's.
    std::mt19937 gen(21);
    for (int trial = 0; trial < 60; ++trial) {
        const Stream s =
            random_stream(trial % 3 == 0 ? 1 + gen() % 300 : 20000 + gen() % 20000, gen);
        const std::size_t size = s.raw.size();
        for (const std::size_t wanted :
             {std::size_t{0}, std::size_t{1}, std::size_t{9000}, size / 3, size - 1, size}) {
            if (wanted > size) continue;
            SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(wanted) + " of " +
                         std::to_string(size) + " bytes");
            const auto [decoded, out] = decode_first(s.packed, wanted, size);
            EXPECT_EQ(decoded.error, nullptr);
            EXPECT_EQ(decoded.produced, size);
            EXPECT_TRUE(is_prefix(out, s.raw));
            // A stated size smaller or larger than the block's: the same error as decoding all.
            for (const std::size_t stated : {size + 1, size - size / 4}) {
                if (stated < wanted) continue;
                const auto [all, all_out] = decode_first(s.packed, stated, stated);
                expect_same_result(decode_first(s.packed, wanted, stated).first, all);
            }
        }
    }
}

TEST(Lzf, DamageAfterTheBytesWantedIsReportedAsDecodingAllWould) {
    // A few bytes changed anywhere in a long block: decoding only its first bytes gives the same
    // error at the same byte, or the same clean result, as decoding it all. No change is missed
    // because its bytes are not written.
    std::mt19937 gen(22);
    int errors = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Stream s = random_stream(25000, gen);
        const std::size_t size = s.raw.size();
        Bytes damaged = s.packed;
        const std::size_t changes = 1 + gen() % 3;
        for (std::size_t k = 0; k < changes; ++k) {
            damaged[damaged.size() / 4 + gen() % (damaged.size() * 3 / 4)] =
                static_cast<unsigned char>(gen());
        }
        const auto [all, all_out] = decode_first(damaged, size, size);
        const std::size_t wanted = gen() % (size / 4);
        SCOPED_TRACE("trial " + std::to_string(trial));
        expect_same_result(decode_first(damaged, wanted, size).first, all);
        errors += all.error != nullptr || all.produced != size;
    }
    EXPECT_GT(errors, 40);  // damage to a control byte shows: the comparison is not vacuous
}

TEST(Lzf, TokensThatNoPieceWalkMeetsAreWalkedOneByOne) {
    // Literal runs of 32 bytes that are all 0x1f (the control byte of a run of 32): a walk
    // started at any byte that is not a token's first moves 33 bytes at a time and never meets
    // the true walk, which must then walk every piece itself.
    Stream s;
    s.literal(random_bytes(10000, 23));
    s.literal(Bytes(33 * 32 * 100, 0x1f));
    const auto [decoded, out] = decode_first(s.packed, 9000, s.raw.size());
    EXPECT_EQ(decoded.error, nullptr);
    EXPECT_EQ(decoded.produced, s.raw.size());
    EXPECT_TRUE(is_prefix(out, s.raw));
    // One byte short at the end: the last run is cut off, as decoding all reports.
    Bytes cut = s.packed;
    cut.pop_back();
    expect_same_result(decode_first(cut, 9000, s.raw.size()).first,
                       decode_first(cut, s.raw.size(), s.raw.size()).first);
    EXPECT_STREQ(decode_first(cut, 9000, s.raw.size()).first.error, "literal run past the end");
}

TEST(Lzf, AnOutputLargerThanTheStatedSizeIsRefused) {
    Bytes out(10);
    EXPECT_THROW(lzf_decompress(Bytes{0x00, 'a'}, out, 9), std::invalid_argument);
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
