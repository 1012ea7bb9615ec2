#include "io/lzf.hpp"

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/simd.hpp"
#include "io/lzf_tokens.hpp"

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

// ---- decoder helpers ----------------------------------------------------------------------------

// The decoder's fast loop copies in fixed-size blocks that may run past a token's end (the next
// token overwrites those bytes). It runs while the input holds a control byte and a 32-byte
// literal copy, and the output holds what any token may write: at most max(32, len + 15) bytes
// for a back reference of len bytes (see copy_far, copy_near), 32 for a literal run.
constexpr std::size_t kFastInput = 1 + kMaxLiteral;
constexpr std::size_t kFastOutput = kMaxMatch + 16;

/// The bytes of v in reverse order (for big-endian hosts).
constexpr std::uint64_t reverse_bytes(std::uint64_t v) {
    std::uint64_t r = 0;
    for (int k = 0; k < 8; ++k, v >>= 8) r = (r << 8) | (v & 0xff);
    return r;
}

/// 8-byte load and store in little-endian order: byte k of the value is byte k in memory.
inline std::uint64_t load64(const unsigned char* p) {
    std::uint64_t v;
    std::memcpy(&v, p, 8);
    if constexpr (std::endian::native == std::endian::big) v = reverse_bytes(v);
    return v;
}

inline void store64(unsigned char* p, std::uint64_t v) {
    if constexpr (std::endian::native == std::endian::big) v = reverse_bytes(v);
    std::memcpy(p, &v, 8);
}

/// A 64-bit value with its low n bytes set (n < 8).
constexpr std::uint64_t low_bytes(std::size_t n) { return (std::uint64_t{1} << (8 * n)) - 1; }

/// How the first 16 bytes of a back reference at distance d < 16 (which repeat the d bytes
/// before it) are built in two 64-bit words from the two words at the reference, w0 and w1:
///
///   lo = (w0 & lo_mask) * lo_mul
///   hi = (w1 & hi_mask) | (((lo >> down) & down_mask) * hi_mul)
///
/// For d < 8, lo_mask keeps the d bytes of the period and lo_mul repeats them across the word
/// (the d-byte copies do not overlap, so the product has no carries); hi repeats the period from
/// its phase at byte 8, r = 8 mod d, which lo holds at bytes r..r+d-1. For 8 <= d < 16, lo is w0
/// itself; w1 gives bytes 8..d-1 and the rest start the period over (byte k is byte k - d: lo
/// shifted up by d - 8 bytes, a multiplication by a power of two). The 16 bytes then repeat every
/// `stride` bytes, the largest multiple of d up to 16.
struct Repeat {
    std::uint64_t lo_mask = 0, lo_mul = 0, hi_mask = 0, down_mask = 0, hi_mul = 0;
    unsigned down = 0;
    std::size_t stride = 0;
};

constexpr std::array<Repeat, 16> kRepeat = [] {
    std::array<Repeat, 16> table{};
    for (std::size_t d = 1; d < 16; ++d) {
        Repeat& r = table[d];
        r.stride = 16 - 16 % d;
        if (d < 8) {
            std::uint64_t spread = 0;
            for (std::size_t shift = 0; shift < 64; shift += 8 * d)
                spread |= std::uint64_t{1} << shift;
            r.lo_mask = low_bytes(d);
            r.lo_mul = spread;
            r.down = static_cast<unsigned>(8 * (8 % d));
            r.down_mask = low_bytes(d);
            r.hi_mul = spread;
        } else {
            r.lo_mask = ~std::uint64_t{0};
            r.lo_mul = 1;
            r.hi_mask = low_bytes(d - 8);
            r.down_mask = ~std::uint64_t{0};
            r.hi_mul = std::uint64_t{1} << (8 * (d - 8));
        }
    }
    return table;
}();

/// The first 8 bytes of the back reference at distance d >= 1: lo of Repeat for d < 8 (the bytes
/// at op and after, not yet written, are masked off), the 8 bytes at the reference otherwise.
inline std::uint64_t first_word(const unsigned char* op, std::size_t distance) {
    const Repeat& r = kRepeat[std::min<std::size_t>(distance, 8)];
    return (load64(op - distance) & r.lo_mask) * r.lo_mul;
}

/// Back reference of len >= 9 bytes at distance >= 16, in 16-byte blocks: each block's source
/// ends at or before its destination, so it reads only bytes already final. The first two blocks
/// are unconditional (most references are 32 bytes at most). Writes max(32, len + 15) bytes.
inline void copy_far(unsigned char* op, std::size_t distance, std::size_t len) {
    const unsigned char* ref = op - distance;
    std::memcpy(op, ref, 16);
    std::memcpy(op + 16, ref + 16, 16);
    for (std::size_t k = 32; k < len; k += 16) std::memcpy(op + k, ref + k, 16);
}

/// Back reference of len >= 9 bytes at distance 1..15: its first 16 bytes, built in registers
/// (see Repeat), stored every stride bytes; the first two stores are unconditional. Reads the 16
/// bytes at op - distance (those not yet written are masked off); writes max(32, len + 15) bytes.
inline void copy_near(unsigned char* op, std::size_t distance, std::size_t len) {
    const Repeat& r = kRepeat[distance];
    const unsigned char* ref = op - distance;
    const std::uint64_t lo = (load64(ref) & r.lo_mask) * r.lo_mul;
    const std::uint64_t hi =
        (load64(ref + 8) & r.hi_mask) | (((lo >> r.down) & r.down_mask) * r.hi_mul);
    store64(op, lo);
    store64(op + 8, hi);
    store64(op + r.stride, lo);
    store64(op + r.stride + 8, hi);
    for (std::size_t k = 2 * r.stride; k < len; k += r.stride) {
        store64(op + k, lo);
        store64(op + k + 8, hi);
    }
}

/// Back reference of len >= 9 bytes at any distance (copy_far or copy_near).
inline void copy_long_reference(unsigned char* op, std::size_t distance, std::size_t len) {
    if (distance >= 16) {
        copy_far(op, distance, len);
    } else {
        copy_near(op, distance, len);
    }
}

/// Byte shuffles that build the first 32 bytes of a token (AVX2 fast loop): for a back reference
/// at distance m < 16, byte k of the first 16 bytes is byte k % m of the 16 at the reference, and
/// byte k of the next 16 is byte (16 + k) % m of the same 16; entry 16 keeps bytes as they are
/// (literal runs and far references, whose next 16 bytes are loaded from 16 bytes further).
struct RepeatShuffles {
    alignas(16) std::array<std::array<std::uint8_t, 16>, 17> first{}, second{};
};

constexpr RepeatShuffles kRepeatShuffles = [] {
    RepeatShuffles t{};
    for (std::size_t m = 1; m <= 16; ++m)
        for (std::size_t k = 0; k < 16; ++k) {
            t.first[m][k] = static_cast<std::uint8_t>(m == 16 ? k : k % m);
            t.second[m][k] = static_cast<std::uint8_t>(m == 16 ? k : (16 + k) % m);
        }
    return t;
}();

/// Where the fast loop stopped: the next token and output byte.
struct FastLoopEnd {
    const unsigned char* ip;
    unsigned char* op;
};

/// x < bound ? if_below : otherwise, as a compare and a conditional move: a compiler turns a
/// conditional expression on an unpredictable value into a branch.
inline std::size_t pick_below(std::size_t x, std::size_t bound, std::size_t if_below,
                              std::size_t otherwise) {
    asm("cmp %[bound], %[x]\n\tcmovb %[if_below], %[result]"
        : [result] "+r"(otherwise)
        : [x] "r"(x), [bound] "r"(bound), [if_below] "r"(if_below)
        : "cc");
    return otherwise;
}

/// The fast loop once kMaxDistance bytes are produced (every distance is then valid), with one
/// path for literal runs and back references of up to 32 bytes (16 at distances 16..31): 32
/// bytes built by two byte shuffles from two 16-byte loads at the literal bytes or the reference,
/// so that the kind of the next token, which is unpredictable, costs no branch. Longer back
/// references take copy_long_reference. The same bounds as the portable loop (kFastInput,
/// kFastOutput).
ESF_TARGET_AVX2 FastLoopEnd fast_loop_shuffles(const unsigned char* ip, unsigned char* op,
                                               const unsigned char* in_fast_end,
                                               unsigned char* out_fast_end) {
    const auto* shuffles = &kRepeatShuffles;
    while (ip <= in_fast_end && op <= out_fast_end) {
        const std::size_t ctrl = ip[0], byte1 = ip[1], byte2 = ip[2];
        // Each choice by a compare and conditional moves (see pick_below), one compare for each
        // kind: a back reference of 3..8 bytes, or (ctrl >= 224) a long one ...
        std::size_t distance_byte = byte1, len = (ctrl >> 5) + 2, step = 2;
        asm("cmp $224, %[ctrl]\n\t"
            "cmovae %[byte2], %[distance_byte]\n\t"
            "cmovae %[long_len], %[len]\n\t"
            "cmovae %[three], %[step]"
            : [distance_byte] "+r"(distance_byte), [len] "+r"(len), [step] "+r"(step)
            : [ctrl] "r"(ctrl), [byte2] "r"(byte2), [long_len] "r"(byte1 + 9),
              [three] "r"(std::size_t{3})
            : "cc");
        const std::size_t distance = ((ctrl & 0x1f) << 8) + distance_byte + 1;
        // ... at most 32 bytes of which one path serves, 16 at distances 16..31; the shuffles'
        // period, at most 16; the bytes it copies ...
        std::size_t most = pick_below(distance - 16, 16, 16, 32);
        std::size_t m = std::min<std::size_t>(distance, 16);
        auto from = reinterpret_cast<std::uintptr_t>(op - distance);
        // ... or (ctrl < 32) a literal run of up to 32 bytes.
        asm("cmp $32, %[ctrl]\n\t"
            "cmovb %[literal_len], %[len]\n\t"
            "cmovb %[literal_step], %[step]\n\t"
            "cmovb %[sixteen], %[m]\n\t"
            "cmovb %[literal_from], %[from]\n\t"
            "cmovb %[thirty_two], %[most]"
            : [len] "+r"(len), [step] "+r"(step), [m] "+r"(m), [from] "+r"(from), [most] "+r"(most)
            : [ctrl] "r"(ctrl), [literal_len] "r"(ctrl + 1), [literal_step] "r"(ctrl + 2),
              [sixteen] "r"(std::size_t{16}),
              [literal_from] "r"(reinterpret_cast<std::uintptr_t>(ip + 1)),
              [thirty_two] "r"(std::size_t{32})
            : "cc");
        if (len > most) {  // a long back reference
            copy_long_reference(op, distance, len);
            op += len;
            ip += 3;
            continue;
        }
        // At distance < 16 the next 16 bytes repeat the first ones too: loaded from the same
        // place (not from bytes that earlier tokens may still be storing).
        const auto* source = reinterpret_cast<const unsigned char*>(from);
        const __m128i head = _mm_loadu_si128(reinterpret_cast<const __m128i*>(source));
        const __m128i tail = _mm_loadu_si128(reinterpret_cast<const __m128i*>(source + (m & 16)));
        const __m128i first = _mm_shuffle_epi8(
            head, _mm_load_si128(reinterpret_cast<const __m128i*>(shuffles->first[m].data())));
        const __m128i second = _mm_shuffle_epi8(
            tail, _mm_load_si128(reinterpret_cast<const __m128i*>(shuffles->second[m].data())));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(op), first);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(op + 16), second);
        op += len;
        ip += step;  // the loop's chain of dependent steps: a load, compares, conditional moves
    }
    return {ip, op};
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
    return lzf_decompress(in, out, out.size());
}

LzfDecoded lzf_decompress(std::span<const unsigned char> in, std::span<unsigned char> out,
                          std::size_t size, Kernels kernels) {
    if (size < out.size()) {
        throw std::invalid_argument("lzf_decompress: output larger than the stated size");
    }
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

    // Fast loop, while any token fits with room to spare on both sides: fixed-size copies (see
    // kFastOutput), and only the distance of back references left to check. One branch per kind
    // of token: literal run, short back reference (one 8-byte word), long back reference. Once
    // 8192 bytes are out (no distance left to check) and where the CPU has AVX2, the kinds share
    // one path instead (fast_loop_shuffles).
    if (in.size() >= kFastInput && out.size() >= kFastOutput) {
        const unsigned char* const in_fast_end = in_end - kFastInput;
        unsigned char* const out_fast_end = out_end - kFastOutput;
        bool shuffles = kernels != Kernels::kPortable && avx2_available();
        while (ip <= in_fast_end && op <= out_fast_end) {
            if (shuffles && static_cast<std::size_t>(op - out.data()) >= kMaxDistance) {
                const FastLoopEnd end = fast_loop_shuffles(ip, op, in_fast_end, out_fast_end);
                ip = end.ip;
                op = end.op;
                shuffles = false;
                continue;
            }
            const std::size_t ctrl = *ip++;
            if (ctrl < 32) {  // literal run of ctrl + 1 bytes: one 32-byte copy serves any length
                std::memcpy(op, ip, kMaxLiteral);
                op += ctrl + 1;
                ip += ctrl + 1;
                continue;
            }
            const std::size_t produced = static_cast<std::size_t>(op - out.data());
            if (ctrl < (7 << 5)) {  // back reference of 3..8 bytes, no length byte
                const std::size_t distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
                if (distance > produced) {
                    return corrupt("back reference before the start of the output");
                }
                store64(op, first_word(op, distance));
                op += (ctrl >> 5) + 2;
                continue;
            }
            const std::size_t len = 9 + std::size_t{*ip++};  // back reference of 9..264 bytes
            const std::size_t distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
            if (distance > produced) {
                return corrupt("back reference before the start of the output");
            }
            copy_long_reference(op, distance, len);
            op += len;
        }
    }

    // Careful loop for the last tokens (and small blocks): every length checked, exact copies.
    // Past the end of `out` the tokens are only checked (lzf_check_tokens), counted up to `size`.
    while (ip < in_end && op < out_end) {
        const std::size_t produced = static_cast<std::size_t>(op - out.data());
        const LzfToken token = read_lzf_token(ip, in_end, produced, size);
        if (token.error) return corrupt(token.error);
        const std::size_t len = token.len, distance = token.distance;
        // The part of the token that `out` holds (the first bytes of a back reference are a back
        // reference of fewer bytes).
        const std::size_t kept = std::min(len, static_cast<std::size_t>(out_end - op));
        if (distance == 0) {
            std::memcpy(op, ip, kept);
            ip += len;
        } else if (distance >= kept) {
            std::memcpy(op, op - distance, kept);
        } else {
            // Overlapping: the output repeats the last `distance` bytes. Copy one period, then
            // double what is done (from the start of the match, so every copy is disjoint and
            // starts at a whole period): log2(len / distance) copies instead of len.
            std::memcpy(op, op - distance, distance);
            for (std::size_t done = distance; done < kept;) {
                const std::size_t chunk = std::min(done, kept - done);
                std::memcpy(op + done, op, chunk);
                done += chunk;
            }
        }
        if (kept < len) {
            return lzf_check_tokens(in, static_cast<std::size_t>(ip - in.data()), produced + len,
                                    size);
        }
        op += len;
    }
    if (ip < in_end) {
        return lzf_check_tokens(in, static_cast<std::size_t>(ip - in.data()),
                                static_cast<std::size_t>(op - out.data()), size);
    }
    result.produced = static_cast<std::size_t>(op - out.data());
    return result;
}

}  // namespace esf::detail
