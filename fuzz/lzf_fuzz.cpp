// libFuzzer target: LZF decoding (src/io/lzf.cpp) of arbitrary bytes, by both copy loops. The input
// is a 4-byte output size (below 1 MiB), a byte whose lowest bit puts 8,224 bytes of literal
// runs first (so that the AVX2 loop, which starts once 8192 bytes are out, runs on the rest), and
// the LZF block. Both loops must give the same bytes, count and error, and stay in bounds (ASan,
// UBSan); the first bytes of a block decoded alone must be those of the whole.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "io/lzf.hpp"

namespace {

using esf::detail::lzf_decompress;
using esf::detail::LzfDecoded;

bool same(const LzfDecoded& a, const LzfDecoded& b) {
    if (a.produced != b.produced || a.at != b.at) return false;
    if ((a.error == nullptr) != (b.error == nullptr)) return false;
    return a.error == nullptr || std::strcmp(a.error, b.error) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHeader = 5;
    if (size < kHeader) return 0;
    std::uint32_t stated = 0;
    std::memcpy(&stated, data, sizeof stated);
    std::size_t room = stated % (std::uint32_t{1} << 20);
    std::vector<unsigned char> block;
    if (data[4] & 1) {  // 257 literal runs of 32 bytes
        for (int run = 0; run < 257; ++run) {
            block.push_back(31);
            for (int k = 0; k < 32; ++k) block.push_back(static_cast<unsigned char>(run * 7 + k));
        }
        room += 257 * 32;
    }
    block.insert(block.end(), data + kHeader, data + size);

    std::vector<unsigned char> best(room), portable(room);
    const LzfDecoded a = lzf_decompress(block, best, room, esf::Kernels::kBest);
    const LzfDecoded b = lzf_decompress(block, portable, room, esf::Kernels::kPortable);
    if (!same(a, b)) __builtin_trap();
    const std::size_t kept = std::min(a.produced, room);
    if (kept > 0 && std::memcmp(best.data(), portable.data(), kept) != 0) __builtin_trap();

    // The first half decoded alone, the rest only checked: the same result, the same bytes.
    std::vector<unsigned char> half(room / 2);
    const LzfDecoded c = lzf_decompress(block, half, room);
    if (!same(a, c)) __builtin_trap();
    const std::size_t kept_half = std::min(c.produced, half.size());
    if (kept_half > 0 && std::memcmp(best.data(), half.data(), kept_half) != 0) __builtin_trap();
    return 0;
}
