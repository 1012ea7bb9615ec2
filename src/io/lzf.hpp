#pragma once
// LZF, the compression of PCD's binary_compressed data: liblzf's format (as in pcl/io/lzf.h),
// written here so that the core needs no PCL.
//
// A block is a sequence of tokens. A control byte c < 32 starts a literal run of c + 1 bytes;
// otherwise len = c >> 5 (7: plus the next byte) and the back reference copies len + 2 bytes from
// distance ((c & 31) << 8) + next byte + 1 behind the output. Matches are at least 3 bytes,
// at most 264, at most 8192 bytes back.

#include <cstddef>
#include <span>

#include "esf/core/kernels.hpp"

namespace esf::detail {

/// Most bytes lzf_compress() writes for `size` input bytes: literal runs of 32 cost one control
/// byte each and a back reference never takes more bytes than it replaces.
constexpr std::size_t lzf_compress_bound(std::size_t size) { return size + size / 32 + 1; }

/// Compresses `in` into `out`, which must hold lzf_compress_bound(in.size()) bytes; returns the
/// bytes written (0 for empty input). Inputs of 4 GiB and more are refused with
/// std::invalid_argument. Deterministic: the same input always gives the same bytes.
std::size_t lzf_compress(std::span<const unsigned char> in, std::span<unsigned char> out);

/// Longest output of one LZF token per input byte: a 3-byte back reference yields 264 bytes.
inline constexpr std::size_t kLzfMaxRatio = 88;

struct LzfDecoded {
    std::size_t produced = 0;     ///< bytes written to the output
    const char* error = nullptr;  ///< why the input is corrupt; null when it decoded cleanly
    std::size_t at = 0;           ///< input byte where the error was found
};

/// Decodes `in` into `out`. Bounds are checked on every token, so corrupt input reports an error
/// instead of reading or writing out of range. Away from the ends of both buffers, tokens are
/// copied in fixed-size blocks: bytes of `out` past `produced` may be overwritten, and bytes of
/// `out` not yet written may be read (and masked off: they never reach the output). The PCD
/// reader passes memory it has not cleared: zeroing 6 MB for every 640 x 480 scene would cost
/// 5 % of reading it.
LzfDecoded lzf_decompress(std::span<const unsigned char> in, std::span<unsigned char> out);

/// Decodes the first out.size() bytes of a block of `size` bytes (size >= out.size(), else
/// std::invalid_argument) and checks the rest of its tokens without writing them: the result,
/// errors included, is the same as decoding the whole block into `size` bytes. For blocks whose
/// last bytes no one reads: checking a token costs about a fifth of decoding it.
///
/// `kernels`: how the decoder copies tokens once 8192 bytes are out. Where the CPU has AVX2 and
/// the kernels are not kPortable, literal runs and back references of up to 32 bytes take one
/// path without branches (the kind of the next token is unpredictable: about 40 % of the time
/// goes to mispredicted branches otherwise); kPortable always branches on the kind. Both give
/// the same result.
LzfDecoded lzf_decompress(std::span<const unsigned char> in, std::span<unsigned char> out,
                          std::size_t size, Kernels kernels = Kernels::kBest);

}  // namespace esf::detail
