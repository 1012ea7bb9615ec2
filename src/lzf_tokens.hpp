#pragma once
// Internal: LZF tokens checked without being decoded (src/lzf_tokens.cpp), for the bytes of a
// block that no one reads (the colour column after a PCD's x, y, z and label).

#include <cstddef>
#include <span>

#include "lzf.hpp"

namespace esf::detail {

/// Checks the tokens of `in` from byte `from` (a token's first byte) to the end as
/// lzf_decompress() would decode them after `produced` bytes into an output of `size` bytes, and
/// returns what it would: the bytes produced in all, or the same error at the same byte. Writes
/// nothing. Long stretches are walked along several chains at once (see the .cpp).
LzfDecoded lzf_check_tokens(std::span<const unsigned char> in, std::size_t from,
                            std::size_t produced, std::size_t size);

}  // namespace esf::detail
