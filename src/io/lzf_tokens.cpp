// LZF tokens checked without being decoded.
//
// Each token's length follows from its first byte (and, for a long back reference, the next), so
// walking the tokens one by one is a chain of dependent loads: about 2 ns a token, and the colour
// block of a 640 x 480 PCD scene has about 400,000 tokens. Long stretches are therefore cut into
// kPieces pieces walked at once: the first from a known token, each other one from its first byte,
// which may lie inside a token. A walk from a wrong byte soon lands on a byte that the true walk
// visits too (tokens are short and of varied lengths), and from there both are the same walk.
// When the true walk reaches a piece, it steps on until it meets one of the first kRecorded bytes
// that piece's walk visited and takes over that walk's count; if it meets none, it walks the piece
// itself. Either way the result is the true walk's: where the pieces start never matters. Six
// walks at once take about 0.65 ns a token (four: 0.85; eight, or 32 in AVX-512 gathers: no
// faster).

#include "io/lzf_tokens.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace esf::detail {

namespace {

constexpr std::size_t kMaxDistance = 8192;  // farthest back reference
constexpr std::size_t kMaxToken = 33;       // most input bytes of one token: a run of 32 literals
constexpr std::size_t kPieces = 6;
constexpr std::size_t kRecorded = 64;
constexpr std::size_t kUnroll = 8;
/// Shortest piece: a walk's recorded tokens and one unrolled round fit in it with room to spare.
constexpr std::size_t kMinPiece = 16384;
static_assert(kMinPiece > (kRecorded + kUnroll) * kMaxToken);
/// Walks stop this far before the input's end, so that a token there is whole and its first two
/// bytes readable; the exact check takes the last bytes.
constexpr std::size_t kGuard = 64;

/// What a token's first byte says: the token's input bytes, its output bytes, and a mask for the
/// next byte, which adds to the output of a long back reference. Three byte tables: one load
/// each, no shifts (an eighth faster than one table of packed entries).
struct TokenSteps {
    std::array<std::uint8_t, 256> input{}, output{}, next_mask{};
};

constexpr TokenSteps kTokenSteps = [] {
    TokenSteps t{};
    for (std::size_t c = 0; c < 256; ++c) {
        std::size_t input = 2, output = (c >> 5) + 2, next_mask = 0;
        if (c < 32) {
            input = c + 2;
            output = c + 1;
        } else if (c >= 224) {
            input = 3;
            output = 9;
            next_mask = 0xff;
        }
        t.input[c] = static_cast<std::uint8_t>(input);
        t.output[c] = static_cast<std::uint8_t>(output);
        t.next_mask[c] = static_cast<std::uint8_t>(next_mask);
    }
    return t;
}();

/// A place on the token chain: a token's first byte and the bytes produced before it.
struct Walk {
    const unsigned char* ip;
    std::size_t produced;

    /// Moves to the next token, checking nothing: table lookups, no branch (which kind of
    /// token comes next is unpredictable).
    void step() {
        const std::size_t c = ip[0];
        const std::size_t next = ip[1];
        produced += std::size_t{kTokenSteps.output[c]} + (next & kTokenSteps.next_mask[c]);
        ip += kTokenSteps.input[c];
    }
};

/// The true walk from `start` to its first token at or after `stop` (at most stop + kMaxToken - 1;
/// stop is at least 2 bytes before the input's end), the pieces walked at once.
Walk walk_pieces(Walk start, const unsigned char* stop) {
    const auto length = static_cast<std::size_t>(stop - start.ip);
    std::array<const unsigned char*, kPieces + 1> bound{};
    for (std::size_t k = 0; k < kPieces; ++k) bound[k] = start.ip + length * k / kPieces;
    bound[kPieces] = stop;
    std::array<Walk, kPieces> walk{};
    walk[0] = start;
    for (std::size_t k = 1; k < kPieces; ++k) walk[k] = {bound[k], 0};

    std::array<std::array<Walk, kRecorded>, kPieces> seen{};  // seen[0] stays unused
    for (std::size_t m = 0; m < kRecorded; ++m) {
        for (std::size_t k = 1; k < kPieces; ++k) seen[k][m] = walk[k];
        for (std::size_t k = 0; k < kPieces; ++k) walk[k].step();
    }
    const auto room = [&] {
        for (std::size_t k = 0; k < kPieces; ++k) {
            if (bound[k + 1] - walk[k].ip < static_cast<std::ptrdiff_t>(kUnroll * kMaxToken)) {
                return false;
            }
        }
        return true;
    };
    while (room()) {
        for (std::size_t u = 0; u < kUnroll; ++u) {
            for (std::size_t k = 0; k < kPieces; ++k) walk[k].step();
        }
    }
    for (std::size_t k = 0; k < kPieces; ++k) {
        while (walk[k].ip < bound[k + 1]) walk[k].step();
    }

    Walk truth = walk[0];
    for (std::size_t k = 1; k < kPieces; ++k) {
        std::size_t m = 0;
        while (m < kRecorded && truth.ip != seen[k][m].ip) {
            if (truth.ip < seen[k][m].ip) {
                truth.step();
            } else {
                ++m;
            }
        }
        if (m < kRecorded) {
            truth = {walk[k].ip, truth.produced + (walk[k].produced - seen[k][m].produced)};
        } else {
            while (truth.ip < bound[k + 1]) truth.step();
        }
    }
    return truth;
}

/// The decoder's careful loop without the copies: the same token reader.
LzfDecoded check_serial(std::span<const unsigned char> in, const unsigned char* ip,
                        std::size_t produced, std::size_t size) {
    const unsigned char* const in_end = in.data() + in.size();
    LzfDecoded result;
    while (ip < in_end) {
        const LzfToken t = read_lzf_token(ip, in_end, produced, size);
        if (t.error) {
            result.error = t.error;
            result.at = static_cast<std::size_t>(ip - in.data());
            result.produced = produced;
            return result;
        }
        if (t.distance == 0) ip += t.len;
        produced += t.len;
    }
    result.produced = produced;
    return result;
}

}  // namespace

LzfDecoded lzf_check_tokens(std::span<const unsigned char> in, std::size_t from,
                            std::size_t produced, std::size_t size) {
    const unsigned char* const ip = in.data() + from;
    // Once kMaxDistance bytes are produced every distance is valid, and a token that starts
    // kGuard bytes before the end is whole: the walk needs no check but the count, which only
    // grows. Past the stated size, the exact check runs again from the start to find the token.
    if (produced >= kMaxDistance && size >= produced &&
        in.size() - from >= kPieces * kMinPiece + kGuard) {
        const Walk end = walk_pieces({ip, produced}, in.data() + in.size() - kGuard);
        if (end.produced <= size) return check_serial(in, end.ip, end.produced, size);
    }
    return check_serial(in, ip, produced, size);
}

}  // namespace esf::detail
