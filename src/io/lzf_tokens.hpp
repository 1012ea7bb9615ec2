#pragma once
// Internal: LZF tokens checked without being decoded (src/io/lzf_tokens.cpp), for the bytes of a
// block that no one reads (the colour column after a PCD's x, y, z and label).

#include <cstddef>
#include <span>

#include "io/lzf.hpp"

namespace esf::detail {

/// One token as the decoder reads it: `len` output bytes, copied from `distance` bytes back (0: a
/// literal run), or the reason the input is corrupt.
struct LzfToken {
    std::size_t len = 0;
    std::size_t distance = 0;
    const char* error = nullptr;
};

/// Reads the token at `ip`, `produced` bytes into an output of `size` bytes, with every check of
/// the format: moves `ip` past the control bytes read (a literal run's bytes follow; on an error,
/// `ip` is where it was found). The decoder's careful loop and lzf_check_tokens both use it.
inline LzfToken read_lzf_token(const unsigned char*& ip, const unsigned char* in_end,
                               std::size_t produced, std::size_t size) {
    LzfToken t;
    const std::size_t ctrl = *ip++;
    if (ctrl < 32) {  // literal run of ctrl + 1 bytes
        t.len = ctrl + 1;
        if (static_cast<std::size_t>(in_end - ip) < t.len) {
            t.error = "literal run past the end";
        } else if (size - produced < t.len) {
            t.error = "output exceeds stated size";
        }
        return t;
    }
    t.len = ctrl >> 5;  // back reference of len + 2 bytes
    if (ip >= in_end) {
        t.error = "back reference cut off";
        return t;
    }
    if (t.len == 7) {
        t.len += *ip++;
        if (ip >= in_end) {
            t.error = "back reference cut off";
            return t;
        }
    }
    t.distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
    t.len += 2;
    if (t.distance > produced) {
        t.error = "back reference before the start of the output";
    } else if (size - produced < t.len) {
        t.error = "output exceeds stated size";
    }
    return t;
}

/// Checks the tokens of `in` from byte `from` (a token's first byte) to the end as
/// lzf_decompress() would decode them after `produced` bytes into an output of `size` bytes, and
/// returns what it would: the bytes produced in all, or the same error at the same byte. Writes
/// nothing. Long stretches are walked along several chains at once (see the .cpp).
LzfDecoded lzf_check_tokens(std::span<const unsigned char> in, std::size_t from,
                            std::size_t produced, std::size_t size);

}  // namespace esf::detail
