#include "lzf.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace esf::detail {

namespace {

constexpr std::size_t kMaxLiteral = 32;
constexpr std::size_t kMaxDistance = 8192;
constexpr std::size_t kMinMatch = 3;
constexpr std::size_t kMaxMatch = 2 + 7 + 255;
constexpr int kHashBits = 14;

/// Hash of the three bytes at p (Fibonacci hashing).
inline std::uint32_t hash3(const unsigned char* p) {
    const std::uint32_t v = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];
    return (v * 2654435761u) >> (32 - kHashBits);
}

}  // namespace

std::size_t lzf_compress(std::span<const unsigned char> in, std::span<unsigned char> out) {
    const std::size_t n = in.size();
    if (n == 0) return 0;
    if (n >= std::numeric_limits<std::uint32_t>::max()) {
        throw std::invalid_argument("lzf_compress: input of 4 GiB or more");
    }
    if (out.size() < lzf_compress_bound(n)) {
        throw std::invalid_argument("lzf_compress: output smaller than lzf_compress_bound");
    }
    const unsigned char* src = in.data();
    unsigned char* dst = out.data();
    // Last position (+ 1; 0 = none) where each 3-byte hash was seen.
    std::vector<std::uint32_t> last(std::size_t{1} << kHashBits, 0);
    std::size_t ip = 0, op = 0;
    std::size_t run = 0, run_ctrl = 0;  // current literal run: length, its control byte
    auto literal = [&](unsigned char c) {
        if (run == 0) run_ctrl = op++;
        dst[op++] = c;
        if (++run == kMaxLiteral) {
            dst[run_ctrl] = static_cast<unsigned char>(run - 1);
            run = 0;
        }
    };
    auto close_run = [&] {
        if (run > 0) dst[run_ctrl] = static_cast<unsigned char>(run - 1);
        run = 0;
    };
    while (ip + kMinMatch <= n) {
        const std::uint32_t h = hash3(src + ip);
        const std::uint32_t seen = last[h];
        last[h] = static_cast<std::uint32_t>(ip + 1);
        if (seen != 0) {
            const std::size_t ref = seen - 1;
            const std::size_t distance = ip - ref;
            if (distance <= kMaxDistance && std::memcmp(src + ref, src + ip, kMinMatch) == 0) {
                const std::size_t longest = std::min(kMaxMatch, n - ip);
                std::size_t len = kMinMatch;
                while (len < longest && src[ref + len] == src[ip + len]) ++len;
                close_run();
                const std::size_t code = len - 2;
                const std::size_t offset = distance - 1;
                if (code < 7) {
                    dst[op++] = static_cast<unsigned char>((code << 5) | (offset >> 8));
                } else {
                    dst[op++] = static_cast<unsigned char>((7 << 5) | (offset >> 8));
                    dst[op++] = static_cast<unsigned char>(code - 7);
                }
                dst[op++] = static_cast<unsigned char>(offset & 0xff);
                // Positions inside the match become candidates too (better ratios on runs).
                const std::size_t stop = std::min(ip + len, n - kMinMatch + 1);
                for (std::size_t k = ip + 1; k < stop; ++k) {
                    last[hash3(src + k)] = static_cast<std::uint32_t>(k + 1);
                }
                ip += len;
                continue;
            }
        }
        literal(src[ip++]);
    }
    while (ip < n) literal(src[ip++]);
    close_run();
    return op;
}

LzfDecoded lzf_decompress(std::span<const unsigned char> in, std::span<unsigned char> out) {
    const unsigned char* ip = in.data();
    const unsigned char* const in_end = ip + in.size();
    unsigned char* op = out.data();
    unsigned char* const out_end = op + out.size();
    LzfDecoded result;
    auto corrupt = [&](const char* why) {
        result.error = why;
        result.at = static_cast<std::size_t>(ip - in.data());
        result.produced = static_cast<std::size_t>(op - out.data());
        return result;
    };
    while (ip < in_end) {
        const std::size_t ctrl = *ip++;
        if (ctrl < 32) {  // literal run of ctrl + 1 bytes
            const std::size_t len = ctrl + 1;
            if (static_cast<std::size_t>(in_end - ip) < len)
                return corrupt("literal run past the end");
            if (static_cast<std::size_t>(out_end - op) < len) {
                return corrupt("output exceeds stated size");
            }
            // With room on both sides, one fixed 32-byte copy (a few vector moves) serves any
            // run; the bytes past the run are overwritten by the next token.
            if (static_cast<std::size_t>(in_end - ip) >= kMaxLiteral &&
                static_cast<std::size_t>(out_end - op) >= kMaxLiteral) {
                std::memcpy(op, ip, kMaxLiteral);
            } else {
                std::memcpy(op, ip, len);
            }
            op += len;
            ip += len;
            continue;
        }
        std::size_t len = ctrl >> 5;  // back reference of len + 2 bytes
        if (ip >= in_end) return corrupt("back reference cut off");
        if (len == 7) {
            len += *ip++;
            if (ip >= in_end) return corrupt("back reference cut off");
        }
        const std::size_t distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
        len += 2;
        if (distance > static_cast<std::size_t>(op - out.data())) {
            return corrupt("back reference before the start of the output");
        }
        if (static_cast<std::size_t>(out_end - op) < len) {
            return corrupt("output exceeds stated size");
        }
        const unsigned char* ref = op - distance;
        if (distance >= 16 && static_cast<std::size_t>(out_end - op) >= len + 16) {
            // 16 bytes at a time: each block's source ends at or before its destination.
            for (std::size_t k = 0; k < len; k += 16) std::memcpy(op + k, ref + k, 16);
        } else if (distance >= len) {
            std::memcpy(op, ref, len);
        } else {
            // Overlapping: the output repeats the last `distance` bytes. Copy one period, then
            // double what is done (from the start of the match, so every copy is disjoint and
            // starts at a whole period): log2(len / distance) copies instead of len.
            std::memcpy(op, ref, distance);
            for (std::size_t done = distance; done < len;) {
                const std::size_t chunk = std::min(done, len - done);
                std::memcpy(op + done, op, chunk);
                done += chunk;
            }
        }
        op += len;
    }
    result.produced = static_cast<std::size_t>(op - out.data());
    return result;
}

}  // namespace esf::detail
